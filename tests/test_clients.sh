#!/usr/bin/env bash
# The caches in the tools that read them (make test-clients): Blender 3.4
# (headless) imports the rest OBJ, plays the PC2 cache on a Mesh Cache modifier
# and must give every frame's vertices; VTK's XML reader (python3-vtk9) reads
# the .pvd and .vtp files. Both up axes. Debian's Blender has no USD (no USD
# library is in Debian): cloth.usda is read back by tests/io/test_caches.cpp.
set -u
W="$1"; SRC="$2"
T=$(mktemp -d); trap 'rm -rf "$T"' EXIT
fails=0
for up in z y; do
  "$W" run drop-table --grid 21 --duration 0.2 --export usd,pc2,vtk --up "$up" --out "$T/$up" --quiet ||
    { echo "FAIL: run --up $up"; fails=$((fails+1)); continue; }
  if out=$(blender -b --factory-startup --python "$SRC/tools/clients/blender_pc2.py" -- "$T/$up" 2>&1); then
    echo "ok: --up $up: $(echo "$out" | grep '^blender:')"
  else
    echo "FAIL: --up $up: Blender: $(echo "$out" | tail -5)"; fails=$((fails+1))
  fi
  if out=$(/usr/bin/python3 "$SRC/tools/clients/vtk_read.py" "$T/$up" 2>&1); then
    echo "ok: --up $up: $out"
  else
    echo "FAIL: --up $up: VTK: $(echo "$out" | tail -5)"; fails=$((fails+1))
  fi
done
[ $fails -eq 0 ]
