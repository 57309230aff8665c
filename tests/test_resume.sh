#!/usr/bin/env bash
# Kill and resume: a small fast run killed by SIGINT, SIGTERM and SIGKILL at
# random moments (TRIALS each, 20 by default) always leaves a metrics.csv of
# whole rows, and `wetcloth run --resume` from it (SIGKILL: from the last
# periodic checkpoint) ends with the bytes of a run never stopped: metrics.csv,
# the last frame, the caches (cloth.pc2, cloth.usda, cloth.pvd). Then the
# refusals, exit 2 with a message naming the file: a checkpoint of another
# scene, of another format, damaged, cut short, none at all, a metrics.csv
# that is not the checkpoint's, and options that would change the scene.
set -u
W="$1"; TRIALS="${TRIALS:-20}"
T=$(mktemp -d)
trap 'rm -rf "$T"' EXIT
# ok, bad, rows_whole
. "$(dirname "$0")/lib.sh"

# The scene: 9 x 9 particles, 0.3 s at 100 frames/s, every cache, a checkpoint
# every 0.1 s of simulated time (a run takes about 0.4 s here).
RUN=(run hang --grid 9 --duration 0.3 --set integrator.dt=2e-4 --set run.fps=100 --threads 1
     --export usd,pc2,vtk --checkpoint-every 0.1 --quiet)
LAST=frames/frame_00030.obj

# The folder's outputs are the reference run's, byte for byte. Prints what differs.
same_as_ref() {
  local d="$1" f
  for f in metrics.csv "$LAST" cloth.pc2 cloth.usda cloth.pvd vtk/cloth_00030.vtp; do
    cmp -s "$T/ref/$f" "$d/$f" || { echo "$f differs"; return 1; }
  done
  [ "$(ls "$d/frames" | wc -l)" = "$(ls "$T/ref/frames" | wc -l)" ] || { echo "frame count differs"; return 1; }
  [ ! -e "$d/checkpoint.state" ] || { echo "checkpoint.state left after a whole run"; return 1; }
  [ ! -e "$d/.cloth.usda.samples" ] || { echo ".cloth.usda.samples left after a whole run"; return 1; }
  [ -z "$(find "$d" -name '*.tmp')" ] || { echo "temporary files left: $(find "$d" -name '*.tmp')"; return 1; }
  grep -q '"status": "ok"' "$d/summary.json" || { echo "summary.json: $(cat "$d/summary.json")"; return 1; }
}

start=$(date +%s)
"$W" "${RUN[@]}" --out "$T/ref" >/dev/null 2>"$T/err" || { echo "FAIL: the reference run: $(cat "$T/err")"; exit 1; }
[ -f "$T/ref/$LAST" ] || { echo "FAIL: the reference run has no $LAST"; exit 1; }

for sig in INT TERM KILL; do
  want=$((128 + $(kill -l "$sig")))
  for trial in $(seq "$TRIALS"); do
    out="$T/$sig-$trial"
    "$W" "${RUN[@]}" --out "$out" >/dev/null 2>"$T/err" & pid=$!
    # SIGKILL resumes from a periodic checkpoint: wait for the first.
    ready="$out/metrics.csv"; [ "$sig" = KILL ] && ready="$out/checkpoint.state"
    wait_for "$ready" $pid
    window=25; [ "$sig" = KILL ] && window=15  # hundredths of a second
    sleep "$(printf '0.%02d' $((RANDOM % window)))"
    kill -"$sig" $pid 2>/dev/null; wait $pid; code=$?
    if [ $code -eq 0 ]; then echo "note: $sig #$trial: the run ended before the signal"; continue; fi
    if [ $code -ne $want ]; then bad "SIG$sig #$trial: exit $code, want $want: $(cat "$T/err")"; continue; fi
    killed=; [ "$sig" = KILL ] && killed=killed
    if why=$(rows_whole "$out/metrics.csv" $killed); [ -n "$why" ]; then bad "SIG$sig #$trial: $why"; continue; fi
    # Killed outright, the rows are the reference run's bytes (the cut row: the start of its next).
    if [ "$sig" = KILL ] && ! cmp -s -n "$(stat -c %s "$out/metrics.csv")" "$out/metrics.csv" "$T/ref/metrics.csv"; then
      bad "SIG$sig #$trial: metrics.csv is not the start of the reference run's"; continue
    fi
    rows=$(($(wc -l <"$out/metrics.csv") - 1))
    # Killed after the run ended whole (summary.json "ok", the checkpoint gone),
    # while it removed its USD samples: --resume finishes that and does nothing else.
    if [ ! -s "$out/checkpoint.state" ] && ! grep -q '"status": "ok"' "$out/summary.json" 2>/dev/null; then
      bad "SIG$sig #$trial: no checkpoint.state"; continue
    fi
    "$W" run --resume "$out" --quiet >/dev/null 2>"$T/err"; code=$?
    if [ $code -ne 0 ]; then bad "SIG$sig #$trial: --resume exit $code: $(cat "$T/err")"; continue; fi
    if why=$(same_as_ref "$out"); [ -n "$why" ]; then bad "SIG$sig #$trial: after --resume: $why"; continue; fi
    ok "SIG$sig #$trial: exit $want with $rows whole rows; --resume gives the same bytes"
    rm -rf "$out"
  done
done

# Stopped twice, resumed twice (with other threads: they never change the bits).
out="$T/twice"
"$W" "${RUN[@]}" --out "$out" >/dev/null 2>&1 & pid=$!
wait_for "$out/checkpoint.state" $pid
kill -KILL $pid; wait $pid 2>/dev/null
"$W" run --resume "$out" --threads 2 --quiet >/dev/null 2>&1 & pid=$!
sleep 0.1; kill -INT $pid; wait $pid; code=$?
"$W" run --resume "$out" --quiet >/dev/null 2>"$T/err" && why=$(same_as_ref "$out") && [ -z "$why" ] &&
  ok "killed, resumed and stopped ($code), resumed again: the same bytes" ||
  bad "killed, resumed, stopped ($code), resumed: ${why:-} $(cat "$T/err")"

# Two signals, the second at a random moment after the first (as the run
# writes its last frame, its checkpoint and cloth.usda): out at once, no
# temporary file left.
for trial in 1 2 3 4 5; do
  out="$T/twice-int-$trial"
  "$W" "${RUN[@]}" --out "$out" >/dev/null 2>"$T/err" & pid=$!
  wait_for "$out/metrics.csv" $pid
  kill -INT $pid; sleep "$(printf '0.%02d' $((RANDOM % 10)))"; kill -INT $pid 2>/dev/null; wait $pid; code=$?
  if [ $code -eq 0 ]; then echo "note: two SIGINTs #$trial: the run ended before the signals"; continue; fi
  left=$(find "$out" -name '*.tmp')
  [ $code -eq 130 ] && [ -z "$left" ] && [ -z "$(rows_whole "$out/metrics.csv")" ] &&
    ok "two SIGINTs #$trial: exit 130, no temporary file" ||
    bad "two SIGINTs #$trial: exit $code, left: $left $(cat "$T/err")"
done

# --- refusals: exit 2, a message naming the file and what is wrong, nothing changed.
# A stopped run to take checkpoints from, and another scene's.
"$W" run hang --grid 9 --duration 30 --set integrator.dt=2e-4 --threads 1 --quiet --out "$T/stopped" \
  >/dev/null 2>&1 & pid=$!
wait_for "$T/stopped/metrics.csv" $pid
kill -INT $pid; wait $pid
"$W" run drop-table --grid 9 --duration 30 --set integrator.dt=2e-4 --threads 1 --quiet --out "$T/other" \
  >/dev/null 2>&1 & pid=$!
wait_for "$T/other/metrics.csv" $pid
kill -INT $pid; wait $pid
good="$T/stopped/checkpoint.state"
cp "$good" "$T/good.state"
refused() {  # refused NAME PATTERN [ARGS...]: exit 2, PATTERN in the message
  local name="$1" pattern="$2"; shift 2
  local before; before=$(md5sum "$T/stopped/metrics.csv")
  "$W" run "$@" --quiet >/dev/null 2>"$T/err"; local code=$?
  if [ $code -eq 2 ] && grep -q -- "$pattern" "$T/err" && [ "$(md5sum "$T/stopped/metrics.csv")" = "$before" ]; then
    ok "$name: exit 2, $(head -1 "$T/err")"
  else
    bad "$name: exit $code (want 2 and '$pattern'): $(cat "$T/err")"
  fi
  cp "$T/good.state" "$good"
}
cp "$T/other/checkpoint.state" "$good"
refused "another scene's checkpoint" "$good: a checkpoint of another scene than $T/stopped/scene.toml" --resume "$T/stopped"
/usr/bin/python3 -c "
import sys; b = bytearray(open(sys.argv[1], 'rb').read()); b[16] = 99; open(sys.argv[1], 'wb').write(b)" "$good"
refused "another format version" "$good: a checkpoint of format 99" --resume "$T/stopped"
/usr/bin/python3 -c "
import sys; b = bytearray(open(sys.argv[1], 'rb').read()); b[len(b) // 2] ^= 1; open(sys.argv[1], 'wb').write(b)" "$good"
refused "a damaged checkpoint" "$good: the checksum does not match" --resume "$T/stopped"
head -c 200 "$T/good.state" >"$good"
refused "a checkpoint cut short" "$good: the checksum does not match" --resume "$T/stopped"
echo "not a checkpoint" >"$good"
refused "not a checkpoint" "$good: not a wetcloth checkpoint" --resume "$T/stopped"
refused "a scene with --resume" "would change it" hang --resume "$T/stopped"
refused "--set with --resume" "--set would change it" --resume "$T/stopped" --set cloth.humidity=1
mkdir "$T/empty"
refused "no checkpoint" "$T/empty/checkpoint.state: no checkpoint to resume from" --resume "$T/empty"
refused "no folder" "not a folder of a run" --resume "$T/nowhere"
cp "$T/stopped/metrics.csv" "$T/metrics.csv"
head -c 300 "$T/metrics.csv" >"$T/stopped/metrics.csv"
"$W" run --resume "$T/stopped" --quiet >/dev/null 2>"$T/err"; code=$?
[ $code -eq 2 ] && grep -q "$T/stopped/metrics.csv: not the metrics.csv $good continues" "$T/err" &&
  ok "a metrics.csv shorter than the checkpoint's: exit 2, $(cat "$T/err")" ||
  bad "a metrics.csv shorter than the checkpoint's: exit $code: $(cat "$T/err")"
cp "$T/metrics.csv" "$T/stopped/metrics.csv"
# A run that ended whole: nothing to resume, and nothing changed.
before=$(md5sum "$T/ref/metrics.csv" "$T/ref/summary.json")
"$W" run --resume "$T/ref" >"$T/log" 2>&1; code=$?
[ $code -eq 0 ] && grep -q "nothing to resume" "$T/log" && [ "$(md5sum "$T/ref/metrics.csv" "$T/ref/summary.json")" = "$before" ] &&
  ok "--resume of a run that ended whole: exit 0, $(cat "$T/log")" ||
  bad "--resume of a run that ended whole: exit $code: $(cat "$T/log")"
# And the folder, untouched by the refusals, resumes.
"$W" run --resume "$T/stopped" --quiet >/dev/null 2>"$T/err" & pid=$!
sleep 0.3; kill -TERM $pid; wait $pid; code=$?
[ $code -eq 143 ] && [ -z "$(rows_whole "$T/stopped/metrics.csv")" ] &&
  ok "after the refusals the folder resumes (stopped again: exit 143)" ||
  bad "after the refusals: exit $code: $(cat "$T/err")"

echo "$passes passed, $fails failed in $(($(date +%s) - start)) s"
[ $fails -eq 0 ]
