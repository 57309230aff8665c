#!/usr/bin/env bash
# A short run of every built-in scene on 1 and 2 threads (make test-sanitize:
# a sanitizer report ends the program with an error, which fails this).
set -u
W="$1"; DURATION="${2:-0.02}"
T=$(mktemp -d); trap 'rm -rf "$T"' EXIT
fails=0; passes=0
for scene in $("$W" scenes | awk '{print $1}'); do
  for threads in 1 2; do
    if "$W" run "$scene" --duration "$DURATION" --threads "$threads" --quiet \
         --out "$T/$scene-$threads" >"$T/log" 2>&1; then
      passes=$((passes+1)); echo "ok: $scene on $threads threads"
    else
      fails=$((fails+1)); echo "FAIL: $scene on $threads threads:"; cat "$T/log"
    fi
  done
done
echo "$passes passed, $fails failed"
[ $fails -eq 0 ]
