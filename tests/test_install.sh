#!/usr/bin/env bash
# Installs wetcloth into a temporary prefix and builds examples/step_cloth against it.
set -euo pipefail
SRC="$1"; BUILD="$2"
T=$(mktemp -d); trap 'rm -rf "$T"' EXIT
cmake --install "$BUILD" --prefix "$T/prefix" > /dev/null
cmake -S "$SRC/examples/step_cloth" -B "$T/build" -DCMAKE_PREFIX_PATH="$T/prefix" -DCMAKE_BUILD_TYPE=Release > /dev/null
cmake --build "$T/build" -j 2 > /dev/null
"$T/build/step_cloth" | tee "$T/out.txt"
grep -q "t = 1.0 s" "$T/out.txt"
echo "1 passed, 0 failed"
