#!/usr/bin/env bash
# Whether a change keeps the numbers: builds REV (default HEAD~1) in a
# temporary worktree and runs every built-in scene for a short time with both
# it and the current build, one thread, comparing metrics.csv bit for bit.
# A refactoring must pass it; a change to the physics says why it does not.
#   tools/same-bits.sh [REV] [BUILD]     (make same-bits REV=...)
set -euo pipefail
REV="${1:-HEAD~1}"; BUILD="${2:-build}"
ROOT="$(git rev-parse --show-toplevel)"
T=$(mktemp -d); trap 'git -C "$ROOT" worktree remove --force "$T/src" >/dev/null 2>&1 || true; rm -rf "$T"' EXIT
git -C "$ROOT" worktree add --detach "$T/src" "$REV" >/dev/null
echo "building $REV ($(git -C "$ROOT" rev-parse --short "$REV")) in $T"
cmake -S "$T/src" -B "$T/build" -DCMAKE_BUILD_TYPE=Release -DWETCLOTH_TESTS=OFF -DWETCLOTH_BENCH=OFF \
  -DWETCLOTH_VIEWER=OFF > /dev/null
cmake --build "$T/build" -j 2 --target wetcloth_cli > /dev/null
differ=0
for scene in $("$BUILD/wetcloth" scenes | awk 'NR > 0 && $1 ~ /^[a-z]/ {print $1}'); do
  for side in old new; do
    exe="$BUILD/wetcloth"; [ "$side" = old ] && exe="$T/build/wetcloth"
    "$exe" run "$scene" --threads 1 --duration 0.1 --set run.meshes=false --out "$T/$side/$scene" \
      > /dev/null 2>&1 || echo "$side: $scene exited $?"
  done
  if cmp -s "$T/old/$scene/metrics.csv" "$T/new/$scene/metrics.csv"; then
    echo "same   $scene"
  else
    echo "DIFFER $scene"; differ=1
  fi
done
exit $differ
