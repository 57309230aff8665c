#!/usr/bin/env bash
# Every command in the README and docs/*.md runs: the lines of their ```sh
# blocks and their ```python blocks, on a small cloth for a short time.
#   wetcloth / build/wetcloth COMMAND ...  run with --grid 9 and a short
#       --duration (bench: --grids 9, one short repetition; render: a small
#       image); `view` needs a display, so only `view --help` is run;
#   make TARGET                            checked to be a target of the Makefile;
#   anything else                          skipped, with the reason printed;
#   ```python blocks                       run by PYTHON (default /usr/bin/python3)
#       with PYTHONPATH=PYTHON_DIR, the module's Simulation on 9 x 9 and
#       advance_to at most 0.05 s, sweep alike; skipped without PYTHON_DIR.
# A command that appears twice (after the changes above) runs once.
# The commands run in a scratch folder in which build/wetcloth is W and
# examples/ and scenes/ are the checkout's, so relative paths (out/...) work
# as the docs say and nothing is written into the checkout.
# Usage: test_doc_commands.sh WETCLOTH SOURCE_DIR [PYTHON_DIR [PYTHON]]
set -u
W=$(realpath "$1"); SRC=$(realpath "$2"); PYDIR=${3:+$(realpath "$3")}
PY=${4:-/usr/bin/python3}; [ -x "$PY" ] || PY=python3
T=$(mktemp -d); trap 'rm -rf "$T"' EXIT
mkdir -p "$T/build"
ln -s "$W" "$T/build/wetcloth"
ln -s "$SRC/examples" "$T/examples"
ln -s "$SRC/scenes" "$T/scenes"
cd "$T" || exit 1
export MPLBACKEND=Agg PYTHONDONTWRITEBYTECODE=1
exec python3 - "$W" "$SRC" "$PYDIR" "$PY" <<'EOF'
import os, re, shlex, shutil, subprocess, sys, time

W, SRC, PYDIR, PY = sys.argv[1:5]
DOCS = ["README.md", "docs/guide.md"] + sorted(
    os.path.join("docs", f) for f in os.listdir(os.path.join(SRC, "docs"))
    if f.endswith(".md") and f != "guide.md")
GRID, DURATION = "9", "0.05"
failures, counts = [], {"ran": 0, "make": 0, "skipped": 0, "python": 0}
started = time.time()


def blocks(path):
    """(language, first line number, lines) of each fenced block of PATH."""
    lang, start, body = None, 0, []
    for n, line in enumerate(open(os.path.join(SRC, path), encoding="utf-8"), 1):
        m = re.match(r"^\s*```(\S*)\s*$", line)
        if m and lang is None:
            lang, start, body = m.group(1) or "text", n, []
        elif m and not m.group(1):
            yield lang, start, body
            lang = None
        elif lang is not None:
            body.append(line.rstrip("\n"))


def sh_commands(lines):
    """The commands of a sh block: continuation lines joined, comments
    dropped, `a && b` split; as word lists."""
    joined, cur = [], ""
    for line in lines:
        if line.rstrip().endswith("\\"):
            cur += line.rstrip()[:-1] + " "
            continue
        joined.append(cur + line)
        cur = ""
    for line in joined:
        words = shlex.split(line, comments=True)
        cmd = []
        for w in words + ["&&"]:
            if w == "&&":
                if cmd:
                    yield cmd
                cmd = []
            else:
                cmd.append(w)


def makefile_targets():
    targets = set()
    for line in open(os.path.join(SRC, "Makefile"), encoding="utf-8"):
        m = re.match(r"^([A-Za-z0-9_.-]+(?:\s+[A-Za-z0-9_.-]+)*)\s*:(?!=)", line)
        if m:
            targets.update(m.group(1).split())
    return targets


def runs(args, timeout=120):
    p = subprocess.run([W] + args, capture_output=True, text=True, timeout=timeout)
    return p.returncode, p.stdout + p.stderr


VIEWER = runs(["render", "--help"])[0] == 0
FFMPEG = shutil.which("ffmpeg") is not None
BULLET = "without Bullet" not in runs(["bench", "--peer", "bullet", "--grids", "9", "--duration", "0.001",
                                   "--repetitions", "1", "--out", "bullet-probe.json"])[1]


def without(words, options, flags=()):
    """WORDS without the options that take a value in OPTIONS and the FLAGS."""
    out, skip = [], False
    for w in words:
        if skip:
            skip = False
            continue
        name = w.split("=", 1)[0]
        if name in options:
            skip = "=" not in w
            continue
        if w in flags:
            continue
        out.append(w)
    return out


_mesh = {}


def mesh_cloth(scene):
    """Whether SCENE's cloth is a mesh (cloth.mesh set), as `check` prints it."""
    if scene not in _mesh:
        out = subprocess.run([W, "check", scene], capture_output=True, text=True).stdout
        section, _mesh[scene] = "", False
        for l in out.splitlines():
            section = l if l.startswith("[") else section
            _mesh[scene] |= section == "[cloth]" and bool(re.match(r'mesh = "[^"]', l))
    return _mesh[scene]


def small(words):
    """A doc's wetcloth command made quick: (arguments, allowed exit codes, note),
    or (None, None, reason) to skip it."""
    sub, rest = words[0], words[1:]
    if sub in ("scenes", "params") or "--help" in rest:
        return words, {0}, ""
    if sub == "view":
        if not VIEWER:
            return None, None, "this build has no viewer"
        return ["view", "--help"], {0}, " (view needs a display: --help only)"
    if sub == "bench":
        args = without(rest, {"--grids", "--duration", "--repetitions"})
        args = [sub] + args + ["--grids", GRID, "--duration", "0.01", "--repetitions", "1"]
        return args, ({0} if BULLET or "--peer" not in rest else {1}), ""
    if sub == "sweep" and "--gather" in rest:
        return words, {0}, ""
    if sub == "run" and "--resume" in rest:  # the scene is the checkpoint's: as it is
        return words, {0}, ""
    if sub in ("run", "check", "converge", "sweep", "render"):
        drop_flags = ()
        note = ""
        if sub == "sweep" and "--render" in rest and not VIEWER:
            drop_flags, note = ("--render",), " (no viewer: without --render)"
        if sub == "render":
            if not VIEWER:
                return None, None, "this build has no viewer"
            if "--video" in rest and not FFMPEG:
                drop_flags, note = ("--video",), " (no ffmpeg: without --video)"
        args = without(rest, {"--grid", "--duration", "--size"}, drop_flags)
        scene = next((w for w in args if not w.startswith("-")), None)
        # A mesh cloth has no grid to shrink (--grid is an error there).
        grid = [] if scene and mesh_cloth(scene) else ["--grid", GRID]
        args = [sub] + args + grid + ["--duration", DURATION]
        if sub == "render":
            args += ["--size", "160x90"]
        return args, {0}, note
    return words, {0}, ""


PRELUDE = f'''
import wetcloth as _w
_Simulation, _sweep = _w.Simulation, _w.sweep
class _Small(_Simulation):
    def __init__(self, scene, overrides=None, **keywords):
        keywords["grid"] = {GRID}
        super().__init__(scene, overrides, **keywords)
    def advance_to(self, t):
        return super().advance_to(min(t, {DURATION}))
import os as _os, tempfile as _tempfile
_run, _tmp = _w.run, _tempfile.mkdtemp()  # a block's folders go to a temporary one
def _small_sweep(scene, vary, client=None, overrides=None, grid=None, processes=None, out=None, plots=True):
    overrides = dict(overrides or {{}}, **{{"run.duration": {DURATION}}})
    out = out and _os.path.join(_tmp, out)
    return _sweep(scene, vary, client=client, overrides=overrides, grid={GRID}, processes=1, out=out,
                  plots=plots)
def _small_run(scene=None, **keywords):
    if scene is not None:
        keywords.update(grid={GRID}, duration=min(keywords.get("duration", {DURATION}), {DURATION}))
    for k in ("out", "resume"):
        if k in keywords:
            keywords[k] = _os.path.join(_tmp, keywords[k])
    return _run(scene, **keywords)
_w.Simulation, _w.sweep, _w.run = _Small, _small_sweep, _small_run
'''

targets = makefile_targets()
seen = {}
python_ok = bool(PYDIR) and subprocess.run(
    [PY, "-c", "import wetcloth"], env=dict(os.environ, PYTHONPATH=PYDIR),
    capture_output=True).returncode == 0

for doc in DOCS:
    for lang, line, body in blocks(doc):
        where = f"{doc}:{line}"
        if lang == "python":
            if not python_ok:
                print(f"skip  {where}: python block (no Python module in this build)")
                counts["skipped"] += 1
                continue
            p = subprocess.run([PY, "-c", PRELUDE + "\n".join(body)],
                               env=dict(os.environ, PYTHONPATH=PYDIR), capture_output=True,
                               text=True, timeout=120)
            counts["python"] += 1
            if p.returncode == 0:
                print(f"ok    {where}: python block ({len(body)} lines, 9 x 9, at most {DURATION} s)")
            else:
                failures.append(f"{where}: python block: {p.stderr.strip()[-600:]}")
                print(f"FAIL  {where}: python block\n{p.stderr.strip()[-600:]}")
            continue
        if lang != "sh":
            continue
        for words in sh_commands(body):
            text = shlex.join(words)
            prog = words[0]
            if prog == "make":
                missing = [t for t in words[1:] if not t.startswith("-") and "=" not in t and t not in targets]
                counts["make"] += 1
                if missing or len(words) < 2:
                    failures.append(f"{where}: {text}: not a Makefile target: {' '.join(missing)}")
                    print(f"FAIL  {where}: {text}: not a Makefile target")
                else:
                    print(f"ok    {where}: {text} (a Makefile target; not run)")
                continue
            if prog not in ("wetcloth", "build/wetcloth"):
                reason = {"/usr/bin/python3": "the pip install: ctest python_install does it",
                          "python3": "the pip install: ctest python_install does it",
                          ".venv/bin/pip": "the pip install: ctest python_install does it",
                          "cmake": "cmake --install: ctest install_and_find_package does it",
                          "tools/validate.sh": "make validate's script (minutes of runs)"}.get(
                              prog, "not a wetcloth or make command")
                print(f"skip  {where}: {text}: {reason}")
                counts["skipped"] += 1
                continue
            if len(words) < 2:
                failures.append(f"{where}: {text}: no command")
                continue
            args, codes, note = small(words[1:])
            if args is None:
                print(f"skip  {where}: {text}: {note}")
                counts["skipped"] += 1
                continue
            shown = "wetcloth " + shlex.join(args)
            if shown in seen:  # the same command, already run: the same outputs
                print(f"ok    {where}: {shown} (as at {seen[shown]})")
                continue
            seen[shown] = where
            t0 = time.time()
            try:
                code, out = runs(args)
            except subprocess.TimeoutExpired:
                code, out = "timeout", ""
            counts["ran"] += 1
            if code in codes:
                print(f"ok    {where}: {shown}{note} ({time.time() - t0:.1f} s)")
            else:
                failures.append(f"{where}: {shown}: exit {code}, want {sorted(codes)}\n{out.strip()[-600:]}")
                print(f"FAIL  {where}: {shown}: exit {code}\n{out.strip()[-600:]}")

print(f"{counts['ran']} wetcloth commands run, {counts['make']} make commands checked, "
      f"{counts['python']} python blocks run, {counts['skipped']} skipped; {time.time() - started:.0f} s")
if counts["ran"] < 10:
    failures.append(f"only {counts['ran']} commands found: is the extraction broken?")
# The docs cite docs/model.md (MODEL.md is a file users do not have), and
# docs/model.md says what the model does now: what it did until a commit or
# a stop is docs/history.md's.
for doc in DOCS:
    for n, line in enumerate(open(os.path.join(SRC, doc), encoding="utf-8"), 1):
        if "MODEL.md" in line:
            failures.append(f"{doc}:{n}: cites MODEL.md: cite docs/model.md's section")
for n, line in enumerate(open(os.path.join(SRC, "docs/model.md"), encoding="utf-8"), 1):
    if re.search(r"\b[Uu]ntil (stop \d+|[0-9a-f]{7}\b)", line):
        failures.append(f"docs/model.md:{n}: history ({line.strip()[:60]}): move it to docs/history.md")
if failures:
    print(f"{len(failures)} FAILED:")
    for f in failures:
        print("  " + f.splitlines()[0])
    sys.exit(1)
EOF
