#!/bin/bash
# The layout issue 40 set: Python binds the library's public headers alone (no
# header of apps/), a run has one frame loop (in study/run.cpp, which the
# command line and Python both call), and the command line's run stays thin.
# Usage: test_layout.sh SOURCE_DIR
set -u
SRC=$(realpath "$1"); cd "$SRC" || exit 1
fails=0
ok()  { echo "ok: $1"; }
bad() { fails=$((fails + 1)); echo "FAIL: $1"; }

# Every quoted include of python/src is a file of include/.
outside=$(grep -ho '#include "[^"]*"' python/src/* | sed 's/#include "\(.*\)"/\1/' |
          while read -r h; do [ -f "include/$h" ] || echo "$h"; done)
[ -z "$outside" ] && ok "python/src includes include/ alone" ||
  bad "python/src includes what include/ does not hold: $outside"
grep -q "apps" python/CMakeLists.txt && bad "python/CMakeLists.txt names apps/" ||
  ok "the Python module's build names no folder of apps/"

# One frame loop: the frames' times are walked in study/ (and by the
# viewer's renderer, which draws its own frame rate), nowhere else.
loops=$(grep -rln "frame_time(" apps python src study | grep -v "^study/" | grep -v "^apps/viewer/render.cpp$")
[ -z "$loops" ] && ok "frames are walked in study/ alone (and the renderer's own)" ||
  bad "a frame loop outside study/: $loops"

lines=$(wc -l < apps/cli/run.cpp)
[ "$lines" -lt 300 ] && ok "apps/cli/run.cpp: $lines lines" || bad "apps/cli/run.cpp: $lines lines, 300 or more"
[ $fails -eq 0 ]
