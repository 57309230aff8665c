#!/usr/bin/env bash
# Validates wetcloth against the paper: runs its experiments at full resolution
# (the scenes' defaults, 51x51), each a `wetcloth sweep` over humidity, into
# validation/runs/<name>/, then writes validation/report.md with its figures in
# validation/figures/ (tools/validation_report.py).
#
# Usage: tools/validate.sh BUILD_DIR [NAME...]
#   NAME...  rerun only these sweeps (pull-straight pull-oblique pull-corner
#            drag-corner drape-ball peel-rig air-models, and for the first three
#            and drape-ball implicit-<scene> and explicit-<scene>: ensembles of
#            ω = 0.7 moved by k·1e-7, implicit Euler at 1/240 s against the
#            explicit step, which the report compares; grid-<scene>-<G>: the
#            grid convergence of pull-straight, pull-oblique and drape-ball at
#            ω = 0.7 on G = 31, 101 and 201 particles (51 is their sweep above), and
#            of the cantilever's bending length on 26, 51 and 101; claims101-<scene>:
#            the paper's sweeps again at 101 x 101; scatter101-pull-oblique:
#            the oblique pull's ensemble about ω = 0.7 at 101 x 101), or the run
#            free-cloth (a law the model keeps; the other, the peel's force
#            balance, is read from the peel-rig sweep), or work-precision
#            (tools/work_precision.py on the paper's scenes); the report still covers
#            every sweep in validation/runs.
# A scene whose `wetcloth check` fails is skipped, with a note in the report.
# Each sweep's output goes to validation/runs/<name>.log.
# Environment: PYTHON (default /usr/bin/python3), JOBS (default 2).
set -u
PAPER="pull-straight pull-oblique pull-corner drag-corner drape-ball peel-rig"
AGREEMENT="pull-straight pull-oblique pull-corner drape-ball"
GRIDDED="pull-straight pull-oblique drape-ball"
GRIDS="31 101 201"
CANTILEVER_GRIDS="26 51 101"
NAMES="pull-straight pull-oblique pull-corner drag-corner drape-ball peel-rig air-models free-cloth scatter101-pull-oblique $(for s in $AGREEMENT; do printf 'implicit-%s explicit-%s ' "$s" "$s"; done)"
NAMES="$NAMES $(for s in $GRIDDED; do for g in $GRIDS; do printf 'grid-%s-%s ' "$s" "$g"; done; done)"
NAMES="$NAMES $(for g in $CANTILEVER_GRIDS; do printf 'grid-cantilever-%s ' "$g"; done) work-precision"
NAMES="$NAMES $(for s in $PAPER; do printf 'claims101-%s ' "$s"; done)"
COMMAND="tools/validate.sh $*"
[ $# -ge 1 ] || { echo "usage: tools/validate.sh BUILD_DIR [NAME...]" >&2; exit 2; }
W="$(cd "$1" 2>/dev/null && pwd)/wetcloth"
[ -x "$W" ] || { echo "validate.sh: error: $1/wetcloth: no such program (build first)" >&2; exit 2; }
shift
for n in "$@"; do
  [[ " $NAMES " == *" $n "* ]] || { echo "validate.sh: error: unknown sweep '$n' (one of: $NAMES)" >&2; exit 2; }
done
ONLY=" $* "; [ $# -gt 0 ] || ONLY=""
PYTHON=${PYTHON:-/usr/bin/python3}; [ -x "$PYTHON" ] || PYTHON=python3
JOBS=${JOBS:-2}
ROOT=$(cd "$(dirname "$0")/.." && pwd)
cd "$ROOT" || exit 2
RUNS=validation/runs
mkdir -p "$RUNS"

# record NAME OUTCOME SECONDS COMMAND: NAME's line in $RUNS/commands.log (tab-separated).
record() {
  { grep -v "^$1	" "$RUNS/commands.log" 2>/dev/null; printf '%s\t%s\t%s\t%s\n' "$@"; } >"$RUNS/commands.log.tmp"
  mv "$RUNS/commands.log.tmp" "$RUNS/commands.log"
}

# sweep NAME SCENE ARGS...: `wetcloth sweep SCENE ARGS...` into $RUNS/NAME (fresh),
# recorded in $RUNS/commands.log; or $RUNS/NAME.skipped when the scene fails its check.
sweep() {
  local name=$1 scene=$2; shift 2
  if [ -n "$ONLY" ] && [[ "$ONLY" != *" $name "* ]]; then return; fi
  rm -rf "${RUNS:?}/$name" "$RUNS/$name.skipped" "$RUNS/$name.log"
  if ! "$W" check "$scene" >/dev/null 2>"$RUNS/$name.check"; then
    { echo "\`wetcloth check $scene\` failed: $(head -3 "$RUNS/$name.check")"; } > "$RUNS/$name.skipped"
    echo "$name: skipped, $(head -1 "$RUNS/$name.check")"
    record "$name" skipped 0 "$W check $scene"
    rm -f "$RUNS/$name.check"
    return
  fi
  rm -f "$RUNS/$name.check"
  local cmd=("$W" sweep "$scene" "$@" --jobs "$JOBS" --out "$RUNS/$name") start=$SECONDS code
  echo "$name: ${cmd[*]}"
  "${cmd[@]}" >"$RUNS/$name.log" 2>&1; code=$?
  echo "$name: exit code $code after $((SECONDS - start)) s (log: $RUNS/$name.log)"
  record "$name" "$code" "$((SECONDS - start))" "${cmd[*]}"
}

# run NAME SCENE ARGS...: one `wetcloth run SCENE ARGS...` into $RUNS/NAME (fresh),
# recorded in $RUNS/commands.log.
run() {
  local name=$1 scene=$2; shift 2
  if [ -n "$ONLY" ] && [[ "$ONLY" != *" $name "* ]]; then return; fi
  rm -rf "${RUNS:?}/$name" "$RUNS/$name.skipped" "$RUNS/$name.log"
  local cmd=("$W" run "$scene" "$@" --out "$RUNS/$name") start=$SECONDS code
  echo "$name: ${cmd[*]}"
  "${cmd[@]}" >"$RUNS/$name.log" 2>&1; code=$?
  echo "$name: exit code $code after $((SECONDS - start)) s (log: $RUNS/$name.log)"
  record "$name" "$code" "$((SECONDS - start))" "${cmd[*]}"
}

HUMIDITY=0,0.3,0.5,0.7,1
for scene in $PAPER; do
  sweep "$scene" "$scene" --humidity "$HUMIDITY" --render  # --render: a contact sheet per scene
done
# Laws the model keeps (docs/model.md section 2). A free cloth (no table,
# gravity, air, adhesion or damping) pulled by 1 N along x accelerates at F/M:
# strain limiting conserves momentum. Springs of 20 N/m let the pull stretch it
# past τ_c every step, so the limiter acts throughout (with the farther end
# alone moving, it accelerated 54 % too fast). A few seconds. The other law, a
# rig's force balancing the load of what it lifts, is read from the peel-rig
# sweep above.
run free-cloth pull-straight --duration 0.1 --set run.meshes=false --set table.enabled=false \
  --set 'contact.surface="none"' --set 'air.model="off"' --set adhesion.enabled=false \
  --set 'forces.gravity=[0,0,0]' --set forces.viscous_damping=0 --set wind.k=0 \
  --set self_collision.enabled=false --set springs.structural_k=20 --set springs.shear_k=20 \
  --set springs.structural_damping=0 --set springs.shear_damping=0 \
  --set material.bending_damping=0 --set 'handle.pull.force=[1,0,0]' --set handle.pull.max_height=0
# Fig. 8 compares the forms of a cloth pulled up at one point, so the rig lifts
# both models to the same height: 1 cm, where sealed air already takes ~15 N
# (at ~1.3 cm its 60 kPa deficit throws the particles crossing the contact
# threshold past the blow-up speed).
sweep air-models peel-rig --air-models exchange,sealed --humidity 0.5,1 --duration 0.5
# Implicit Euler at 1/240 s against the explicit step (issue 4: the final handle
# height and contact area within 5 %). The pulls' contact patterns are chaotic:
# ω moved by 1e-7 moves the straight pull's contact area by a few percent, and
# lands the implicit oblique pull's handle at one of two heights. So each side is
# an ensemble, ω = 0.7 moved by k·1e-7 for k = -2..2 (the explicit sweeps above
# ran k = 0), and the report compares means.
JITTERED=0.6999998,0.6999999,0.7000001,0.7000002
for scene in $AGREEMENT; do
  sweep "explicit-$scene" "$scene" --humidity "$JITTERED" --no-plots
  sweep "implicit-$scene" "$scene" --humidity "0.7,$JITTERED" --no-plots \
    --set 'integrator.type="implicit-euler"' --set integrator.dt=0.004166666666666667
done

# The material does not change with the grid (docs/model.md section 1, issue 25):
# the same cloth (--grid: its handle's patch in metres, the explicit step
# shrunk with its stability limit) at ω = 0.7 on coarser and finer grids, and
# the cantilever's bending length at 12, 6 and 3 mm spacing.
for scene in $GRIDDED; do
  for g in $GRIDS; do
    sweep "grid-$scene-$g" "$scene" --grid "$g" --humidity 0.7 --no-plots
  done
done
for g in $CANTILEVER_GRIDS; do
  sweep "grid-cantilever-$g" cantilever --grid "$g" --humidity 0 --no-plots
done

# The paper's claims again on the finer grid, 101 x 101 (its step shrunk with
# the stability limit): a claim that holds at 51 only would be the grid's.
# About 12 times a 51 sweep's cost: an hour and a half on 2 cores for the six.
for scene in $PAPER; do
  sweep "claims101-$scene" "$scene" --grid 101 --humidity "$HUMIDITY" --no-plots
done
# The oblique pull's own scatter at 101 x 101, as explicit-pull-oblique's at
# 51: its lifted-area claim there is read against it (two minutes).
sweep scatter101-pull-oblique pull-oblique --grid 101 --humidity "$JITTERED" --no-plots

# Work against precision (docs/performance.md): each integrator setting's
# cost and error against the reference on the paper's scenes at ω = 0, 0.7, 1.
if [ -z "$ONLY" ] || [[ "$ONLY" == *" work-precision "* ]]; then
  start=$SECONDS
  cmd=("$PYTHON" tools/work_precision.py "$(dirname "$W")" --jobs "$JOBS" --out "$RUNS/work-precision"
       --scenes pull-straight,pull-oblique,pull-corner,drag-corner,drape-ball,peel-rig
       --table "$RUNS/work-precision/table.md")
  echo "work-precision: ${cmd[*]}"
  mkdir -p "$RUNS/work-precision"
  "${cmd[@]}" >"$RUNS/work-precision.log" 2>&1; code=$?
  echo "work-precision: exit code $code after $((SECONDS - start)) s (log: $RUNS/work-precision.log)"
  record work-precision "$code" "$((SECONDS - start))" "${cmd[*]}"
fi

"$PYTHON" tools/validation_report.py "$RUNS" validation/report.md --command "$COMMAND"
