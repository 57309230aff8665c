#!/usr/bin/env bash
# Output folders: a run removes only what an earlier wetcloth run wrote there
# (DIR/.wetcloth.manifest), writes and clears through no symbolic link, refuses
# the root, system folders and a folder of someone else's files (unless
# --force), leaves no lock file; `run --resume` checks every output its
# checkpoint says was written. Refusals exit 2 naming the folder or file, and
# change nothing.
set -u
W=$(realpath "$1")
T=$(mktemp -d)
trap 'rm -rf "$T"' EXIT
# ok, bad, wait_for
. "$(dirname "$0")/lib.sh"
RUN=(run hang --grid 9 --set integrator.dt=2e-4 --threads 1 --quiet)

# refused NAME TEXT ARGS...: exit 2 and TEXT in the message.
refused() {
  local name="$1" text="$2"; shift 2
  "$W" "$@" >/dev/null 2>"$T/err"; local code=$?
  [ $code -eq 2 ] && grep -qF -- "$text" "$T/err" && ok "$name: exit 2, $(head -1 "$T/err")" ||
    bad "$name: exit $code (want 2 and '$text'): $(cat "$T/err")"
}

# A user's files beside a run's, in the folder and in frames/: a second run
# keeps them, and removes the frames of the first that it does not write.
d="$T/run"
"$W" "${RUN[@]}" --duration 0.1 --export usd,pc2,vtk --out "$d" || bad "first run"
echo mine >"$d/notes.txt"; echo mine >"$d/frames/mine.obj"; echo mine >"$d/vtk/mine.vtp"
[ -s "$d/frames/frame_00003.obj" ] && [ -s "$d/.wetcloth.manifest" ] && ok "a run lists its files" ||
  bad "first run: $(ls -a "$d" "$d/frames")"
"$W" "${RUN[@]}" --duration 0.05 --out "$d" || bad "second run"
[ "$(cat "$d/notes.txt" "$d/frames/mine.obj" "$d/vtk/mine.vtp")" = "$(printf 'mine\nmine\nmine')" ] &&
  ok "a second run keeps the user's files (notes.txt, frames/mine.obj, vtk/mine.vtp)" ||
  bad "a second run removed a user's file: $(ls "$d" "$d/frames" "$d/vtk")"
[ ! -e "$d/frames/frame_00003.obj" ] && [ ! -e "$d/cloth.usda" ] && [ ! -e "$d/cloth.pc2" ] &&
  [ ! -e "$d/vtk/cloth_00000.vtp" ] && [ -s "$d/frames/frame_00002.obj" ] &&
  ok "a second run removes the first one's outputs it does not write" ||
  bad "outputs of the first run left: $(ls "$d" "$d/frames" "$d/vtk")"
[ ! -e "$d/.wetcloth.lock" ] && ok "no lock file left after a run" || bad ".wetcloth.lock left"
# A run of a folder's own scene.toml into it (the resume refusal's advice): its meshes read first.
m="$T/mesh"
"$W" run drape-disc --duration 0.01 --out "$m" --quiet && "$W" run "$m/scene.toml" --out "$m" --quiet 2>"$T/err" &&
  [ -s "$m/meshes/cloth_disc.obj" ] && ok "a folder's scene.toml runs into it again" ||
  bad "scene.toml into its own folder: $(cat "$T/err")"

# A folder of someone else's files: refused unless --force; with it, the files stay.
mkdir -p "$T/theirs/frames"; echo keep >"$T/theirs/thesis.tex"; echo keep >"$T/theirs/frames/a.obj"
refused "a folder of other files" "holds files no wetcloth run wrote" "${RUN[@]}" --duration 0.01 --out "$T/theirs"
[ "$(ls "$T/theirs")" = "$(printf 'frames\nthesis.tex')" ] && ok "... and nothing written there" ||
  bad "refused, yet wrote: $(ls -a "$T/theirs")"
"$W" "${RUN[@]}" --duration 0.01 --out "$T/theirs" --force 2>"$T/err" && [ -s "$T/theirs/metrics.csv" ] &&
  [ "$(cat "$T/theirs/thesis.tex" "$T/theirs/frames/a.obj")" = "$(printf 'keep\nkeep')" ] &&
  ok "--force writes beside them and keeps them" || bad "--force: $(cat "$T/err") $(ls "$T/theirs")"
(cd "$T/theirs/frames" && "$W" "${RUN[@]}" --duration 0.01 --out . >/dev/null 2>"$T/err"); code=$?
[ $code -eq 2 ] && grep -qF "holds files no wetcloth run wrote" "$T/err" && ok "--out . in a folder of other files: exit 2" ||
  bad "--out .: exit $code $(cat "$T/err")"
mkdir -p "$T/empty"; touch "$T/empty/.wetcloth.lock"
"$W" "${RUN[@]}" --duration 0.01 --out "$T/empty" && ok "a folder with an old lock file alone is empty" ||
  bad "a folder with only .wetcloth.lock refused"

# A folder of a wetcloth that wrote no manifest: its outputs go by their names, nothing else.
o="$T/older"
"$W" "${RUN[@]}" --duration 0.1 --out "$o" && rm "$o/.wetcloth.manifest" && echo mine >"$o/frames/mine.obj"
"$W" "${RUN[@]}" --duration 0.05 --out "$o" && [ ! -e "$o/frames/frame_00003.obj" ] && [ -s "$o/frames/mine.obj" ] &&
  ok "an older run's folder: its frames go, the user's stay" || bad "older run's folder: $(ls "$o/frames")"

# The root and system folders, however they are spelt: refused, --force or not.
refused "--out /" "the filesystem's root" "${RUN[@]}" --duration 0.01 --out /
depth=$(echo "$T" | tr -cd / | wc -c); up=$(printf '../%.0s' $(seq "$depth"))
refused "--out $T/$up" "the filesystem's root" "${RUN[@]}" --duration 0.01 --out "$T/$up" --force
refused "--out /proc" "/proc is a system folder" "${RUN[@]}" --duration 0.01 --out /proc
refused "--out /etc/x" "/etc/x is a system folder" "${RUN[@]}" --duration 0.01 --out /etc/x --force
[ ! -e /etc/x ] && ok "... /etc/x not made" || bad "/etc/x made"
refused "sweep --out /usr" "/usr is a system folder" sweep hang --humidity 0.5 --duration 1e-3 --out /usr

# Symbolic links: a frames/ (or vtk/) that is one, or an output file that is
# one, is refused; what they name is untouched.
mkdir -p "$T/elsewhere"; echo precious >"$T/elsewhere/frame_00000.obj"; echo precious >"$T/elsewhere/target"
for sub in frames vtk; do
  l="$T/link-$sub"
  "$W" "${RUN[@]}" --duration 0.01 --export vtk --out "$l" || bad "run into $l"
  rm -rf "$l/$sub"; ln -s "$T/elsewhere" "$l/$sub"
  refused "$sub a symbolic link" "$l/$sub: a symbolic link" "${RUN[@]}" --duration 0.01 --export vtk --out "$l"
done
l="$T/link-file"
"$W" "${RUN[@]}" --duration 0.01 --out "$l" || bad "run into $l"
rm "$l/metrics.csv"; ln -s "$T/elsewhere/target" "$l/metrics.csv"
refused "metrics.csv a symbolic link" "$l/metrics.csv: a symbolic link" "${RUN[@]}" --duration 0.01 --out "$l"
[ "$(cat "$T/elsewhere/frame_00000.obj" "$T/elsewhere/target")" = "$(printf 'precious\nprecious')" ] &&
  [ "$(ls "$T/elsewhere" | wc -l)" = 2 ] && ok "... what the links name is untouched" ||
  bad "a link was followed: $(ls -l "$T/elsewhere")"

# --resume: an output the checkpoint says was written, missing: exit 2 naming it.
s="$T/stopped"
"$W" "${RUN[@]}" --duration 30 --export vtk --out "$s" >/dev/null 2>&1 & pid=$!
wait_for "$s/frames/frame_00003.obj" $pid
kill -INT $pid; wait $pid
for f in frames/frame_00001.obj vtk/cloth_00002.vtp obstacles.obj; do
  mv "$s/$f" "$T/aside"
  before=$(md5sum "$s/metrics.csv")
  refused "--resume, $f missing" "$s/$f: missing, where $s/checkpoint.state continues a run that wrote it" \
    run --resume "$s"
  [ "$(md5sum "$s/metrics.csv")" = "$before" ] || bad "--resume refused, yet metrics.csv changed"
  mv "$T/aside" "$s/$f"
done
"$W" run --resume "$s" --quiet >/dev/null 2>"$T/err" & pid=$!
sleep 0.3; kill -TERM $pid; wait $pid; code=$?
[ $code -eq 143 ] && ok "the folder whole again resumes" || bad "resume after the refusals: exit $code $(cat "$T/err")"

# Sweep, converge and render: a folder of someone else's files is refused
# (exit 2, nothing written) unless --force; their own earlier folder is not.
for cmd in "sweep hang --humidity 0.5 --grid 9 --duration 0.01 --jobs 1 --no-plots --quiet" \
  "converge hang --grid 9 --duration 0.01 --dt 2e-4 --dt 1e-4 --jobs 1 --quiet"; do
  name=${cmd%% *}; f="$T/their-$name"
  mkdir -p "$f" && echo mine >"$f/thesis.tex"
  # shellcheck disable=SC2086
  refused "$name into a folder of other files" "holds files no wetcloth" $cmd --out "$f"
  [ "$(ls "$f")" = "thesis.tex" ] && ok "... $name wrote nothing there" || bad "$name wrote: $(ls "$f")"
  # shellcheck disable=SC2086
  "$W" $cmd --out "$f" --force >/dev/null 2>"$T/err" && [ "$(cat "$f/thesis.tex")" = mine ] &&
    ok "$name --force writes beside them" || bad "$name --force: $(cat "$T/err")"
  # shellcheck disable=SC2086
  "$W" $cmd --out "$T/own-$name" >/dev/null 2>&1 && "$W" $cmd --out "$T/own-$name" >/dev/null 2>"$T/err" &&
    ok "$name into its own earlier folder" || bad "$name again: $(cat "$T/err")"
done
mkdir -p "$T/their-render" && echo mine >"$T/their-render/thesis.tex"
refused "render into a folder of other files" "holds files no wetcloth render wrote" \
  render hang --grid 9 --duration 0.01 --out "$T/their-render"
[ "$(ls "$T/their-render")" = "thesis.tex" ] && ok "... render wrote nothing there" ||
  bad "render wrote: $(ls "$T/their-render")"

echo "$passes passed, $fails failed"
[ $fails -eq 0 ]
