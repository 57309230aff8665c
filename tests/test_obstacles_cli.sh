#!/usr/bin/env bash
# Mesh obstacles from the command line: a bad mesh, an open mesh with no
# thickness, a path out of the scene's folder, a missing file exit 2 from
# `wetcloth check`, naming the file and the key; the built-in scenes with
# obstacles check and run (briefly, coarse), and their obstacles reach
# obstacles.obj and the caches.
set -u
W="$1"
SRC=$(cd "$(dirname "$0")/.." && pwd)
T=$(mktemp -d)
trap 'rm -rf "$T"' EXIT
fails=0; passes=0
ok()  { passes=$((passes+1)); echo "ok: $1"; }
bad() { fails=$((fails+1)); echo "FAIL: $1"; }

mkdir -p "$T/scene/meshes"
printf 'v 0 0 0\nv 1 0 0\nv 1 1 0\nv 0 1 0\nf 1 2 3\nf 1 3 4\n' > "$T/scene/meshes/plate.obj"
printf 'v 0 0 0\nv 1 0 0\nv 2 0 0\nf 1 2 3\n' > "$T/scene/meshes/flat.obj"
printf 'v 0 0 0\nv 1 0 0\nv 0 1 0\nf 1 2 7\n' > "$T/scene/meshes/index.obj"
printf 'not an obj file at all\n' > "$T/scene/meshes/text.obj"
echo 'v 0 0 0' > "$T/outside.obj"

# expect_error NAME OBSTACLE_TABLE KEY FILE: check exits 2 and says KEY and FILE.
expect_error() {
  local name="$1" table="$2" key="$3" file="$4"
  printf '[obstacle.thing]\n%b' "$table" > "$T/scene/$name.toml"
  "$W" check "$T/scene/$name.toml" >/dev/null 2>"$T/err"; local code=$?
  if [ $code -eq 2 ] && grep -q "$key" "$T/err" && grep -q "$file" "$T/err"; then
    ok "$name: exit 2, names $key and $file"
  else
    bad "$name: exit $code: $(cat "$T/err")"
  fi
}
expect_error open 'mesh = "meshes/plate.obj"\n' obstacle.thing.thickness plate.obj
expect_error degenerate 'mesh = "meshes/flat.obj"\n' obstacle.thing.mesh flat.obj
expect_error bad-index 'mesh = "meshes/index.obj"\n' obstacle.thing.mesh index.obj
expect_error missing 'mesh = "meshes/none.obj"\n' obstacle.thing.mesh none.obj
expect_error outside 'mesh = "../outside.obj"\n' obstacle.thing.mesh outside.obj
expect_error absolute "mesh = \"$T/outside.obj\"\n" obstacle.thing.mesh outside.obj
expect_error no-mesh 'scale = [1, 1, 1]\n' obstacle.thing.mesh 'name the obstacle'
expect_error typo 'mesh = "meshes/plate.obj"\nthicknes = 0.01\n' obstacle.thing.thicknes thickness

# An open mesh with a thickness checks.
printf '[obstacle.thing]\nmesh = "meshes/plate.obj"\nthickness = 0.01\ntranslate = [-0.5, -0.5, -0.1]\n' \
  > "$T/scene/plate.toml"
"$W" check "$T/scene/plate.toml" >"$T/out" 2>"$T/err" && grep -q '^\[obstacle.thing\]' "$T/out" &&
  ok "an open mesh with a thickness checks" || bad "plate: $(cat "$T/err")"

# The built-in scenes with obstacles: check, and a short coarse run whose
# obstacles.obj and caches hold the mesh.
for scene in bowl-drape towel-rail mannequin-drape sleeve-pull arm-swing ball-roll; do
  "$W" check "$scene" >/dev/null 2>"$T/err" && ok "check $scene" || bad "check $scene: $(cat "$T/err")"
done
"$W" run mannequin-drape --grid 15 --duration 0.05 --export usd,vtk --out "$T/run" --quiet \
  2>"$T/err" >/dev/null; code=$?
if [ $code -eq 0 ] && grep -q '^o torso' "$T/run/obstacles.obj" &&
   grep -q 'torso' "$T/run/cloth.usda" && [ -s "$T/run/vtk/obstacles.vtp" ]; then
  ok "mannequin-drape runs; the torso is in obstacles.obj, cloth.usda and obstacles.vtp"
else
  bad "mannequin-drape run: exit $code: $(cat "$T/err")"
fi

# Moving obstacles in the outputs (docs/guide.md): the arm where it is each
# frame in frames/obstacles_NNNNN.obj, its own PC2 over its rest OBJ, a
# time-sampled transform in cloth.usda, a VTK frame and obstacles.pvd.
"$W" run arm-swing --duration 0.1 --set run.fps=30 --export usd,pc2,vtk --out "$T/swing" \
  --quiet 2>"$T/err" >/dev/null; code=$?
if [ $code -eq 0 ] && [ -s "$T/swing/frames/obstacles_00003.obj" ] &&
   ! cmp -s "$T/swing/frames/obstacles_00000.obj" "$T/swing/frames/obstacles_00003.obj" &&
   [ -s "$T/swing/obstacle_arm.pc2" ] && grep -q '^o arm' "$T/swing/obstacle_arm_rest.obj" &&
   grep -q 'matrix4d xformOp:transform.timeSamples' "$T/swing/cloth.usda" &&
   grep -q 'vtk/obstacles_00003.vtp' "$T/swing/obstacles.pvd" && [ -s "$T/swing/vtk/obstacles_00003.vtp" ]; then
  ok "arm-swing: the moving arm in frames/obstacles_*.obj, obstacle_arm.pc2, cloth.usda and obstacles.pvd"
else
  bad "arm-swing's moving arm in the outputs: exit $code: $(cat "$T/err")"
fi

# A run's folder runs anywhere: the meshes its scene names are copied to
# OUT/meshes/ (a built-in scene's from the program), scene.toml names them
# there, and running that scene.toml, from another place, gives the same bits.
"$W" run sleeve-pull --duration 0.05 --out "$T/sleeve" --quiet 2>"$T/err" >/dev/null &&
  cmp -s "$T/sleeve/meshes/arm.obj" "$SRC/scenes/meshes/arm.obj" &&
  cmp -s "$T/sleeve/meshes/cloth_sleeve.obj" "$SRC/scenes/meshes/cloth_sleeve.obj" &&
  grep -q '^mesh = "meshes/cloth_sleeve.obj"$' "$T/sleeve/scene.toml" &&
  mv "$T/sleeve" "$T/moved" && "$W" run "$T/moved/scene.toml" --out "$T/again" --quiet 2>"$T/err" &&
  cmp -s "$T/moved/metrics.csv" "$T/again/metrics.csv" &&
  ok "a built-in mesh scene's run: its meshes copied, its scene.toml runs moved, the same bits" ||
  bad "sleeve-pull's scene.toml: $(cat "$T/err")"
# A scene of its own, with two meshes of one name in two folders.
mkdir -p "$T/own/a" "$T/own/b"
cp "$T/scene/meshes/plate.obj" "$T/own/a/plate.obj"
sed 's/^v 1 1 0$/v 1 1.5 0/' "$T/scene/meshes/plate.obj" > "$T/own/b/plate.obj"
printf 'name = "own"\n[cloth]\nmesh = "a/plate.obj"\nmesh_scale = 0.2\ncenter = [0, 0, 0.05]\n' > "$T/own/own.toml"
printf '[obstacle.shelf]\nmesh = "b/plate.obj"\nthickness = 0.004\nscale = [0.3, 0.3, 1]\n' >> "$T/own/own.toml"
printf 'translate = [-0.1, -0.1, 0]\n[run]\nduration = 0.05\n' >> "$T/own/own.toml"
"$W" run "$T/own/own.toml" --out "$T/own-out" --quiet 2>"$T/err" >/dev/null &&
  cmp -s "$T/own-out/meshes/plate.obj" "$T/own/a/plate.obj" &&
  cmp -s "$T/own-out/meshes/2-plate.obj" "$T/own/b/plate.obj" &&
  grep -q '^mesh = "meshes/2-plate.obj"$' "$T/own-out/scene.toml" &&
  mv "$T/own-out" "$T/own-moved" && "$W" run "$T/own-moved/scene.toml" --out "$T/own-again" --quiet 2>"$T/err" &&
  cmp -s "$T/own-moved/metrics.csv" "$T/own-again/metrics.csv" &&
  ok "two meshes of one name: meshes/plate.obj and meshes/2-plate.obj; the same bits moved" ||
  bad "own scene's copied meshes: $(cat "$T/err"; ls "$T/own-out/meshes" 2>&1)"

# A deforming obstacle (obstacle.NAME.cache): a bad cache exits 2 from check
# and run, naming the file, the key and its line, and run writes nothing; a
# good one runs, its folder (the cache copied to OUT/caches/) runs moved with
# the same bits, and a run stopped by SIGINT resumes to the same bytes.
mkdir -p "$T/deform/meshes"
python3 - "$T/deform" <<'PY'
import math, struct, sys
d, n, half = sys.argv[1], 9, 0.2
def grid(t):
    return [(-half + 2 * half * i / (n - 1), -half + 2 * half * j / (n - 1),
             0.02 * min(t / 0.2, 1) * math.exp(-((2 * half * i / (n - 1) - half) ** 2 +
                                                 (2 * half * j / (n - 1) - half) ** 2) / 0.01))
            for j in range(n) for i in range(n)]
faces = [f for j in range(n - 1) for i in range(n - 1)
         for a in [j * n + i + 1] for f in [(a, a + 1, a + n + 1), (a, a + n + 1, a + n)]]
obj = lambda pts: "".join("v %.17g %.17g %.17g\n" % p for p in pts) + "".join("f %d %d %d\n" % f for f in faces)
open(d + "/meshes/bump.obj", "w").write(obj(grid(0)))
for k in range(8):
    open(d + "/meshes/bump_%02d.obj" % (k + 1), "w").write(obj(grid(k / 24)))
pc2 = b"POINTCACHE2\0" + struct.pack("<iiffi", 1, n * n - 1, 0.0, 1.0, 2) + b"\0" * (24 * (n * n - 1))
open(d + "/meshes/short.pc2", "wb").write(pc2)
PY
deform_scene() {  # deform_scene NAME CACHE_KEYS
  printf 'name = "%s"\n[cloth]\nresolution = [11, 11]\nsize = [0.2, 0.2]\ncenter = [0, 0, 0.0012]\n' "$1" > "$T/deform/$1.toml"
  printf '[table]\nenabled = false\n[contact]\nsurface = "obstacle"\n[run]\nduration = 0.3\nfps = 24\n' >> "$T/deform/$1.toml"
  printf 'checkpoint_every = 0.05\nexport = "pc2"\n[obstacle.plate]\nmesh = "meshes/bump.obj"\nthickness = 0.002\n' >> "$T/deform/$1.toml"
  printf 'contact = true\n%b' "$2" >> "$T/deform/$1.toml"
}
deform_error() {  # deform_error NAME CACHE_KEYS WHAT: check and run exit 2 naming it; nothing written
  deform_scene "$1" "$2"
  "$W" check "$T/deform/$1.toml" >/dev/null 2>"$T/err"; local code=$?
  "$W" run "$T/deform/$1.toml" --out "$T/deform-out-$1" --quiet >/dev/null 2>"$T/err2"; local run=$?
  if [ $code -eq 2 ] && [ $run -eq 2 ] && grep -q "$1.toml:19: obstacle.plate.cache" "$T/err" &&
     grep -q "$3" "$T/err" && [ ! -e "$T/deform-out-$1" ]; then
    ok "cache $1: check and run exit 2, naming $1.toml:19, obstacle.plate.cache and $3; nothing written"
  else
    bad "cache $1: check $code, run $run: $(cat "$T/err" "$T/err2")"
  fi
}
deform_error missing-cache 'cache = "meshes/none.pc2"\n' 'none.pc2: no such file'
deform_error count-cache 'cache = "meshes/short.pc2"\n' 'has 80 vertices a frame'
deform_error no-frames 'cache = "meshes/arm_##.obj"\n' 'no such files'
deform_scene fps-cache 'cache = "meshes/bump_##.obj"\ncache_fps = -24\n'
"$W" check "$T/deform/fps-cache.toml" >/dev/null 2>"$T/err"; code=$?
[ $code -eq 2 ] && grep -q "fps-cache.toml:20" "$T/err" && grep -q "obstacle.plate.cache_fps" "$T/err" &&
  ok "cache_fps out of range: exit 2, its line and key" || bad "cache_fps: exit $code, $(cat "$T/err")"
deform_scene bump 'cache = "meshes/bump_##.obj"\n'
"$W" run "$T/deform/bump.toml" --out "$T/bump" --quiet 2>"$T/err" >/dev/null &&
  cmp -s "$T/bump/caches/bump_08.obj" "$T/deform/meshes/bump_08.obj" &&
  grep -q '^cache = "caches/bump_##.obj"$' "$T/bump/scene.toml" &&
  ! cmp -s "$T/bump/obstacle_plate_rest.obj" "$T/bump/frames/obstacles_00007.obj" &&
  mv "$T/bump" "$T/bump-moved" && "$W" run "$T/bump-moved/scene.toml" --out "$T/bump-again" --quiet 2>"$T/err" &&
  cmp -s "$T/bump-moved/metrics.csv" "$T/bump-again/metrics.csv" &&
  cmp -s "$T/bump-moved/obstacle_plate.pc2" "$T/bump-again/obstacle_plate.pc2" &&
  ok "a deforming obstacle runs; its cache copied to OUT/caches/, the folder runs moved, the same bits" ||
  bad "deforming run: $(cat "$T/err")"
"$W" run "$T/deform/bump.toml" --out "$T/bump-stop" --quiet >/dev/null 2>&1 & pid=$!
for _ in $(seq 300); do [ -f "$T/bump-stop/checkpoint.state" ] && break; sleep 0.05; done
kill -INT $pid 2>/dev/null; wait $pid; code=$?
if [ -f "$T/bump-stop/checkpoint.state" ]; then
  "$W" run --resume "$T/bump-stop" --quiet >/dev/null 2>"$T/err" &&
    cmp -s "$T/bump-moved/metrics.csv" "$T/bump-stop/metrics.csv" &&
    cmp -s "$T/bump-moved/obstacle_plate.pc2" "$T/bump-stop/obstacle_plate.pc2" &&
    cmp -s "$T/bump-moved/cloth.pc2" "$T/bump-stop/cloth.pc2" &&
    ok "a deforming obstacle's run stopped ($code) and resumed: the same bytes" ||
    bad "deforming resume: $(cat "$T/err")"
else
  ok "a deforming obstacle's run ended before SIGINT (exit $code): nothing to resume"
fi

# towel-dry (the humidity field's drying) is towel-rail's towel and rail.
"$W" check towel-dry >/dev/null 2>"$T/err" && ok "check towel-dry" || bad "check towel-dry: $(cat "$T/err")"

# Obstacles' keys in sweeps, as handles': obstacle.NAME.KEY.
"$W" sweep towel-rail --vary "obstacle.rail.translate=[0,0,0.6],[0,0,0.55]" --grid 9 --list >"$T/l" 2>"$T/err" &&
  [ "$(cut -f2 "$T/l" | tr '\n' ' ')" = "translate=0x0x0.6 translate=0x0x0.55 " ] &&
  ok "sweep --vary obstacle.rail.translate" || bad "sweep obstacle key: $(cat "$T/l" "$T/err")"
"$W" sweep towel-rail --vary "obstacle.rail.translate=[0,0,0.6],[0,0,0.55]" --grid 9 --duration 0.02 \
  --no-plots --quiet --out "$T/sweep" >/dev/null 2>"$T/err" &&
  head -1 "$T/sweep/sweep.csv" | grep -q '^case,obstacle.rail.translate,' &&
  grep -q '^translate=0x0x0.55,"\[0, 0, 0.55\]",' "$T/sweep/sweep.csv" &&
  grep -q '^translate = \[0.0, 0.0, 0.55\]$' "$T/sweep/translate=0x0x0.55/scene.toml" &&
  ok "the obstacle sweep runs: sweep.csv's column, each case's scene" ||
  bad "obstacle sweep: $(cat "$T/err"; cat "$T/sweep/sweep.csv" 2>&1 | cut -c1-120)"
"$W" sweep towel-rail --vary "obstacle.pole.scale=[1,1,1],[2,2,2]" --list >/dev/null 2>"$T/err"; code=$?
[ $code -eq 2 ] && grep -q "obstacle.pole: the scene has no such obstacle" "$T/err" &&
  ok "sweep: an unknown obstacle exits 2, named" || bad "unknown obstacle: exit $code, $(cat "$T/err")"

echo "$passes passed, $fails failed"
[ $fails -eq 0 ]
