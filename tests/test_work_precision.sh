#!/usr/bin/env bash
# tools/work_precision.py on a tiny case: a table with the reference at 0 %
# and each setting's error and cost, its CSV, the runs reused when measured
# again; an unknown scene or setting is exit 2 and names it.
# Usage: tests/test_work_precision.sh SOURCE_DIR BUILD_DIR   (PYTHON: default /usr/bin/python3)
set -u
SRC=$1 BUILD=$2
PY="${PYTHON:-/usr/bin/python3}"
T=$(mktemp -d); trap 'rm -rf "$T"' EXIT
passes=0; fails=0
ok()  { passes=$((passes + 1)); echo "ok: $1"; }
bad() { fails=$((fails + 1)); echo "FAIL: $1"; }
WP=("$PY" "$SRC/tools/work_precision.py" "$BUILD" --scenes hang --humidity 0.7 --grid 11
    --duration 0.1 --settings symplectic-5e-5,xpbd-10 --jobs 2 --out "$T/wp")

if "${WP[@]}" >"$T/table" 2>"$T/err"; then
  grep -q '^| reference | [0-9.]* | 0.0 % |' "$T/table" && grep -q '^| xpbd-10 | ' "$T/table" &&
    grep -q '^| hang | 0.7 | ' "$T/table" && ok "table" || bad "table: $(cat "$T/table")"
  rows=$(tail -n +2 "$T/wp/work_precision.csv" | wc -l)
  [ "$rows" -eq 3 ] && ok "csv: a row per setting" || bad "csv has $rows rows"
  # The same command again reuses the runs: the same table, to the digit.
  "${WP[@]}" >"$T/again" 2>&1 && cmp -s "$T/table" "$T/again" && ok "runs reused" ||
    bad "second table differs: $(diff "$T/table" "$T/again" | head -5)"
else
  bad "tiny case: exit code $?: $(cat "$T/err")"
fi
"$PY" "$SRC/tools/work_precision.py" "$BUILD" --scenes nowhere >/dev/null 2>"$T/err"
[ $? -eq 2 ] && grep -qF "unknown scene 'nowhere'" "$T/err" && ok "unknown scene" || bad "unknown scene: $(cat "$T/err")"
"$PY" "$SRC/tools/work_precision.py" "$BUILD" --settings fastest >/dev/null 2>"$T/err"
[ $? -eq 2 ] && grep -qF "unknown setting 'fastest'" "$T/err" && ok "unknown setting" || bad "unknown setting: $(cat "$T/err")"
echo "$passes passed, $fails failed"
[ "$fails" -eq 0 ]
