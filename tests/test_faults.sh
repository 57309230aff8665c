#!/usr/bin/env bash
# Outputs under faults: a full disk (injected: WETCLOTH_FAIL_AFTER_BYTES), a
# read-only folder, two runs into one folder, and SIGINT / SIGTERM / SIGKILL
# at random moments. After each: the documented exit code, a message naming
# the file and the reason, whole rows in metrics.csv, no temporary files.
set -u
W="$1"; TRIALS="${TRIALS:-8}"
T=$(mktemp -d)
cleanup() { [ -n "${RO:-}" ] && chattr -i "$RO" 2>/dev/null; chmod -R u+w "$T" 2>/dev/null; rm -rf "$T"; }
trap cleanup EXIT
# ok, bad, rows_whole
. "$(dirname "$0")/lib.sh"
no_temporaries() {
  local left; left=$(find "$1" -name '*.tmp' 2>/dev/null)
  [ -z "$left" ] || { echo "left: $left"; return 1; }
}

# --- a full disk, at several moments: in scene.toml, in metrics.csv's header,
# part way through a row, in a frame, in summary.json.
for bytes in 0 100 6000 9000 12000 40000 200000 20000000; do
  out="$T/full_$bytes"
  WETCLOTH_FAIL_AFTER_BYTES=$bytes "$W" run hang --duration 0.5 --set run.fps=100 --out "$out" \
    --quiet 2>"$T/err" >/dev/null; code=$?
  if [ $bytes -eq 20000000 ]; then  # more than the run writes: no fault
    [ $code -eq 0 ] && ok "full disk after $bytes bytes: not reached, exit 0" ||
      bad "full disk after $bytes bytes: exit $code: $(cat "$T/err")"
    continue
  fi
  why=$(rows_whole "$out/metrics.csv" 2>&1); whole=$?
  [ -f "$out/metrics.csv" ] || whole=0  # failed before metrics.csv was begun
  if [ $code -ne 4 ]; then bad "full disk after $bytes bytes: exit $code, want 4: $(cat "$T/err")"
  elif ! grep -q "$out/.*: No space left on device" "$T/err"; then
    bad "full disk after $bytes bytes: message names no file and reason: $(cat "$T/err")"
  elif [ $whole -ne 0 ]; then bad "full disk after $bytes bytes: metrics.csv: $why"
  elif ! no_temporaries "$out" >/dev/null; then bad "full disk after $bytes bytes: $(no_temporaries "$out")"
  else ok "full disk after $bytes bytes: exit 4, $(head -1 "$T/err")"; fi
done

# --- a read-only folder (immutable as root; without write permission otherwise)
RO="$T/readonly"
"$W" run hang --duration 0.05 --out "$RO" --quiet >/dev/null 2>&1
if { [ "$(id -u)" -eq 0 ] && chattr +i "$RO" 2>/dev/null; } || { [ "$(id -u)" -ne 0 ] && chmod a-w "$RO"; }; then
  "$W" run hang --duration 0.05 --out "$RO" --quiet 2>"$T/err" >/dev/null; code=$?
  [ $code -eq 4 ] && grep -q "$RO/.*: \(Operation not permitted\|Permission denied\|Read-only file system\)" "$T/err" &&
    [ -s "$RO/metrics.csv" ] &&
    ok "read-only folder: exit 4, $(cat "$T/err"), the earlier run's files kept" ||
    bad "read-only folder: exit $code: $(cat "$T/err")"
  chattr -i "$RO" 2>/dev/null; chmod u+w "$RO"
else
  echo "skipped: cannot make a read-only folder here"
fi

# --- two runs into one folder: the second refuses (exit 2), the first goes on.
out="$T/twice"
"$W" run hang --duration 30 --out "$out" --quiet >/dev/null 2>&1 & first=$!
wait_for "$out/metrics.csv" $first
"$W" run hang --duration 0.05 --out "$out" --quiet 2>"$T/err" >/dev/null; code=$?
kill -0 $first 2>/dev/null; alive=$?
kill -TERM $first 2>/dev/null; wait $first; first_code=$?
[ $code -eq 2 ] && grep -q "another wetcloth run is writing into it" "$T/err" && [ $alive -eq 0 ] &&
  [ $first_code -eq 143 ] && ok "a second run into one --out: exit 2, $(cat "$T/err")" ||
  bad "a second run into one --out: exit $code (first alive $alive, exit $first_code): $(cat "$T/err")"
# and once the first has ended, the folder is free again.
"$W" run hang --duration 0.05 --out "$out" --quiet >/dev/null 2>"$T/err" && ok "the folder is free after it" ||
  bad "the folder after the first run: $(cat "$T/err")"

# --- signals at random moments, frames and rows as fast as the steps.
for sig in INT TERM KILL; do
  for trial in $(seq "$TRIALS"); do
    out="$T/sig_${sig}_$trial"
    "$W" run hang --duration 100 --set run.fps=240 --out "$out" --quiet >/dev/null 2>"$T/err" & pid=$!
    wait_for "$out/metrics.csv" $pid
    sleep "0.$((RANDOM % 30))"
    kill -"$sig" $pid; wait $pid 2>/dev/null; code=$?
    want=$((128 + $(kill -l "$sig")))
    killed=; [ "$sig" = KILL ] && killed=killed
    why=$(rows_whole "$out/metrics.csv" $killed)
    if [ $code -ne $want ]; then bad "SIG$sig #$trial: exit $code, want $want: $(cat "$T/err")"; continue; fi
    if [ -n "$why" ]; then bad "SIG$sig #$trial: $why"; continue; fi
    if [ "$sig" != KILL ]; then
      last=$(tail -1 "$out/metrics.csv" | cut -d, -f1)
      if ! grep -q '"interrupted": true' "$out/summary.json" 2>/dev/null; then
        bad "SIG$sig #$trial: summary.json does not say interrupted"; continue; fi
      if ! python3 -c "import json,sys; s=json.load(open('$out/summary.json')); sys.exit(abs(s['simulated_seconds']-float('$last'))>1e-12)"; then
        bad "SIG$sig #$trial: summary.json's time is not the last row's ($last)"; continue; fi
      if ! no_temporaries "$out" >/dev/null; then bad "SIG$sig #$trial: $(no_temporaries "$out")"; continue; fi
    fi
    ok "SIG$sig #$trial: exit $code, $(($(wc -l <"$out/metrics.csv") - 1)) whole rows"
  done
done

# --- a second SIGINT: out at once, no temporary file.
out="$T/twice_int"
"$W" run hang --duration 100 --set run.fps=240 --out "$out" --quiet >/dev/null 2>"$T/err" & pid=$!
wait_for "$out/metrics.csv" $pid
kill -INT $pid; kill -INT $pid; wait $pid; code=$?
[ $code -eq 130 ] && no_temporaries "$out" >/dev/null && [ -z "$(rows_whole "$out/metrics.csv")" ] &&
  ok "two SIGINTs: exit 130, rows whole, no temporary file" ||
  bad "two SIGINTs: exit $code, $(no_temporaries "$out"), $(rows_whole "$out/metrics.csv"): $(cat "$T/err")"

# --- a sweep passes SIGINT on: its running case stops whole, no other starts.
out="$T/sweep"
"$W" sweep hang --humidity 0.1 0.5 0.9 --jobs 1 --duration 100 --no-plots --quiet --out "$out" \
  >/dev/null 2>"$T/err" & pid=$!
wait_for "$out/omega_0.10/metrics.csv" $pid
kill -INT $pid; wait $pid; code=$?
[ $code -eq 130 ] && grep -q '^omega_0.10,.*,interrupted,' "$out/sweep.csv" && [ ! -e "$out/omega_0.50" ] &&
  [ -z "$(rows_whole "$out/omega_0.10/metrics.csv")" ] && grep -q '"interrupted": true' "$out/omega_0.10/summary.json" &&
  ok "sweep, SIGINT: exit 130, the case stopped whole, no other started" ||
  bad "sweep, SIGINT: exit $code, $(cat "$out/sweep.csv" 2>&1) $(ls "$out") $(cat "$T/err")"

echo "$passes passed, $fails failed"
[ $fails -eq 0 ]
