#!/usr/bin/env bash
# `wetcloth sweep --vary`: a 3 x 2 sweep run at once, and the same sweep run as
# 6 tasks of examples/cluster/sweep.slurm (SLURM_ARRAY_TASK_ID set by hand)
# and gathered, give the same sweep.csv; a partial gather lists what is missing.
# Usage: test_sweep_cluster.sh WETCLOTH SOURCE_DIR
set -u
W=$1; SRC=$2
T=$(mktemp -d); trap 'rm -rf "$T"' EXIT
fails=0
ok() { echo "ok: $1"; }
bad() { echo "FAIL: $1"; fails=$((fails + 1)); }

VARY="--vary cloth.humidity=0.3,0.5,0.7 --vary material.stretch_stiffness=100,200"
EXTRA="--grid 9 --duration 0.05"
# shellcheck disable=SC2086
"$W" sweep pull-straight $VARY $EXTRA --no-plots --quiet --out "$T/once"; code=$?
[ $code -eq 0 ] && [ "$(head -1 "$T/once/sweep.csv" | cut -d, -f1-4)" = \
  "case,material.stretch_stiffness,air_model,humidity" ] && [ "$(wc -l <"$T/once/sweep.csv")" -eq 7 ] &&
  [ -s "$T/once/omega_0.70_stretch_stiffness=200/metrics.csv" ] &&
  ok "a 3 x 2 sweep: 6 cases, a column per varied key" || bad "sweep at once: exit $code, $(head -3 "$T/once/sweep.csv")"

# shellcheck disable=SC2086
"$W" sweep pull-straight $VARY $EXTRA --list --out "$T/listed" >"$T/list"
[ "$(wc -l <"$T/list")" -eq 6 ] && [ "$(head -1 "$T/list")" = \
  "$(printf '0\tomega_0.30_stretch_stiffness=100\tcloth.humidity=0.3 material.stretch_stiffness=100')" ] &&
  [ ! -e "$T/listed" ] && ok "--list: a case per line, index first" || bad "--list: $(cat "$T/list")"

for i in 0 1 2 3 4 5; do
  SLURM_ARRAY_TASK_ID=$i SLURM_CPUS_PER_TASK=1 WETCLOTH="$W" OUT="$T/array" VARY="$VARY" EXTRA="$EXTRA" \
    bash "$SRC/examples/cluster/sweep.slurm" || bad "task $i: exit $?"
  if [ $i -eq 3 ]; then  # a gather before the array has finished: the missing ones listed, exit 1
    "$W" sweep --gather "$T/array" --no-plots --quiet 2>"$T/err"; code=$?
    [ $code -eq 1 ] && grep -q "missing 2 of 6 cases" "$T/err" && grep -q "5 omega_0.70_stretch_stiffness=200" "$T/err" &&
      [ "$(wc -l <"$T/array/sweep.csv")" -eq 5 ] && ok "--gather of 4 of 6 cases: lists the 2 missing, exit 1" ||
      bad "partial gather: exit $code, $(cat "$T/err")"
  fi
done
"$W" sweep --gather "$T/array" --quiet >/dev/null; code=$?
[ $code -eq 0 ] && cmp -s "$T/once/sweep.csv" "$T/array/sweep.csv" && [ -s "$T/array/fig7.png" ] &&
  ok "6 --case tasks gathered: the same sweep.csv as the sweep at once" ||
  { bad "gathered sweep.csv differs (exit $code)"; diff "$T/once/sweep.csv" "$T/array/sweep.csv" | head; }

# The shorthands still name cases as before; bad input exits 2, naming what.
"$W" sweep hang --air-models exchange,sealed --humidity 0.5 --grid 9 --duration 0.01 --no-plots --quiet --list >"$T/l2"
[ "$(cut -f2 "$T/l2" | tr '\n' ' ')" = "exchange_omega_0.50 sealed_omega_0.50 " ] &&
  ok "--air-models and --humidity: cases named as before" || bad "shorthand names: $(cat "$T/l2")"
"$W" sweep hang --vary "cloth.resolution=[9,9],[11,11]" --duration 0.01 --list >"$T/l3"
[ "$(cut -f2 "$T/l3" | tr '\n' ' ')" = "resolution=9x9 resolution=11x11 " ] &&
  ok "--vary an array: values split outside brackets" || bad "array vary: $(cat "$T/l3")"
expect2() {  # expect2 TEXT ARGS...: exit 2 and TEXT in the error
  local text=$1; shift
  "$W" "$@" >/dev/null 2>"$T/err"; local code=$?
  [ $code -eq 2 ] && grep -q -- "$text" "$T/err" && ok "bad input: $text" || bad "$*: exit $code, $(cat "$T/err")"
}
expect2 "cloth.humidty: unknown key" sweep hang --vary cloth.humidty=0.1,0.2 --list
expect2 "cloth.humidity: value 3.0 is out of range" sweep hang --vary cloth.humidity=0.1,3 --list
expect2 "0.5 is given twice" sweep hang --vary cloth.humidity=0.5,0.50 --list
expect2 "cloth.humidity is varied twice" sweep hang --humidity 0.2 --vary cloth.humidity=0.5 --list
expect2 "nothing to vary" sweep hang --list
expect2 "the sweep has 2 cases, 0 to 1" sweep hang --vary cloth.humidity=0.1,0.2 --case 2 --out "$T/x"
expect2 "no cases.csv" sweep --gather "$T"
expect2 "takes no scene" sweep hang --gather "$T/array"
[ ! -e "$T/x" ] && ok "a bad --case writes nothing" || bad "a bad --case made $T/x"
[ $fails -eq 0 ] && echo "all sweep cluster checks passed" || { echo "$fails failed"; exit 1; }
