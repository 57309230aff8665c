#!/usr/bin/env bash
# The command-line program end to end: outputs, reproducibility, bad input.
set -u
W="$1"; SRC="$2"
T=$(mktemp -d); trap 'rm -rf "$T"' EXIT
fails=0; passes=0
ok()   { passes=$((passes+1)); echo "ok: $1"; }
bad()  { fails=$((fails+1)); echo "FAIL: $1"; }

# expect_bad NAME EXPECTED_TEXT ARGS...: exit code 2, message names EXPECTED_TEXT, nothing written.
expect_bad() {
  local name="$1" text="$2"; shift 2
  local out="$T/bad_$name"
  "$W" run "$@" --out "$out" --quiet 2>"$T/err" >/dev/null; local code=$?
  if [ $code -ne 2 ]; then bad "$name: exit code $code, want 2"; return; fi
  if ! grep -qF -- "$text" "$T/err"; then bad "$name: message lacks '$text': $(cat "$T/err")"; return; fi
  if [ -e "$out" ]; then bad "$name: wrote $out"; return; fi
  ok "$name ($(head -1 "$T/err"))"
}

printf '[cloth]\nhumidity = = 1\n' > "$T/syntax.toml"
printf '[cloth]\nhumidty = 0.5\n' > "$T/unknown.toml"
printf '[integrator]\ndt = "small"\n' > "$T/type.toml"
printf '[cloth]\nareal_density = -0.12\n' > "$T/mass.toml"
printf '\n[cloth]\nhumidity = 1.5\n' > "$T/humid.toml"
printf '[cloth]\nresolution = [1, 5]\n' > "$T/res.toml"
printf '[integrator]\ndt = 0.0\n' > "$T/dt.toml"
printf '[material]\nbending_rigidity = -7.2e-4\n' > "$T/material.toml"
printf '[springs]\n\nbending_k = "stiff"\n' > "$T/springs.toml"
expect_bad syntax     "syntax.toml:2"                   "$T/syntax.toml"
expect_bad unknown    "unknown.toml:2: cloth.humidty"   "$T/unknown.toml"
expect_bad nearest    "did you mean cloth.humidity?"    "$T/unknown.toml"
expect_bad type       "type.toml:2: integrator.dt"      "$T/type.toml"
expect_bad mass       "mass.toml:2: cloth.areal_density" "$T/mass.toml"
expect_bad humidity   "humid.toml:3: cloth.humidity"    "$T/humid.toml"
expect_bad resolution "res.toml:2: cloth.resolution"    "$T/res.toml"
expect_bad dt         "dt.toml:2: integrator.dt"        "$T/dt.toml"
expect_bad material   "material.toml:2: material.bending_rigidity: value -0.00072 is out of range" "$T/material.toml"
expect_bad springs    "springs.toml:3: springs.bending_k: expected a number" "$T/springs.toml"
expect_bad missing    "nowhere.toml: no such file"      "$T/nowhere.toml"

# A cloth from a mesh (cloth.mesh): `check` names the mesh file and what is
# wrong with it, and exits 2; `run` refuses it the same way.
expect_check_bad() {
  local name="$1" text="$2" obj="$3"
  mkdir -p "$T/mesh_$name"
  printf '[cloth]\nmesh = "cloth.obj"\n' > "$T/mesh_$name/scene.toml"
  [ -n "$obj" ] && printf "$obj" > "$T/mesh_$name/cloth.obj"
  "$W" check "$T/mesh_$name/scene.toml" >/dev/null 2>"$T/err"; local code=$?
  if [ $code -ne 2 ]; then bad "mesh $name: check exit code $code, want 2"; return; fi
  if ! grep -qF -- "$text" "$T/err"; then bad "mesh $name: message lacks '$text': $(cat "$T/err")"; return; fi
  ok "mesh $name ($(head -1 "$T/err"))"
}
expect_check_bad nonmanifold "cloth.obj: not a manifold mesh" \
  'v 0 0 0\nv 1 0 0\nv 0 1 0\nv 0 -1 0\nv 0 0 1\nf 1 2 3\nf 2 1 4\nf 1 2 5\n'
expect_check_bad degenerate "cloth.obj: face 1 is degenerate" 'v 0 0 0\nv 1 0 0\nv 2 0 0\nf 1 2 3\n'
expect_check_bad nofaces "cloth.obj: no faces" 'v 0 0 0\nv 1 0 0\n'
expect_check_bad notobj "cloth.obj: no faces" 'this is not an OBJ file\n'
expect_check_bad index "cloth.obj: face 1 names a vertex that is not in the file" 'v 0 0 0\nv 1 0 0\nv 0 1 0\nf 1 2 9\n'
expect_check_bad absent "scene.toml: cloth.mesh" ''
expect_bad mesh_run "cloth.obj: face 1 is degenerate" "$T/mesh_degenerate/scene.toml"
# --live: the live tier over the scene's integrator; a later --set over the tier.
"$W" check pull-straight --live | grep -q '^type = "xpbd"$' &&
  "$W" check pull-straight --live | grep -q '^dt = 0.004166666666666667' &&
  "$W" check pull-straight --live --set integrator.type=implicit-euler | grep -q '^type = "implicit-euler"$' &&
  "$W" check pull-straight | grep -q '^type = "symplectic-euler"$' && ok "--live" || bad "--live"
"$W" check drape-disc | grep -q '^mesh = "meshes/cloth_disc.obj"$' && ok "check a mesh cloth" ||
  bad "check drape-disc: $("$W" check drape-disc 2>&1 | head -3)"
"$W" run drape-disc --set run.duration=0.01 --out "$T/disc" --quiet --export usd,pc2,vtk &&
  [ "$(grep -c '^vt ' "$T/disc/frames/frame_00000.obj")" = 1951 ] &&
  ok "run a mesh cloth: its UVs in the frames" || bad "run drape-disc"
# A mesh cloth's memory estimate counts its vertices, not cloth.resolution's
# grid (which it ignores: at 2001 x 2001 the grid would be refused).
"$W" run drape-disc --set 'cloth.resolution=[2001,2001]' --duration 0.001 --out "$T/discmem" \
  --quiet 2>"$T/err" && ok "a mesh cloth's memory estimate: its vertices" ||
  bad "mesh cloth memory estimate: $(cat "$T/err")"
expect_bad name       "no-such-scene"                   no-such-scene
expect_bad set        "--humidity: value 2 is out of range [0, 1]" hang --humidity 2
expect_bad duration   "--duration: value -1 is out of range" hang --duration -1
expect_bad setkey     "cloth.colour"                    hang --set cloth.colour=1
expect_bad handlename "handle.pul: the scene has no such handle (its handles: pull)" \
  pull-straight --set 'handle.pul.force=[0,0,3]'
expect_bad bracket    "cloth.resolution: Error while parsing array" \
  hang --set 'cloth.resolution=[101,101'
printf 'cloth = 5\n' > "$T/section.toml"
expect_bad section    "section.toml:1: cloth: expected a table, [cloth]" "$T/section.toml"
# Options CLI11 rejects are bad input too (its own codes are 100 and up).
expect_bad notanumber "--humidity: not a number: abc" hang --humidity abc
expect_bad option     "--frobnicate"                    hang --frobnicate
expect_bad inside     "drop-table.toml:5 with --set 'cloth.tilt=20': cloth.center: the cloth starts 1.3 mm inside the table" \
  drop-table --set cloth.tilt=20
expect_bad handletype "pull-corner.toml:14 with --set 'handle.pull.type=\"move\"': handle.pull.force: applies to force handles only" \
  pull-corner --set 'handle.pull.type="move"'
# An override the message names is named, though of another section.
expect_bad surface    "drop-table.toml with --set 'table.enabled=false': contact.surface: is 'table' but table.enabled is false" \
  drop-table --set table.enabled=false
# An --out that cannot be made, or that is a file: bad input, named, the file untouched.
"$W" run hang --out /proc/wetcloth-out --quiet 2>"$T/err"; code=$?
[ $code -eq 2 ] && grep -qF -- "--out /proc/wetcloth-out: /proc/wetcloth-out is a system folder" "$T/err" &&
  ok "--out that cannot be made: exit 2, named" || bad "--out /proc: exit $code, $(cat "$T/err")"
# A misspelt command, an option before it, or none: exit 2, and what there is.
"$W" runn hang 2>"$T/err"; code=$?
[ $code -eq 2 ] && grep -qF "unknown command 'runn' (the commands: run, scenes" "$T/err" &&
  ok "misspelt command: exit 2, named" || bad "runn: exit $code, $(cat "$T/err")"
"$W" --bogus run hang 2>"$T/err"; code=$?
[ $code -eq 2 ] && grep -qF "unknown option '--bogus' before the command" "$T/err" &&
  ok "option before the command: exit 2, named" || bad "--bogus: exit $code, $(cat "$T/err")"
"$W" 2>"$T/err"; code=$?
[ $code -eq 2 ] && grep -q "Subcommands:" "$T/err" && ok "no command: exit 2, the help" ||
  bad "no command: exit $code, $(cat "$T/err")"
# A folder named like a built-in scene (a run's --out) does not hide the scene.
mkdir -p "$T/hang"
(cd "$T" && "$W" check hang 2>&1) | grep -q '^name = "hang"' && ok "a folder named hang does not hide the scene" ||
  bad "folder hides the scene: $(cd "$T" && "$W" check hang 2>&1 | head -3)"
rmdir "$T/hang"
# A --grid that scales a scene past a range (a handle's patch, in grid steps):
# named, before anything runs (sweep's worker threads used to abort the process).
printf '[cloth]\nresolution = [11, 11]\n[handle.p]\nat = [0.5, 0.5]\npatch = 200\n' > "$T/big.toml"
"$W" sweep "$T/big.toml" --grid 101 --humidity 0.5 --out "$T/bigsweep" 2>"$T/err" >/dev/null; code=$?
[ $code -eq 2 ] && grep -qF -- "--grid 101: handle.p.patch: value 2000.0 is out of range" "$T/err" &&
  [ ! -e "$T/bigsweep" ] && ok "--grid past a range: exit 2, named, nothing written" ||
  bad "--grid past a range: exit $code, $(cat "$T/err")"
# An empty --out (an unset variable) is a mistake, not the default folder.
for cmd in "run hang" "sweep hang --humidity 0.5" "converge hang" "bench"; do
  (cd "$T" && "$W" $cmd --out "" 2>"$T/err" >/dev/null); code=$?
  [ $code -eq 2 ] && grep -qF -- "--out: an empty path" "$T/err" && [ ! -e "$T/out" ] &&
    ok "$cmd --out '': exit 2, named" || bad "$cmd --out '': exit $code, $(cat "$T/err")"
done
echo keep > "$T/afile"
"$W" run hang --out "$T/afile" --quiet 2>"$T/err"; code=$?
[ $code -eq 2 ] && grep -qF -- "--out $T/afile: exists and is not a folder" "$T/err" &&
  [ "$(cat "$T/afile")" = keep ] && ok "--out a file: exit 2, named, untouched" ||
  bad "--out a file: exit $code, $(cat "$T/err")"

# Scene files are untrusted: guarded before toml++ parses them (it overflows
# the stack on deep nesting and reaches undefined behaviour on a stray
# non-ASCII byte); every case is bad input, named, nothing written.
printf 'name = "x"\n\xc3\xa9 = 1\n' > "$T/nonascii.toml"
expect_bad nonascii   "nonascii.toml:2: a non-ASCII character outside a string or comment" "$T/nonascii.toml"
printf 'name = "\xff"\n' > "$T/utf8.toml"
expect_bad utf8       "utf8.toml:1: not valid UTF-8" "$T/utf8.toml"
python3 -c "print('[' + '.'.join(['a'] * 20000) + ']')" > "$T/deepkey.toml"
expect_bad deepkey    "deepkey.toml:1: a dotted key of more than 32 parts" "$T/deepkey.toml"
python3 -c "print('a = ' + '[' * 20000 + ']' * 20000)" > "$T/deeparray.toml"
expect_bad deeparray  "deeparray.toml:1: tables or arrays nested more than 32 deep" "$T/deeparray.toml"
head -c 1100000 /dev/zero | tr '\0' '#' > "$T/huge.toml"
expect_bad huge       "huge.toml: more than a scene's 1048576 bytes" "$T/huge.toml"
expect_bad setdeep    "characters): a dotted key of more than 32 parts" \
  hang --set "$(python3 -c "print('.'.join(['a'] * 30000))")=1"
printf '[foo]\n' > "$T/emptytable.toml"
expect_bad emptytable "emptytable.toml:1: foo: unknown table" "$T/emptytable.toml"
printf '[cloth.foo.bar]\nx = 1\n' > "$T/subtable.toml"
expect_bad subtable   "subtable.toml:1: cloth.foo: unknown table" "$T/subtable.toml"
# Runs that would take no step, or repeat frames, or need more than the machine has.
expect_bad dtlong     "integrator.dt: = 0.01 s is longer than run.duration = 0.001 s" \
  hang --set integrator.type=implicit-euler --set integrator.dt=0.01 --set run.fps=10 --duration 0.001
expect_bad fpshigh    "run.fps: = 1e+05 frames/s is above the step rate" hang --set run.fps=1e5
# (The memory guard: below, under ulimit -v.)
expect_bad disk       "with run.meshes) need about" hang --set run.fps=1000 --set integrator.dt=1e-3 \
  --set integrator.type=implicit-euler --duration 1e6
# Positions so far out that they lose the springs' precision (1e14 m wrote inf).
expect_bad center     "cloth.center: value 1e+14 is out of range [-10000, 10000]" hang --set 'cloth.center=[0,0,1e14]'
# A stiff shear spring blows a given explicit step up: the message says the
# step is over the limit and gives the shear springs' constant. Given no step,
# the scene gets a step that fraction of its own limit, and runs.
"$W" check hang --set springs.shear_k=1e7 | grep -q '^dt = 7.8[0-9]*e-07$' &&
  ok "shear_k = 1e7, no dt: the step falls with the limit" ||
  bad "shear_k = 1e7, no dt: $("$W" check hang --set springs.shear_k=1e7 | grep '^dt ')"
"$W" run hang --set springs.shear_k=1e7 --set integrator.dt=5e-5 --duration 0.01 --out "$T/shear" --quiet 2>"$T/err"; code=$?
[ $code -eq 3 ] && grep -q "integrator.dt = 5e-05 s is too large for the springs (structural 200 N/m, shear 1e+07 N/m" "$T/err" &&
  ok "shear_k = 1e7: exit 3, the step named over the limit with the shear constant" ||
  bad "shear_k = 1e7: exit $code: $(cat "$T/err")"
# A control character in a string reads back from the resolved scene.toml.
printf 'description = "a\\u0001b\\u007f\\tc"\n' > "$T/control.toml"
"$W" run "$T/control.toml" --duration 0.01 --out "$T/control" --quiet 2>"$T/err" &&
  "$W" check "$T/control/scene.toml" >/dev/null 2>>"$T/err" &&
  grep -qF 'description = "a\u0001b\u007F\tc"' "$T/control/scene.toml" &&
  ok "a control character in a string: escaped in scene.toml, which reads back" ||
  bad "control character: $(cat "$T/err")"
# A scene's name is a label: the default folder stays under out/.
mkdir -p "$T/cwd/deeper"
printf 'name = "../../escaped"\n' > "$T/cwd/deeper/name.toml"
(cd "$T/cwd/deeper" && "$W" run name.toml --duration 0.01 --quiet 2>"$T/err")
[ ! -e "$T/escaped" ] && [ ! -e "$T/cwd/escaped" ] && [ -s "$T/cwd/deeper/out/_._.._escaped/metrics.csv" ] &&
  ok "name = \"../../escaped\": written under out/ ($(ls "$T/cwd/deeper/out"))" ||
  bad "name with ..: $(ls "$T" "$T/cwd" "$T/cwd/deeper/out" 2>&1 | tr '\n' ' ') $(cat "$T/err")"

# A run writes every output; its scene.toml reproduces it bit for bit.
args=(--set cloth.resolution=[15,15] --duration 0.1 --quiet)
"$W" run pull-straight --out "$T/a" "${args[@]}" || bad "run failed"
for f in metrics.csv scene.toml summary.json obstacles.obj frames/frame_00000.obj frames/frame_00003.obj; do
  [ -s "$T/a/$f" ] && ok "wrote $f" || bad "missing $f"
done
head -1 "$T/a/metrics.csv" | grep -q "time_s,handle_height_m" && ok "metrics header" || bad "metrics header"
grep -q '"threads": 0,' "$T/a/summary.json" && grep -q '"threads_used": 1' "$T/a/summary.json" &&
  ok "summary.json: threads a number (0: chosen as it ran), the count used beside it" ||
  bad "summary.json threads: $(grep -A3 threads "$T/a/summary.json")"
[ "$(wc -l < "$T/a/metrics.csv")" -eq 5 ] && ok "one row per frame" || bad "rows: $(wc -l < "$T/a/metrics.csv")"
ls "$T/a" "$T/a/frames" | grep -q '\.tmp$' && bad "temporary files left" || ok "no temporary files"
"$W" run pull-straight --out "$T/b" "${args[@]}"
cmp -s "$T/a/metrics.csv" "$T/b/metrics.csv" && ok "identical metrics.csv twice" || bad "metrics differ between runs"
"$W" run "$T/a/scene.toml" --out "$T/c" --quiet
cmp -s "$T/a/metrics.csv" "$T/c/metrics.csv" && ok "scene.toml reproduces the run" || bad "scene.toml does not reproduce"
grep -q '"realtime_factor"' "$T/a/summary.json" && grep -q '"final"' "$T/a/summary.json" && ok "summary.json" || bad "summary.json"

# Caches: --export writes them beside the frames, and leaves no temporary file;
# an unknown format or up axis is bad input that names the key.
"$W" run pull-straight --out "$T/e" --set cloth.resolution=[9,9] --duration 0.1 --quiet --export usd,pc2,vtk --up y
for f in cloth.usda cloth.pc2 cloth_rest.obj cloth.pvd vtk/cloth_00003.vtp vtk/obstacles.vtp; do
  [ -s "$T/e/$f" ] && ok "--export wrote $f" || bad "--export: missing $f"
done
grep -q 'upAxis = "Y"' "$T/e/cloth.usda" && head -1 "$T/e/frames/frame_00000.obj" | grep -q ", y up" &&
  ok "--up y: the USD stage and the OBJ frames say so" || bad "--up y not recorded"
ls "$T/e" "$T/e/vtk" "$T/e/frames" | grep -q '\.tmp$' && bad "--export left temporary files" || ok "--export: no temporary files"
"$W" run pull-straight --out "$T/e" --set cloth.resolution=[9,9] --duration 0.05 --quiet
[ ! -e "$T/e/cloth.usda" ] && [ ! -e "$T/e/cloth.pc2" ] && [ ! -e "$T/e/vtk/cloth_00003.vtp" ] &&
  ok "a run without --export clears the caches of the run before" || bad "old caches left beside a new run"
# USD read back: a frame's time code is its number exactly (the state's time,
# whole steps, is 0.03335 s at frame 1), the last one between two frames its
# time x fps; velocities, and the pressure deficit with its unit in its doc.
"$W" run hang --grid 9 --duration 0.05 --export usd --out "$T/usd" --quiet &&
  /usr/bin/python3 - "$T/usd/cloth.usda" <<'PY' && ok "USD: time codes 0, 1, 1.5; velocities; the deficit in Pa" || bad "USD read back"
import re, sys
text = open(sys.argv[1]).read()
def samples(name):
    block = text[text.index(name + ".timeSamples = {"):]
    block = block[:block.index("        }")]
    return re.findall(r"^ +([0-9.e+-]+): ", block, re.M)
assert samples("point3f[] points") == ["0", "1", "1.5"], samples("point3f[] points")
assert samples("vector3f[] velocities") == ["0", "1", "1.5"]
assert samples("float[] primvars:pressure_deficit") == ["0", "1", "1.5"]
assert re.search(r'primvars:pressure_deficit \(\n +doc = "[^"]*Pa"', text)
assert "endTimeCode = 1.5" in text
PY
expect_bad export "run.export" pull-straight --export usd,alembic
expect_bad up_axis "--up" pull-straight --up x

# A duration between two frames: the run goes on to it, with a last frame there.
"$W" run pull-straight --out "$T/d" --set cloth.resolution=[9,9] --duration 0.05 --quiet
[ "$(tail -1 "$T/d/metrics.csv" | cut -d, -f1)" = "0.05" ] && [ -s "$T/d/frames/frame_00002.obj" ] &&
  [ ! -e "$T/d/frames/frame_00003.obj" ] && ok "a run covers its whole duration" ||
  bad "duration 0.05 at 30 fps ended at $(tail -1 "$T/d/metrics.csv" | cut -d, -f1)"

# --grid: the same cloth on a finer grid (handle patch in metres, explicit step
# shrunk with the spacing), or at a time step the command line sets; a grid out
# of range is bad input.
"$W" run pull-straight --grid 101 --duration 1e-4 --quiet --out "$T/g"
grep -q '^resolution = \[101, 101\]' "$T/g/scene.toml" && grep -q '^dt = 4.926646390821466e-05' "$T/g/scene.toml" &&
  grep -q '^patch = 2' "$T/g/scene.toml" && ok "--grid 101: resolution, dt, patch" ||
  bad "--grid 101: $(grep -E '^(resolution|dt|patch) ' "$T/g/scene.toml" | tr '\n' ' ')"
"$W" run pull-straight --grid 101 --set integrator.dt=4e-5 --duration 4e-5 --quiet --out "$T/g2"
grep -q '^dt = 4e-05' "$T/g2/scene.toml" && ok "--grid keeps a --set integrator.dt" ||
  bad "--grid with --set integrator.dt: $(grep '^dt ' "$T/g2/scene.toml")"
expect_bad grid "--grid: 1 gives a 1 x 1 cloth; each side must be 2 to 2001" pull-straight --grid 1

# A blow-up: exit 3, a message naming the time step, the outputs so far intact.
"$W" run hang --out "$T/boom" --set integrator.dt=2e-3 --duration 1 --quiet 2>"$T/err"; code=$?
[ $code -eq 3 ] && ok "blow-up exits 3" || bad "blow-up exit code $code"
grep -q "integrator.dt" "$T/err" && ok "blow-up message names integrator.dt" || bad "blow-up message: $(cat "$T/err")"
[ -s "$T/boom/metrics.csv" ] && [ -s "$T/boom/summary.json" ] && ok "outputs kept" || bad "blow-up outputs missing"
# 30 N on a single particle runs past integrator.max_speed: the message names the handle first.
# (3 N did until the strain limiter conserved momentum: it let the pulled particle run
# ahead of the cloth; now it holds it to the cloth, which 3 N drags along at F/M.)
"$W" run pull-straight --set 'handle.pull.force=[0,0,30]' --set handle.pull.patch=0 --duration 0.01 \
  --set 'cloth.resolution=[15,15]' --out "$T/boom2" --quiet 2>"$T/err"; code=$?
[ $code -eq 3 ] && grep -q "Likely cause: handle.pull.force = 30 N on its 1 particle" "$T/err" &&
  ok "blow-up by a handle's force names it" || bad "handle blow-up: exit $code, $(cat "$T/err")"
# Forward Euler within the symplectic step's limit: the message names the integrator first.
# Without strain limiting: the limiter holds forward Euler's growing ringing at τ_c (with
# it, this run holds for 0.2 s at least; without, it blows up at 6 ms).
"$W" run pull-straight --set springs.structural_k=2000 --set 'integrator.type="explicit-euler"' \
  --set integrator.dt=1e-5 --set strain_limit.enabled=false --duration 0.02 --threads 1 \
  --out "$T/boom3" --quiet 2>"$T/err"; code=$?
[ $code -eq 3 ] && grep -q 'Likely cause: integrator.type = "explicit-euler"' "$T/err" &&
  ok "forward Euler's blow-up names the integrator" || bad "explicit-euler blow-up: exit $code, $(cat "$T/err")"

# The example scenes stay valid and run.
for f in "$SRC"/examples/scenes/*.toml; do
  "$W" run "$f" --duration 0.02 --out "$T/example" --quiet 2>"$T/err" && ok "example $(basename "$f") runs" ||
    bad "example $(basename "$f"): $(cat "$T/err")"
done

# The other commands.
"$W" scenes | grep -q "^pull-straight" && ok "scenes" || bad "scenes"
# Every description starts in one column, after the longest name.
[ "$("$W" scenes | awk '{ match($0, /^[^ ]+ +/); print RLENGTH }' | sort -u | wc -l)" = 1 ] &&
  ok "scenes: the descriptions aligned" || bad "scenes misaligned: $("$W" scenes)"
"$W" check drop-ball --humidity 0.3 | grep -q "humidity = 0.3" && ok "check" || bad "check"
# check prints the xpbd substeps that will run: a set count, at any grid.
"$W" check hang --grid 101 --set 'integrator.type="xpbd"' --set integrator.substeps=12 |
  grep -q '^# xpbd: 12 substeps a step' && ok "check: xpbd's substeps" ||
  bad "check substeps: $("$W" check hang --grid 101 --set 'integrator.type="xpbd"' --set integrator.substeps=12 | head -2)"
# check prints the material and the springs it gives on this grid, or as a scene sets them.
"$W" check pull-straight --grid 101 --set springs.shear_k=30 >"$T/check.txt"
"$W" check pull-straight --grid 101 --set 'material.bending="provot"' --set material.bending_rigidity=7.2e-4 >"$T/check_provot.txt"
grep -q '^bending_rigidity = 2e-05$' "$T/check.txt" && grep -q '^# structural_k: unset, from \[material\]$' "$T/check.txt" &&
  grep -q '^#   bending: quadratic (a curvature energy, no springs), B 2e-05 N·m (material.bending_rigidity)$' "$T/check.txt" &&
  grep -q '^#   bending: k 80 N/m (from material.bending_rigidity); damping 0.04 N·s/m (from material.bending_damping)$' "$T/check_provot.txt" &&
  grep -q '^#   shear: k 30 N/m (set in \[springs\]); damping 0.01 N·s/m (from material.shear_damping)$' "$T/check.txt" &&
  ok "check: the material and the springs resolved on the grid" || bad "check springs: $(grep -A4 '^\[springs\]' "$T/check.txt")"
"$W" run --help | grep -q -- "--humidity" && ok "run --help" || bad "run --help"
# `wetcloth params` lines its columns up by characters (°, ², −∞ are several
# bytes), and --json gives every parameter.
"$W" params | python3 -c '
import sys
lines = [l.rstrip("\n") for l in sys.stdin]
center = next(l for l in lines if l.startswith("cloth.center "))
size = next(l for l in lines if l.startswith("cloth.size "))
sys.exit(0 if center.index("centre") == size.index("width") else 1)' &&
  ok "params: columns aligned by characters" || bad "params: columns not aligned"
"$W" params --json | python3 -c '
import json, sys
d = json.load(sys.stdin)
h = next(x for x in d if x["key"] == "cloth.humidity")
sys.exit(0 if h["min"] == 0 and h["max"] == 1 and len(d) > 80 and any("choices" in x for x in d) else 1)' &&
  ok "params --json" || bad "params --json"

# params --preset NAME: what the preset sets (key, value, unit, source); no
# name, the presets; a name that is none, bad input that lists them.
"$W" params --preset denim >"$T/preset.txt"; code=$?
[ $code -eq 0 ] && [ "$(grep -c . "$T/preset.txt")" -eq 9 ] &&
  grep -q '^# material.preset = "denim": ' "$T/preset.txt" &&
  grep -q '^cloth.areal_density  *0.4 kg/m²  *12 oz' "$T/preset.txt" &&
  grep -q '^material.bending_rigidity  *9.807e-05 N·m  *KES B 1 gf·cm²/cm' "$T/preset.txt" &&
  grep -q '^air.d_delta  *0.0002 m/(s·Pa)  *20 l/m²/s at 100 Pa' "$T/preset.txt" &&
  ok "params --preset denim" || bad "params --preset denim: exit $code, $(cat "$T/preset.txt")"
"$W" params --preset >"$T/presets.txt"; code=$?
[ $code -eq 0 ] && grep -q '^cotton-poplin  *cotton poplin' "$T/presets.txt" &&
  grep -q '^terry-towel ' "$T/presets.txt" && ok "params --preset: the presets" ||
  bad "params --preset: exit $code, $(cat "$T/presets.txt")"
"$W" params --preset wool >/dev/null 2>"$T/err"; code=$?
[ $code -eq 2 ] && grep -q "'wool' is not a preset" "$T/err" && grep -q '^silk ' "$T/err" &&
  ok "params --preset wool: exits 2, lists the presets" || bad "params --preset wool: exit $code, $(cat "$T/err")"
printf 'name = "p"\n[material]\npreset = "dennim"\n' > "$T/preset.toml"
expect_bad preset "preset.toml:3: material.preset: 'dennim' is not one of" "$T/preset.toml"
expect_bad preset_nearest "(did you mean denim?)" "$T/preset.toml"
expect_bad preset_set "--set 'material.preset=wool': material.preset:" pull-straight --set material.preset=wool
# A preset's run: its scene.toml holds the preset and its values, and reproduces it.
pargs=(--set material.preset=silk --set friction.mu=0.6 --set cloth.resolution=[11,11] --duration 0.05 --quiet)
"$W" run pull-straight --out "$T/ps" "${pargs[@]}" && "$W" run "$T/ps/scene.toml" --out "$T/ps2" --quiet &&
  cmp -s "$T/ps/metrics.csv" "$T/ps2/metrics.csv" && grep -q '^preset = "silk"$' "$T/ps/scene.toml" &&
  grep -q '^areal_density = 0.061$' "$T/ps/scene.toml" && grep -q '^mu = 0.6$' "$T/ps/scene.toml" &&
  ok "a preset's scene.toml reproduces its run" || bad "preset scene.toml: $(grep -E '^(preset|areal_density|mu) ' "$T/ps/scene.toml")"

# The user guide's parameter table is the one `wetcloth params --markdown` prints.
"$W" params --markdown > "$T/params.md"
# Five cells a row: a "|" inside a cell ("table | ball") is escaped.
[ -z "$(awk -F'(^|[^\\\\])[|]' 'NF != 7' "$T/params.md")" ] && ok "params table: five cells a row" ||
  bad "params table rows with a stray |: $(awk -F'(^|[^\\\\])[|]' 'NF != 7' "$T/params.md" | head -2)"
if awk '/<!-- params:begin -->/{f=1;next}/<!-- params:end -->/{f=0}f' "$SRC/docs/guide.md" | cmp -s - "$T/params.md"; then
  ok "docs/guide.md parameter table is current"
else
  bad "docs/guide.md parameter table differs from 'wetcloth params --markdown' (run: make docs-params)"
fi

# bench: one small grid, JSON out; bad input and a blow-up write nothing. No timing checks.
"$W" bench --grids 9 --duration 0.002 --repetitions 2 --out "$T/bench.json" >/dev/null; code=$?
[ $code -eq 0 ] && ok "bench exits 0" || bad "bench exit code $code"
python3 -c '
import json, sys
d = json.load(open(sys.argv[1]))
g = d["grids"]
assert len(g) == 1 and g[0]["particles"] == 81 and len(g[0]["wall_s"]) == 2 and d["repetitions"] == 2, d
' "$T/bench.json" && ok "bench.json: one grid, 81 particles, 2 repetitions" || bad "bench.json"
"$W" bench --grids 9 --duration 0.01 --repetitions 1 --integrator implicit-euler \
  --set integrator.dt=0.004166666666666667 --out "$T/bench_implicit.json" >"$T/bench_implicit.txt"
python3 -c '
import json, sys
g = json.load(open(sys.argv[1]))["grids"][0]
e = json.load(open(sys.argv[2]))["grids"][0]
assert g["solves_per_step"] >= g["substeps_per_step"] >= 1 and g["cg_iterations_per_solve"] > 0, g
assert e["solves_per_step"] == 0 and e["cg_iterations_per_solve"] == 0, e
' "$T/bench_implicit.json" "$T/bench.json" && grep -q "conjugate-gradient iterations a solve" "$T/bench_implicit.txt" &&
  ok "bench: implicit Euler's solves and iterations" || bad "bench: implicit Euler's solves and iterations"
expect_bad_bench() {
  local name="$1" want="$2"; shift 2
  "$W" bench "$@" --out "$T/bench_$name.json" >/dev/null 2>"$T/err"; local code=$?
  [ $code -eq "$want" ] && [ ! -e "$T/bench_$name.json" ] && ok "bench $name: exit $want, nothing written" ||
    bad "bench $name: exit code $code (want $want), $(cat "$T/err")"
}
expect_bad_bench grid1   2 --grids 1
expect_bad_bench scene   2 --scene no-such-scene --grids 9
expect_bad_bench blow-up 3 --scene hang --set integrator.dt=2e-3 --duration 1 --repetitions 1

# sweep: a case per humidity, named with as many decimals as tells them apart
# (an ensemble 1e-7 apart); a humidity given twice is bad input.
"$W" sweep hang --humidity 0.3,0.6999999,0.7,0.7000001 --duration 1e-3 --no-plots --quiet \
  --out "$T/sw"; code=$?
[ $code -eq 0 ] && [ "$(cut -d, -f1 "$T/sw/sweep.csv" | tail -n +2 | sort | tr '\n' ' ')" = \
  "omega_0.3000000 omega_0.6999999 omega_0.7000000 omega_0.7000001 " ] &&
  [ -s "$T/sw/omega_0.6999999/metrics.csv" ] && ok "sweep: close humidities get their own cases" ||
  bad "sweep: exit $code, cases $(cut -d, -f1 "$T/sw/sweep.csv" 2>&1 | tr '\n' ' ')"
"$W" sweep hang --humidity 0.5,0.5 --duration 1e-3 --no-plots --quiet --out "$T/sw2" 2>"$T/err"; code=$?
[ $code -eq 2 ] && [ ! -e "$T/sw2" ] && grep -q -- "--humidity: 0.5 is given twice" "$T/err" &&
  ok "sweep: a humidity given twice exits 2" || bad "sweep twice: exit $code, $(cat "$T/err")"

# converge: three steps of a small cloth, a row each; the table gives an order.
"$W" converge pull-straight --set 'cloth.resolution=[9,9]' --duration 0.02 --dt 4e-5,2e-5,1e-5 \
  --out "$T/conv" >"$T/conv.txt" 2>&1; code=$?
[ $code -eq 0 ] && ok "converge exits 0" || bad "converge exit code $code: $(cat "$T/conv.txt")"
[ "$(cut -d, -f1,2 "$T/conv/converge.csv" | tr '\n' ' ')" = "dt_s,status 4e-05,ok 2e-05,ok 1e-05,ok " ] &&
  ok "converge.csv: a row per step, largest first" || bad "converge.csv: $(cat "$T/conv/converge.csv")"
grep -q "^order p" "$T/conv.txt" && grep -q "^limit dt->0" "$T/conv.txt" && ok "converge: order and limit" ||
  bad "converge table: $(cat "$T/conv.txt")"
# converge on a corner dragged along the table (it slides, and stays flat): what
# is the same at every step says so, not nan; the slide is measured; times print short.
"$W" converge drag-corner --humidity 1 --set 'cloth.resolution=[9,9]' --duration 0.03 \
  --dt 4e-5,2e-5,1e-5 --out "$T/conv3" >"$T/conv3.txt" 2>&1; code=$?
grep -q "^order p *\(same at every dt  *\)\{4\}" "$T/conv3.txt" &&
  grep -q "^limit dt->0  *0  *0.09  *0  *0  " "$T/conv3.txt" &&
  ok "converge: a measurement the same at every step says so" ||
  bad "converge same: exit $code, $(cat "$T/conv3.txt")"
slide=$(awk -F, 'NR == 1 { for (i = 1; i <= NF; i++) c[$i] = i; next }
  NR == 2 { x0 = $c["centroid_x_m"]; y0 = $c["centroid_y_m"] }
  { x = $c["centroid_x_m"]; y = $c["centroid_y_m"] }
  END { printf "%.9f", sqrt((x - x0)^2 + (y - y0)^2) }' "$T/conv3/dt_1e-05/metrics.csv")
awk -F, -v want="$slide" 'NR == 1 { for (i = 1; i <= NF; i++) c[$i] = i; next }
  $1 == "1e-05" { got = $c["slide_m"] }
  END { exit !(want > 1e-4 && got != "" && (got - want)^2 < 1e-18) }' "$T/conv3/converge.csv" &&
  grep -q "^dt s .* slide_m" "$T/conv3.txt" && ok "converge: the slide, $slide m" ||
  bad "converge slide: want $slide m, $(cat "$T/conv3/converge.csv")"
grep -q "^final values at t = 0.03 s;" "$T/conv3.txt" && ok "converge: the time prints short" ||
  bad "converge time: $(grep "^final" "$T/conv3.txt")"
"$W" converge pull-straight --dt 5e-5,5e-5 --out "$T/conv2" >/dev/null 2>"$T/err"; code=$?
[ $code -eq 2 ] && [ ! -e "$T/conv2" ] && grep -q -- "--dt" "$T/err" && ok "converge: a step given twice exits 2" ||
  bad "converge twice: exit $code, $(cat "$T/err")"
"$W" converge pull-straight --dt 5e-5,-1 --out "$T/conv4" >/dev/null 2>"$T/err"; code=$?
[ $code -eq 2 ] && [ ! -e "$T/conv4" ] && grep -qF -- "--dt: value -1 is out of range [1e-09, 1]" "$T/err" &&
  ok "converge: a negative step exits 2, named" || bad "converge negative: exit $code, $(cat "$T/err")"

# Input read whole or refused (exit 2, the file, line or option, and the key named).
check_bad() {  # check_bad NAME TEXT ARGS...: `wetcloth check ARGS` exits 2 naming TEXT
  local name="$1" text="$2"; shift 2
  "$W" check "$@" >/dev/null 2>"$T/err"; local code=$?
  [ $code -eq 2 ] && grep -qF -- "$text" "$T/err" && ok "$name: exit 2, $(head -1 "$T/err")" ||
    bad "$name: exit $code (want 2 and '$text'): $(cat "$T/err")"
}
check_bad "--set with a second key" "cloth.humidity: the value goes on past one TOML value" \
  hang --set $'cloth.humidity=0.3\nname="x"'
check_bad "--set with a second key of the section" "past one TOML value" hang --set $'cloth.humidity=0.3\ncloth.tilt=5'
"$W" check hang --set 'handle.pull.force={}' >/dev/null 2>&1; [ $? -ne 1 ] && ok "--set an inline table: one value" ||
  bad "--set inline table"
check_bad "--grid ''" "--grid: '' is not a whole number" hang --grid ''
check_bad "--grid overflowing" "--grid: '999999999999999999999' is not a whole number" hang --grid 999999999999999999999
check_bad "--grid 1.5" "--grid: '1.5' is not a whole number" hang --grid 1.5
printf '[run]\nduration = 1e-9\n' >"$T/short.toml"
"$W" check "$T/short.toml" >/dev/null 2>"$T/err"; code=$?
[ $code -eq 2 ] && ! grep -q -- "--set" "$T/err" && grep -qF "short.toml: integrator.dt" "$T/err" &&
  ok "a short duration: no --set nobody gave is named ($(cat "$T/err"))" || bad "short duration: exit $code, $(cat "$T/err")"
check_bad "--duration 1e-300" "run.duration = 0 writes the start alone" hang --duration 1e-300
"$W" run hang --duration 0 --out "$T/zero" --quiet && [ "$(wc -l <"$T/zero/metrics.csv")" = 2 ] &&
  [ "$(ls "$T/zero/frames")" = frame_00000.obj ] && ok "--duration 0: the start alone, one row and frame" ||
  bad "--duration 0: $(ls "$T/zero" 2>&1)"
# OBJ numbers read whole: a comma, a fractional or overflowing index is refused, by line.
expect_check_bad comma "cloth.obj:1: \`1,5\` is not a number" 'v 1,5 0 0\nv 1 0 0\nv 0 1 0\nf 1 2 3\n'
expect_check_bad fraction "cloth.obj:4: \`1.5\` is not a face corner" 'v 0 0 0\nv 1 0 0\nv 0 1 0\nf 1.5 2 3\n'
expect_check_bad wrap "cloth.obj:4: \`4294967297\` is not a face corner" 'v 0 0 0\nv 1 0 0\nv 0 1 0\nf 4294967297 2 3\n'
expect_check_bad isolated "scene.toml: cloth.mesh: $T/mesh_isolated/cloth.obj: vertex 4 is in no face" \
  'v 0 0 0\nv 1 0 0\nv 0 1 0\nv 5 5 5\nf 1 2 3\n'
expect_check_bad scenenamed "mesh_scenenamed/scene.toml: cloth.mesh: " 'v 0 0 0\nv 1 0 0\nv 2 0 0\nf 1 2 3\n'
# A FIFO as the scene, a link that loops as the mesh: exit 2 at once, named.
mkfifo "$T/fifo.toml"
timeout 20 "$W" check "$T/fifo.toml" >/dev/null 2>"$T/err"; code=$?
[ $code -eq 2 ] && grep -qF "$T/fifo.toml: not a regular file" "$T/err" && ok "a FIFO scene: exit 2, named" ||
  bad "FIFO scene: exit $code, $(cat "$T/err")"
mkdir -p "$T/loop"; ln -s loop.obj "$T/loop/loop.obj"; printf '[cloth]\nmesh = "loop.obj"\n' >"$T/loop/scene.toml"
check_bad "a mesh link that loops" "$T/loop/scene.toml: cloth.mesh: \"loop.obj\" cannot be followed" "$T/loop/scene.toml"
# The memory guard is an estimate from the measured cost a particle (1.7 kB),
# and says so: 1401 x 1401 passes it (the disk's guard, after it, refuses a
# 1000 s run of meshes), and is refused under a 2.5 GB address space.
"$W" run hang --grid 1401 --duration 1000 --out "$T/m1401" --quiet 2>"$T/err"; code=$?
[ $code -eq 2 ] && grep -q "the outputs (.*need about" "$T/err" && ! grep -q "of memory" "$T/err" &&
  ok "1401 x 1401: memory enough by the estimate" || bad "1401 x 1401: exit $code, $(cat "$T/err")"
(ulimit -v 2500000; "$W" run hang --grid 1401 --duration 1 --out "$T/m1401" --quiet 2>"$T/err"); code=$?
[ $code -eq 2 ] && grep -qF "needs about 3.4 GB of memory (an estimate: 1.7 kB a particle, as measured)" "$T/err" &&
  [ ! -e "$T/m1401" ] && ok "under ulimit -v: refused, the estimate said" || bad "ulimit -v: exit $code, $(cat "$T/err")"

echo "$passes passed, $fails failed"
[ $fails -eq 0 ]
