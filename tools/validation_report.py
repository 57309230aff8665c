#!/usr/bin/env python3
"""Write the Markdown validation report of wetcloth against the paper's claims.

Usage: validation_report.py RUNS_DIR REPORT_MD [--command TEXT]

RUNS_DIR holds one `wetcloth sweep` folder per experiment (as tools/validate.sh
makes them): RUNS_DIR/<name>/sweep.csv, RUNS_DIR/<name>/<case>/{metrics.csv,
summary.json,scene.toml} and the figures of tools/plot_sweep.py; beside them
validate.sh may leave <name>.skipped (why it was not run), <name>.log (the
sweep's output) and commands.log (one line per sweep: name, exit code,
seconds, command).

REPORT_MD gets: the command that made it, date, machine; a table per
experiment; its figures (copied to <report dir>/figures/<name>_<fig>.png and
linked relative to the report; plot_sweep.py is run first if a sweep has
none); and a table of the paper's claims (docs/model.md section 11), each with the
paper's statement, our numbers and PASS/FAIL computed from the data, and of
implicit Euler's agreement with the explicit step (issue 4: the implicit-<scene>
sweeps against explicit-<scene> and the explicit sweeps' ω = 0.7, each an
ensemble of ω = 0.7 moved by k·1e-7); and a table of laws the model keeps
(docs/model.md sections 2 and 9: a free cloth under a force accelerates at
F/M, from the single run RUNS_DIR/free-cloth; a rig's force balances the load
of what it lifts, from the peel-rig sweep), each measured, expected and
PASS/FAIL. Missing
data reads "not run"; the script does not fail on it. Needs only the standard
library (matplotlib only if it has to draw missing figures).
"""
import argparse
import csv
import datetime
import json
import math
import os
import platform
import shutil
import subprocess
import sys

AGREEMENT = ["pull-straight", "pull-oblique", "pull-corner", "drape-ball"]  # implicit-<scene> sweeps
EXPERIMENTS = ["pull-straight", "pull-oblique", "pull-corner", "drag-corner", "drape-ball",
               "peel-rig", "air-models"] + [f"{i}-{s}" for s in AGREEMENT for i in ("explicit", "implicit")]
FIGURES = ["fig7", "fig8", "handle_height", "handle_force", "pressure", "contact_area"]
TREND = [0.3, 0.5, 0.7, 1.0]  # the humidities the trend claims are tested over
# The material does not change with the grid (docs/model.md section 1): these scenes
# at ω = 0.7 on grid-<scene>-<G> (51: their sweeps above), and the cantilever's
# bending length on grid-cantilever-<G>.
GRIDDED = ["pull-straight", "pull-oblique", "drape-ball"]
GRID_SIZES = [31, 51, 101, 201]
CANTILEVER_GRIDS = [26, 51, 101]
GRID_RUNS = [f"grid-{s}-{g}" for s in GRIDDED for g in GRID_SIZES if g != 51] + \
    [f"grid-cantilever-{g}" for g in CANTILEVER_GRIDS]
# The paper's claims again on a finer grid: claims101-<scene> (validate.sh).
PAPER = EXPERIMENTS[:6]
FINE = 101
FINE_RUNS = [f"claims{FINE}-{s}" for s in PAPER]
# The oblique pull's scatter at 101 x 101 (its lifted-area claim): scatter101-pull-oblique.
SCATTERED = ["pull-oblique"]
SCATTER_RUNS = [f"scatter{FINE}-{s}" for s in SCATTERED]
P_ATM = 101325.0
HERE = os.path.dirname(os.path.abspath(__file__))


# ---------------------------------------------------------------- reading

def number(text):
    try:
        return float(text)
    except (TypeError, ValueError):
        return None


def read_csv(path):
    """Rows as dicts, numbers parsed where they parse; [] when unreadable."""
    try:
        with open(path, newline="", encoding="utf-8") as f:
            return [{k: (number(v) if number(v) is not None else v) for k, v in row.items() if k}
                    for row in csv.DictReader(f)]
    except (OSError, UnicodeDecodeError, csv.Error):
        return []


def read_toml(path):
    """A flat TOML reader for scene.toml: {section: {key: raw value text}}."""
    out, section = {}, ""
    try:
        with open(path, encoding="utf-8") as f:
            for line in f:
                line = line.split("#", 1)[0].strip()
                if line.startswith("["):
                    section = line.strip("[] ")
                elif "=" in line:
                    key, value = line.split("=", 1)
                    out.setdefault(section, {})[key.strip()] = value.strip()
    except (OSError, UnicodeDecodeError):
        pass
    return out


def read_json(path):
    try:
        with open(path, encoding="utf-8") as f:
            return json.load(f)
    except (OSError, ValueError):
        return {}


def load_sweep(folder):
    """The cases of a sweep folder (None without sweep.csv): each the sweep.csv
    row plus what is derived from its metrics.csv, summary.json and scene.toml."""
    if not os.path.exists(os.path.join(folder, "sweep.csv")):
        return None
    cases = read_csv(os.path.join(folder, "sweep.csv"))
    for c in cases:
        case_dir = os.path.join(folder, str(c.get("case", "")))
        c["folder"] = case_dir
        rows = read_csv(os.path.join(case_dir, "metrics.csv"))
        col = lambda k: [r[k] for r in rows if isinstance(r.get(k), float)]
        c["summary"] = read_json(os.path.join(case_dir, "summary.json"))
        c["scene"] = read_toml(os.path.join(case_dir, "scene.toml"))
        c["ok"] = c.get("status") == "ok"
        c["peak_force_n"] = max(col("handle_force_n"), default=None)
        c["slid_m"] = None
        if rows and all(isinstance(rows[i].get(k), float) for i in (0, -1)
                        for k in ("centroid_x_m", "centroid_y_m")):
            c["slid_m"] = math.hypot(rows[-1]["centroid_x_m"] - rows[0]["centroid_x_m"],
                                     rows[-1]["centroid_y_m"] - rows[0]["centroid_y_m"])
        # A driven hand (a move handle): its mean force over its travel, the
        # work it did per metre; from the frames while it moved, and the
        # lifted area when it stops (the last frame of its travel). A frame is
        # written at the first step past its time, so the one at the hand's
        # stop may fall a step after it: the frames up to half a frame past.
        c["travel_force_n"] = c["stop_lifted_m2"] = None
        path = driven_path(c["scene"])
        times = [r["time_s"] for r in rows if isinstance(r.get("time_s"), float)]
        gaps = sorted(b - a for a, b in zip(times, times[1:]) if b > a)
        if path and path[1] > 0 and gaps:
            start, end = path[0], path[0] + path[1] + 0.5 * gaps[len(gaps) // 2]
            moving = [r for r in rows if isinstance(r.get("time_s"), float) and start < r["time_s"] <= end]
            forces = [r["handle_force_n"] for r in moving if isinstance(r.get("handle_force_n"), float)]
            if forces:
                c["travel_force_n"] = sum(forces) / len(forces)
            if moving and isinstance(moving[-1].get("lifted_area_m2"), float):
                c["stop_lifted_m2"] = moving[-1]["lifted_area_m2"]
        # The tent's mean slope at the end: pulled height over half its base diagonal.
        h, b = c.get("handle_height_m"), c.get("base_diagonal_m")
        if isinstance(h, float) and isinstance(b, float) and b > 0:
            c["tent_slope"] = h / (b / 2)
    return cases


def driven_path(scene):
    """(start, time on its path) of the measured handle (the first by name that
    is not a pin) when it is a move handle with a travel limit, else None."""
    for section in sorted(k for k in scene if k.startswith("handle.")):
        kind = scene[section].get("type", '"force"').strip('"')
        if kind == "pin":
            continue
        if kind != "move":
            return None
        try:
            velocity = [float(v) for v in scene[section].get("velocity", "[0, 0, 0]").strip("[]").split(",")]
            travel = float(scene[section].get("max_travel", "0"))
            start = float(scene[section].get("start", "0"))
        except ValueError:
            return None
        speed = math.sqrt(sum(v * v for v in velocity))
        return (start, travel / speed) if speed > 0 and travel > 0 else None
    return None


def main_model(cases):
    models = sorted({c.get("air_model") for c in cases})
    return "exchange" if "exchange" in models or not models else models[0]


def find(cases, w, model=None):
    """The case at humidity w (and air model, default the sweep's main one)."""
    model = model or main_model(cases)
    for c in cases:
        if isinstance(c.get("humidity"), float) and abs(c["humidity"] - w) < 1e-6 \
                and c.get("air_model") == model:
            return c
    return None


# ---------------------------------------------------------------- formatting

def fmt(v, scale=1.0, digits=2):
    if not isinstance(v, float) or math.isnan(v):
        return "—"
    return f"{v * scale:.{digits}f}"


def md_table(header, rows):
    lines = ["| " + " | ".join(header) + " |", "|" + "---|" * len(header)]
    lines += ["| " + " | ".join(str(x) for x in row) + " |" for row in rows]
    return "\n".join(lines)


# ---------------------------------------------------------------- the claims

def series(sweeps, name, hums, key, model=None):
    """([(ω, value)], problem): problem is '' when every case is there and ok."""
    cases = sweeps.get(name)
    if cases is None:
        return [], "not run"
    found = [(w, find(cases, w, model)) for w in hums]
    missing = [w for w, c in found if c is None or not isinstance(c.get(key), float)]
    if missing:
        return [], "not run (no data at ω = " + ", ".join(f"{w:g}" for w in missing) + ")"
    bad = [w for w, c in found if not c["ok"]]
    values = [(w, c[key]) for w, c in found]
    return values, ("blew up at ω = " + ", ".join(f"{w:g}" for w in bad)) if bad else ""


def listed(values, scale, unit, digits=2):
    return ", ".join(f"ω={w:g}: {fmt(v, scale, digits)}" for w, v in values) + f" {unit}"


def verdict(ok, problem):
    if problem.startswith("not run"):
        return "not run"
    if problem:
        return f"FAIL ({problem}; the numbers alone would {'pass' if ok else 'fail'})"
    return "PASS" if ok else "FAIL"


def trend(sweeps, name, key, scale, unit, test, digits=2):
    values, problem = series(sweeps, name, TREND, key)
    if problem.startswith("not run"):
        return problem, "not run"
    v = [x for _, x in values]
    return listed(values, scale, unit, digits), verdict(test(v), problem)


def informational(result):
    measured, outcome = result
    return measured, "not run" if outcome == "not run" else "info"


def falling(v):
    return all(b < a for a, b in zip(v, v[1:]))


def rising(v):
    return all(b > a for a, b in zip(v, v[1:]))


def falling_within(tol):
    return lambda v: all(b <= a + tol for a, b in zip(v, v[1:])) and v[-1] < v[0]


def compare(sweeps, name, key, hums, scale, unit, test, model=None, digits=2):
    """Measured text and verdict for test(values at hums)."""
    values, problem = series(sweeps, name, hums, key, model)
    if problem.startswith("not run"):
        return problem, "not run"
    return listed(values, scale, unit, digits), verdict(test([x for _, x in values]), problem)


def whole_cloth_lifts(sweeps):
    cases = sweeps.get("pull-straight")
    c0, c3 = (find(cases, 0.0), find(cases, 0.3)) if cases else (None, None)
    if c0 is None or not isinstance(c0.get("contact_area_m2"), float):
        return "not run (no data at ω = 0)", "not run"
    size = c0["scene"].get("cloth", {}).get("size", "[0.3, 0.3]").strip("[]").split(",")
    area = math.prod(number(s) or 0.3 for s in size) if len(size) == 2 else 0.09
    share = c0["contact_area_m2"] / area
    text = (f"ω=0: contact {fmt(c0['contact_area_m2'], 1e4, 1)} cm² = {share:.1%} of "
            f"{area * 1e4:.0f} cm²; handle height {fmt(c0.get('handle_height_m'), 100)} cm "
            f"(ω=0.3: {fmt(c3.get('handle_height_m') if c3 else None, 100)} cm)")
    return text, verdict(share < 0.10, "" if c0["ok"] else "blew up at ω = 0")


def drape(sweeps):
    cases = sweeps.get("drape-ball")
    parts = []
    for w in (0.0, 1.0):
        c = find(cases, w) if cases else None
        if c is None:
            return f"not run (no data at ω = {w:g})", "not run"
        parts.append(c)
    text = "; ".join(f"ω={w:g}: outer {fmt(c.get('outer_diagonal_m'), 100, 1)} cm, base "
                     f"{fmt(c.get('base_diagonal_m'), 100, 1)} cm, wrinkle {fmt(c.get('wrinkle_rad'), 1, 3)} rad"
                     for w, c in zip((0, 1), parts))
    w0, w1 = (c.get("wrinkle_rad") for c in parts)
    if not (isinstance(w0, float) and isinstance(w1, float)):
        return text, "not run"
    bad = [str(w) for w, c in zip((0, 1), parts) if not c["ok"]]
    return text, verdict(w1 > w0, ("blew up at ω = " + ", ".join(bad)) if bad else "")


def air_models(sweeps, key, scale, unit, digits=0):
    """At each humidity of the air-models sweep: PASS if sealed's value > exchange's."""
    cases = sweeps.get("air-models")
    hums = sorted({c["humidity"] for c in cases or [] if isinstance(c.get("humidity"), float)})
    texts, ok, problems = [], True, []
    for w in hums:
        s, e = find(cases, w, "sealed"), find(cases, w, "exchange")
        if not (s and e and isinstance(s.get(key), float) and isinstance(e.get(key), float)):
            continue
        texts.append(f"ω={w:g}: sealed {fmt(s[key], scale, digits)}, exchange {fmt(e[key], scale, digits)} {unit}")
        ok &= s[key] > e[key]
        problems += [f"{c['air_model']} ω={w:g}" for c in (s, e) if not c["ok"]]
    if not texts:
        return "not run", "not run"
    return "; ".join(texts), verdict(ok, ("blew up: " + ", ".join(problems)) if problems else "")


def ensemble(cases, w):
    """The cases within 1e-6 of ω = w: a run at w and those at w moved by k·1e-7."""
    return [c for c in cases or [] if isinstance(c.get("humidity"), float) and abs(c["humidity"] - w) < 1e-6]


def spread(values):
    """Mean, standard deviation (n - 1) and range of values."""
    n = len(values)
    mean = sum(values) / n
    sd = math.sqrt(sum((v - mean) ** 2 for v in values) / (n - 1)) if n > 1 else 0.0
    return mean, sd, min(values), max(values)


def agreement(sweeps, scene, keys, w=0.7, tolerance=0.05):
    """Issue 4: implicit Euler's final values within 5 % of the explicit step's,
    for each (key, label, scale, unit, digits). Both sides are ensembles: the runs at
    ω = w and at w moved by k·1e-7 (implicit-<scene>; explicit-<scene> and the
    explicit sweep's own run at w), since the contact patterns of these scenes
    are chaotic. The means are compared: PASS within the tolerance; beyond it
    FAIL when the difference is more than twice its standard error (Welch), and
    INCONCLUSIVE when the runs spread too widely to tell."""
    imp = ensemble(sweeps.get("implicit-" + scene), w)
    exp = ensemble(sweeps.get(scene), w) + ensemble(sweeps.get("explicit-" + scene), w)
    if not imp or not exp:
        return f"not run (no {'implicit' if not imp else 'explicit'} case at ω = {w:g})", "not run"
    texts, ok, clear = [], True, True
    for key, label, scale, unit, digits in keys:
        a = [c.get(key) for c in imp]
        b = [c.get(key) for c in exp]
        if not all(isinstance(v, float) for v in a + b):
            return f"not run (no {label} at ω = {w:g})", "not run"
        (ma, sa, lo_a, hi_a), (mb, sb, lo_b, hi_b) = spread(a), spread(b)
        if mb == 0:
            return f"not run (no {label} at ω = {w:g})", "not run"
        diff = ma / mb - 1
        side = lambda m, lo, hi, n: fmt(m, scale, digits) + (
            f" ({fmt(lo, scale, digits)}–{fmt(hi, scale, digits)}, {n} runs)" if n > 1 else "")
        text = f"{label} {side(ma, lo_a, hi_a, len(a))} against {side(mb, lo_b, hi_b, len(b))} {unit}: {diff:+.1%}"
        if abs(diff) > tolerance:
            ok = False
            if len(a) > 1 and len(b) > 1:
                se = math.sqrt(sa * sa / len(a) + sb * sb / len(b))
                t = (ma - mb) / se if se > 0 else math.copysign(math.inf, ma - mb)
                text += f", {abs(t):.1f} standard errors" if abs(t) < 1000 else ", over 1000 standard errors"
                clear &= abs(t) > 2
        texts.append(text)
    bad = [n for n, cs in (("implicit", imp), ("explicit", exp)) if not all(c["ok"] for c in cs)]
    result = verdict(ok, ("blew up: " + ", ".join(bad)) if bad else "")
    if result == "FAIL" and not clear:
        result = "INCONCLUSIVE (the runs spread too widely to tell)"
    return "; ".join(texts), result


HANDLE = ("handle_height_m", "handle", 100, "cm", 2)
CONTACT = ("contact_area_m2", "contact", 1e4, "cm²", 0)
HAND_FORCE = ("travel_force_n", "the hand's force over its travel", 1, "N", 3)
# What each agreement compares: a hand's height is set by its path, so its force.
AGREEMENT_KEYS = {"pull-oblique": [HAND_FORCE, CONTACT], "drape-ball": [CONTACT]}
AGREEMENT_TEXT = {"pull-oblique": "the hand's mean force over its travel and the final contact area",
                  "drape-ball": "final contact area"}

CLAIMS = [  # (experiment, the paper reports, the test, evaluate(sweeps) -> (measured, verdict))
    ("pull-straight", "Fig. 7a: the wetter the cloth, the lower it is pulled up",
     "final handle height strictly decreasing over ω = 0.3, 0.5, 0.7, 1",
     lambda s: trend(s, "pull-straight", "handle_height_m", 100, "cm", falling)),
    ("pull-straight", "Fig. 7b: the wetter the cloth, the smaller the base diagonal",
     "final base diagonal strictly decreasing over ω = 0.3, 0.5, 0.7, 1",
     lambda s: trend(s, "pull-straight", "base_diagonal_m", 100, "cm", falling)),
    ("pull-straight", "Fig. 7: below ω ≈ 0.3 the whole cloth lifts",
     "at ω = 0 the final contact area is < 10 % of the cloth area (handle height shown for reference)",
     whole_cloth_lifts),
    ("pull-straight", "Fig. 4: the wetter the cloth, the flatter its surfaces",
     "informational: final wrinkle_rad at each ω (flatter = smaller)",
     lambda s: informational(compare(s, "pull-straight", "wrinkle_rad", [0.0] + TREND, 1, "rad",
                                     lambda v: True, digits=3))),
    ("pull-oblique", "Fig. 2: a wetter cloth is harder to pull up: more force for the same travel",
     "the hand's mean force over its 10 cm travel at 45° strictly increasing over ω = 0.3, 0.5, 0.7, 1",
     lambda s: trend(s, "pull-oblique", "travel_force_n", 1, "N", rising, digits=3)),
    ("pull-oblique", "Fig. 2: a wetter cloth is harder to pull up: less of it lifted",
     "lifted area when the hand stops, at the end of its travel, strictly decreasing over "
     "ω = 0.3, 0.5, 0.7, 1",
     lambda s: trend(s, "pull-oblique", "stop_lifted_m2", 1e4, "cm²", falling, digits=1)),
    ("pull-corner", "Fig. 5: a wetter cloth lifts fewer parts",
     "final lifted area strictly decreasing over ω = 0.3, 0.5, 0.7, 1",
     lambda s: trend(s, "pull-corner", "lifted_area_m2", 1e4, "cm²", falling, digits=1)),
    ("pull-corner", "Fig. 5: a wetter cloth wrinkles more",
     "final wrinkle_rad at ω = 1 greater than at ω = 0.3",
     lambda s: compare(s, "pull-corner", "wrinkle_rad", [0.3, 1.0], 1, "rad", lambda v: v[1] > v[0],
                       digits=3)),
    ("drag-corner", "sec. 1: a wetter cloth takes more force to drag",
     "the hand's mean force over its 10 cm drag strictly increasing over ω = 0.3, 0.5, 0.7, 1",
     lambda s: trend(s, "drag-corner", "travel_force_n", 1, "N", rising, digits=3)),
    ("drag-corner", "sec. 1: a wetter cloth slides less as a whole",
     "slid distance (final centroid from the first) strictly decreasing over ω = 0.3, 0.5, 0.7, 1",
     lambda s: trend(s, "drag-corner", "slid_m", 100, "cm", falling)),
    ("drape-ball", "Fig. 6: a wetter cloth contracts more and wrinkles more",
     "final wrinkle_rad at ω = 1 greater than at ω = 0 (diagonals shown for the contraction)",
     drape),
    ("peel-rig", "a wetter cloth is harder to peel",
     "peak handle force over time strictly increasing over ω = 0.3, 0.5, 0.7, 1",
     lambda s: trend(s, "peel-rig", "peak_force_n", 1, "N", rising, digits=3)),
    ("air-models", "Fig. 8: the sealed model traps a larger pressure deficit than air exchange",
     "peak pressure deficit at any step: sealed > exchange at every ω of the sweep",
     lambda s: air_models(s, "peak_deficit_pa", 1, "Pa")),
    ("air-models", "Fig. 8: air exchange gives a gentler slope than Yamada's sealed air",
     "rig lifts both to the same height; tent slope (height over half the base diagonal): "
     "exchange < sealed at every ω",
     lambda s: air_models(s, "tent_slope", 1, "", digits=2)),
] + [("implicit-" + scene, "issue 4: implicit Euler at 1/240 s agrees with the explicit step",
      AGREEMENT_TEXT.get(scene, "final handle height and contact area") +
      ", mean of ω = 0.7 and ω moved by ±1e-7 and ±2e-7, within 5 % of the explicit step's "
      "(INCONCLUSIVE when beyond 5 % but within twice the standard error)",
      lambda s, scene=scene: agreement(s, scene, AGREEMENT_KEYS.get(scene, [HANDLE, CONTACT])))
     for scene in AGREEMENT]


# Why a claim fails, from the runs: a note under the claims table for each
# failing claim that has one (the paper's text as the key).

def still_lifting(sweeps, grid, w=0.0, span=0.5):
    """The straight pull at ω = w over the last `span` s: is it still lifting?"""
    c = find(sweeps.get("pull-straight") or [], w)
    rows = read_csv(os.path.join(c["folder"], "metrics.csv")) if c else []
    rows = [r for r in rows if all(isinstance(r.get(k), float)
                                   for k in ("time_s", "contact_area_m2", "handle_height_m"))]
    if len(rows) < 2:
        return None
    end = rows[-1]
    start = next(r for r in rows if r["time_s"] >= end["time_s"] - span - 1e-9)
    dt = end["time_s"] - start["time_s"]
    if dt <= 0:
        return None
    return (f"at the sweep's end ({end['time_s']:.2f} s) the cloth at ω = {w:g} is still lifting: over its "
            f"last {dt:.2f} s the contact fell by {(start['contact_area_m2'] - end['contact_area_m2']) / dt * 1e4:.0f} "
            f"cm²/s and the hand rose by {(end['handle_height_m'] - start['handle_height_m']) / dt * 100:.1f} cm/s. "
            "The hand lifts the cloth as fast as air seeps in under the tent (eq. 4), so a longer run lifts "
            "it whole; docs/validation.md gives runs to 8 s at ω = 0, 0.3 and 0.5, which show no threshold "
            "at ω ≈ 0.3, only a slower lift the wetter the cloth")


def lifted_only(sweeps, grid, scene="pull-corner", ws=(0.3, 1.0)):
    cases = sweeps.get(scene) or []
    found = [find(cases, w) for w in ws]
    if not all(c and isinstance(c.get("lifted_area_m2"), float) for c in found):
        return None
    return ("the wrinkle measure is the mean dihedral angle over lifted triangles alone (docs/model.md "
            "section 10): " + ", ".join(f"at ω = {w:g} the lifted part is {c['lifted_area_m2'] * 1e4:.0f} cm²"
                                        for w, c in zip(ws, found)) +
            "; it does not see the cloth that stays on the table, where the wetter cloth is held")


def within_scatter(scene, key, scale, unit, falls=True):
    """A trend broken between neighbouring humidities, against the scene's own
    scatter on the same grid (its runs at ω = 0.7 moved by k·1e-7:
    explicit-<scene> at 51 x 51, scatter101-<scene> at 101 x 101), or at 51 x 51
    where the finer grid's was not run."""
    def note(sweeps, grid):
        cases = sweeps.get(scene) or []
        values = [(w, (find(cases, w) or {}).get(key)) for w in TREND]
        if not all(isinstance(v, float) for _, v in values):
            return None
        broken = [(a, b) for a, b in zip(values, values[1:]) if (b[1] >= a[1] if falls else b[1] <= a[1])]
        scatter = sweeps.get(f"scatter{grid}-{scene}") if grid != 51 else None
        measured = 51 if scatter is None else grid
        runs = [c.get(key) for c in ensemble(scatter or sweeps.get("explicit-" + scene), 0.7)]
        runs = [x for x in runs if isinstance(x, float)]
        if not broken or len(runs) < 2:
            return None
        spread_ = (max(runs) - min(runs)) / (sum(runs) / len(runs))
        within = all(abs(b[1] / a[1] - 1) <= spread_ for a, b in broken)
        return ("; ".join(f"from ω = {a[0]:g} to {b[0]:g} it goes from {a[1] * scale:.0f} to {b[1] * scale:.0f} {unit} "
                          f"({b[1] / a[1] - 1:+.1%})" for a, b in broken) +
                f"; the scene's own scatter, its runs at ω = 0.7 moved by ±1e−7 and ±2e−7 on "
                f"{measured} × {measured}, spreads it by {spread_:.1%}" +
                (": the contact pattern is chaotic, and a step within it is not the humidity's" if within else
                 ": the step is beyond it" +
                 (f" (the scatter on {grid} × {grid} was not measured)" if measured != grid else
                  ", so it is the model's")))
    return note


# Why a failing claim fails, from the runs: note(sweeps, grid), grid the one the
# claim was read on (51, or FINE with its sweeps in the scenes' place).
CLAIM_NOTES = {
    "Fig. 7: below ω ≈ 0.3 the whole cloth lifts": still_lifting,
    "Fig. 5: a wetter cloth wrinkles more": lifted_only,
    "Fig. 2: a wetter cloth is harder to pull up: less of it lifted":
        within_scatter("pull-oblique", "stop_lifted_m2", 1e4, "cm²"),
}


# ---------------------------------------------------------------- laws the model keeps

def vector(text):
    """A TOML array of numbers ('[1.0, 0.0, 0.0]') as a list of floats, or None."""
    values = [number(v) for v in (text or "").strip("[] ").split(",")]
    return values if values and all(v is not None for v in values) else None


def areal_mass(scene):
    """ρ_A (1 + r_w ω), kg/m², from a resolved scene.toml (docs/model.md section 1)."""
    cloth = scene.get("cloth", {})
    rho, ratio, w = (number(cloth.get(k)) for k in ("areal_density", "water_ratio", "humidity"))
    return rho * (1 + ratio * w) if None not in (rho, ratio, w) else None


def measured_handle(scene):
    """The handle the metrics follow: the first by name that is not a pin ({} if none)."""
    return next((v for k, v in sorted(scene.items())
                 if k.startswith("handle.") and v.get("type", "").strip('"') != "pin"), {})


def free_cloth(runs):
    """A free cloth pulled by a constant force: its centroid's acceleration against F/M
    (strain limiting conserves momentum, docs/model.md section 2)."""
    folder = os.path.join(runs, "free-cloth")
    rows = read_csv(os.path.join(folder, "metrics.csv"))
    scene = read_toml(os.path.join(folder, "scene.toml"))
    status = read_json(os.path.join(folder, "summary.json")).get("status")
    handle = measured_handle(scene)
    force, size = vector(handle.get("force")), vector(scene.get("cloth", {}).get("size"))
    dt, mass_per_area = number(scene.get("integrator", {}).get("dt")), areal_mass(scene)
    ok_rows = len(rows) >= 2 and all(isinstance(rows[i].get(k), float) for i in (0, -1)
                                     for k in ("time_s", "centroid_x_m", "centroid_y_m"))
    if not (ok_rows and force and size and dt and mass_per_area):
        return "not run", "—", "not run"
    t = rows[-1]["time_s"] - rows[0]["time_s"]
    moved = math.hypot(rows[-1]["centroid_x_m"] - rows[0]["centroid_x_m"],
                       rows[-1]["centroid_y_m"] - rows[0]["centroid_y_m"])
    # Symplectic Euler from rest under a constant force: x_n - x_0 = a dt² n (n + 1) / 2.
    measured = 2 * moved / (t * (t + dt))
    expected = math.hypot(*force) / (mass_per_area * size[0] * size[1])
    strain = max((r["max_strain"] for r in rows if isinstance(r.get("max_strain"), float)), default=0.0)
    text = (f"{measured:.3f} m/s² over {t:g} s ({measured / expected - 1:+.2%}); "
            f"largest structural strain {strain:.3f} (the limiter holds it at τ_c)")
    return text, f"F/M = {expected:.3f} m/s², within 1 %", \
        verdict(abs(measured / expected - 1) < 0.01, "" if status == "ok" else "blew up")


def rig_balance(case):
    """One peel-rig run: per frame once more than the patch is lifted, the recorded
    force over the load of what the rig lifts, (ρ g + ΔP) A_lifted + front pull.
    Returns (median ratio, 90th-percentile |ratio - 1|, frames) or None."""
    scene = case["scene"]
    rows = read_csv(os.path.join(case["folder"], "metrics.csv"))
    handle = measured_handle(scene)
    cloth = scene.get("cloth", {})
    res, size, gravity = vector(cloth.get("resolution")), vector(cloth.get("size")), \
        vector(scene.get("forces", {}).get("gravity"))
    patch, p_atm, mass_per_area = number(handle.get("patch")), \
        number(scene.get("air", {}).get("p_atm")), areal_mass(scene)
    if not (rows and res and size and gravity and mass_per_area) or None in (patch, p_atm):
        return None
    keys = ("handle_force_n", "lifted_area_m2", "inner_pressure_pa", "front_pull_n")
    # The rig's patch (2 patch + 1 particles a side, each l × l): lifted alone at first.
    spacing = (size[0] / (res[0] - 1)) * (size[1] / (res[1] - 1))
    patch_area = (2 * patch + 1) ** 2 * spacing
    ratios = []
    for r in rows:
        if not all(isinstance(r.get(k), float) for k in keys) or r["lifted_area_m2"] <= patch_area * 1.0001:
            continue
        load = (mass_per_area * abs(gravity[2]) + p_atm - r["inner_pressure_pa"]) * r["lifted_area_m2"] \
            + r["front_pull_n"]
        if load > 0:
            ratios.append(r["handle_force_n"] / load)
    if not ratios:
        return None
    ratios.sort()
    off = sorted(abs(x - 1) for x in ratios)
    return ratios[len(ratios) // 2], off[len(off) * 9 // 10], len(ratios)


def peel_balance(sweeps, tolerance=0.05):
    """The peel rig's recorded force against the load of what it lifts, at every ω
    of the peel-rig sweep (docs/model.md sections 2 and 9)."""
    cases = sweeps.get("peel-rig")
    if not cases:
        return "not run", "—", "not run"
    texts, ok, problems = [], True, []
    resolution = cases[0]["scene"].get("cloth", {}).get("resolution", "?")
    for c in sorted(cases, key=lambda c: c.get("humidity") or 0):
        b = rig_balance(c)
        if b is None:
            return (f"not run (no front_pull_n at ω = {c.get('humidity')}: rerun peel-rig)", "—",
                    "not run")
        median, p90, frames = b
        texts.append(f"ω={c.get('humidity'):g}: {median:.3f} (90th percentile off by {p90:.1%}, {frames} frames)")
        ok &= abs(median - 1) < tolerance
        if not c["ok"]:
            problems.append(f"ω={c.get('humidity'):g}")
    return (f"grid {resolution}; the median frame's recorded force / load: " + "; ".join(texts),
            f"1, within {tolerance:.0%}",
            verdict(ok, ("blew up at " + ", ".join(problems)) if problems else ""))


LAWS = [  # (law, how it is checked, evaluate(runs, sweeps) -> (measured, expected, verdict))
    ("Strain limiting conserves momentum: a free cloth pulled by a force accelerates at F/M "
     "(docs/model.md section 2)",
     "`free-cloth`: `pull-straight` in free space (no table, gravity, air, adhesion or damping; "
     "springs of 20 N/m, so that the limiter acts every step), 1 N along x; the centroid's "
     "acceleration from its travel, 2 Δx / (t (t + Δt))",
     lambda runs, sweeps: free_cloth(runs)),
    ("A rig's recorded force balances the load of what it lifts, the strain limiter's impulses "
     "included (docs/model.md sections 2, 9)",
     "`peel-rig` sweep: each frame once more than the patch is lifted, the recorded force "
     "over the lifted cloth's weight + deficit × lifted area (the suction) + the front pull (the "
     "springs' pull on the cloth still in contact, which its adhesion holds); the median frame",
     lambda runs, sweeps: peel_balance(sweeps)),
]


# ---------------------------------------------------------------- the grids

def elastica(lam, tip, n=2000):
    """Peirce's cantilever, the heavy elastica θ'' = −(λ − s) cos θ in units of
    its bending length, over an overhang λ, integrated (RK4) from the free end
    (θ = tip, θ' = 0) back to the clamp: (θ at the clamp, the tip's chord angle
    below the level)."""
    h = -lam / n
    s, th, k, x, z = lam, tip, 0.0, 0.0, 0.0
    f = lambda s_, th_: -(lam - s_) * math.cos(th_)
    for _ in range(n):
        k1, t1 = f(s, th), k
        k2, t2 = f(s + h / 2, th + h / 2 * t1), k + h / 2 * k1
        k3, t3 = f(s + h / 2, th + h / 2 * t2), k + h / 2 * k2
        k4, t4 = f(s + h, th + h * t3), k + h * k3
        angles = (th, th + h / 2 * t1, th + h / 2 * t2, th + h * t3)
        x -= h / 6 * (math.cos(angles[0]) + 2 * math.cos(angles[1]) + 2 * math.cos(angles[2]) + math.cos(angles[3]))
        z -= h / 6 * (math.sin(angles[0]) + 2 * math.sin(angles[1]) + 2 * math.sin(angles[2]) + math.sin(angles[3]))
        th += h / 6 * (t1 + 2 * t2 + 2 * t3 + t4)
        k += h / 6 * (k1 + 2 * k2 + 2 * k3 + k4)
        s += h
    return th, math.atan2(z, x)


def chord_angle(lam):
    """The chord angle of an overhang of λ bending lengths (single-valued to λ ≈ 5, 82°)."""
    lo, hi = 0.0, math.pi / 2
    for _ in range(60):
        mid = (lo + hi) / 2
        lo, hi = (lo, mid) if elastica(lam, mid, 300)[0] > 0 else (mid, hi)
    return elastica(lam, (lo + hi) / 2)[1]


def bending_length(overhang, phi):
    """The bending length c of an overhang whose tip droops to the chord angle phi."""
    lo, hi = 0.01, 5.0
    for _ in range(50):
        mid = math.sqrt(lo * hi)
        lo, hi = (mid, hi) if chord_angle(mid) < phi else (lo, mid)
    return overhang / math.sqrt(lo * hi)


def peirce(overhang, phi):
    """Peirce's formula for the bending length, c = L (cos(θ/2) / (8 tan θ))^(1/3)."""
    return overhang * (math.cos(phi / 2) / (8 * math.tan(phi))) ** (1 / 3)


def cantilever(folder):
    """The cantilever run in a sweep folder: {grid, spacing, bending_k, chord, c, peirce}
    from its last frame (the chord from the clamp's edge, at + span of its pin,
    to the free end, each the mean across the strip), or None."""
    cases = load_sweep(folder)
    if not cases:
        return None
    c = cases[0]
    case_dir = os.path.join(folder, str(c.get("case", "")))
    frames = sorted(f for f in os.listdir(os.path.join(case_dir, "frames"))
                    if f.endswith(".obj")) if os.path.isdir(os.path.join(case_dir, "frames")) else []
    scene = c["scene"]
    try:
        nu, nv = (int(v) for v in scene["cloth"]["resolution"].strip("[]").split(","))
        width = float(scene["cloth"]["size"].strip("[]").split(",")[0])
        clamp = next(v for k, v in sorted(scene.items()) if k.startswith("handle.") and v.get("type") == '"pin"')
        edge_u = sum(float(a) for a in (clamp["at"].strip("[]").split(",")[0], clamp["span"].strip("[]").split(",")[0]))
        rigidity = float(scene["material"]["bending_rigidity"])
        provot = scene["material"].get("bending", '"quadratic"') == '"provot"'
        density = float(scene["cloth"].get("areal_density", 0.12))
        with open(os.path.join(case_dir, "frames", frames[-1]), encoding="utf-8") as f:
            v = [[float(x) for x in line.split()[1:4]] for line in f if line.startswith("v ")]
    except (KeyError, ValueError, StopIteration, IndexError, OSError):
        return None
    spacing = width / (nu - 1)
    bending_k = (number(scene.get("springs", {}).get("bending_k")) or rigidity / spacing ** 2) if provot else None
    column = lambda i: [sum(v[j * nu + i][a] for j in range(nv)) / nv for a in range(3)]
    edge = round(edge_u * (nu - 1))
    a, b = column(edge), column(nu - 1)
    overhang = (nu - 1 - edge) * spacing
    phi = math.atan2(a[2] - b[2], b[0] - a[0])
    c_length = bending_length(overhang, phi)
    # The statics at mid-overhang: the moment of the weight beyond column m
    # about the centre line there, over the strip's width, against the centre
    # line's curvature (its turn between its neighbours over the arc between
    # them): M = B κ w for any bend, where the droop's chord carries the
    # clamp's error (tests/model/test_material.cpp does the same).
    strip = float(scene["cloth"]["size"].strip("[]").split(",")[1])
    cell = spacing * strip / (nv - 1)
    mass = lambda i, j: density * cell * (0.5 if i in (0, nu - 1) else 1) * (0.5 if j in (0, nv - 1) else 1)
    mid = (edge + nu - 1) // 2
    x_mid = column(mid)[0]
    moment = sum(mass(i, j) * 9.81 * (v[j * nu + i][0] - x_mid) for i in range(mid + 1, nu) for j in range(nv))
    back = [p - q for p, q in zip(column(mid), column(mid - 1))]
    ahead = [p - q for p, q in zip(column(mid + 1), column(mid))]
    turn = math.atan2(back[2], back[0]) - math.atan2(ahead[2], ahead[0])
    kappa = turn / (0.5 * (math.hypot(*back) + math.hypot(*ahead)))
    return {"grid": nu, "spacing": spacing, "bending_k": bending_k, "rigidity": rigidity, "chord": phi,
            "ok": c["ok"], "c": c_length, "peirce": peirce(overhang, phi), "overhang": overhang,
            "b_from_c": c_length ** 3 * density * 9.81,
            "b_statics": moment / (kappa * strip) if kappa and not provot else None}


GRID_MEASURES = [("handle_height_m", "handle height", 1000, "mm", 1),
                 ("contact_area_m2", "contact area", 1e4, "cm²", 0),
                 ("base_diagonal_m", "base diagonal", 100, "cm", 1),
                 ("travel_force_n", "hand's force over its travel", 1, "N", 3)]


def grid_section(sweeps, runs):
    """The grid-convergence section: its Markdown lines, and the done-criteria
    [(what, measured, verdict)]."""
    sizes = [g for g in GRID_SIZES if g == 51 or any(sweeps.get(f"grid-{s}-{g}") is not None for s in GRIDDED)]
    value = {}
    for scene in GRIDDED:
        for g in sizes:
            cases = sweeps.get(scene if g == 51 else f"grid-{scene}-{g}")
            value[scene, g] = find(cases, 0.7) if cases else None
    change = lambda a, b: (b / a - 1) if isinstance(a, float) and isinstance(b, float) and a else None
    pct = lambda x: "—" if x is None else f"{x:+.1%}"
    refinements = list(zip(sizes, sizes[1:]))  # each grid to the next finer one
    rows = []
    for scene in GRIDDED:
        for key, label, scale, unit, digits in GRID_MEASURES:
            vals = [(value[scene, g] or {}).get(key) for g in sizes]
            if not any(isinstance(x, float) for x in vals) or (key == "handle_height_m" and scene == "drape-ball"):
                continue
            at = dict(zip(sizes, vals))
            # The scene's own scatter at 51: its runs at ω = 0.7 moved by k·1e-7.
            runs51 = [c.get(key) for c in ensemble(sweeps.get(scene), 0.7) + ensemble(sweeps.get("explicit-" + scene), 0.7)]
            runs51 = [x for x in runs51 if isinstance(x, float)]
            scatter = (f"{fmt(min(runs51), scale, digits)}–{fmt(max(runs51), scale, digits)} "
                       f"({(max(runs51) - min(runs51)) / (sum(runs51) / len(runs51)):.1%})") if len(runs51) > 1 else "—"
            rows.append([scene, f"{label}, {unit}"] + [fmt(x, scale, digits) for x in vals] +
                        [pct(change(at.get(a), at.get(b))) for a, b in refinements] + [scatter])
    lines = ["## Grid convergence", "",
             "The same cloth on grids of " + ", ".join(f"{g} × {g}" for g in sizes) + " particles "
             "(`wetcloth sweep SCENE --grid G --humidity 0.7`: a handle's patch keeps its size in metres, "
             "the explicit step shrinks with its stability limit; 51 is the sweep above), at the final frame. "
             "The material is the same at every grid (docs/model.md section 1): structural and shear springs "
             "keep their constants, and the bending is a curvature energy of rigidity B (with "
             "material.bending = \"provot\", bending springs of B / l²).", "",
             md_table(["scene", "measure"] + [f"{g} × {g}" for g in sizes] +
                      [f"{a} → {b}" for a, b in refinements] + ["51 × 51 scatter (ω = 0.7 ± k·1e−7)"], rows), "",
             "The last column is how far the scene's own chaos spreads its result at 51 × 51: the five "
             "runs with the humidity moved by up to 2e−7. A change between grids within it is not the "
             "grid's.", ""]
    criteria = []
    # Issue 37: from 51 on, each refinement changes the measure by less than
    # 5 %, and by less than the refinement before it.
    for scene, key, label in (("pull-straight", "handle_height_m", "straight pull's handle height"),
                              ("pull-oblique", "travel_force_n", "oblique hand's force over its travel"),
                              ("drape-ball", "contact_area_m2", "drape-ball's contact area")):
        what = f"{label}: from 51 on, each refinement changes it by less than 5 %, and by less than the one before"
        at = {g: (value[scene, g] or {}).get(key) for g in sizes}
        steps = [(a, b, change(at.get(a), at.get(b))) for a, b in refinements]
        steps = [(a, b, c) for a, b, c in steps if c is not None]
        if not any(a >= 51 for a, _, _ in steps):
            criteria.append((what, "not run", "not run"))
            continue
        ok = (all(abs(c) < 0.05 for a, _, c in steps if a >= 51)
              and all(abs(c2) < abs(c1) for (_, _, c1), (_, _, c2) in zip(steps, steps[1:])))
        bad = [g for g in sizes if value[scene, g] and not value[scene, g]["ok"]]
        criteria.append((what, "; ".join(f"{a} → {b}: {c:+.1%}" for a, b, c in steps),
                         verdict(ok, ("blew up at " + ", ".join(map(str, bad))) if bad else "")))
    bent = [cantilever(os.path.join(runs, f"grid-cantilever-{g}")) for g in CANTILEVER_GRIDS
            if os.path.exists(os.path.join(runs, f"grid-cantilever-{g}", "sweep.csv"))]
    bent = [b for b in bent if b]
    lines += ["### The cantilever's bending length", "",
              "`wetcloth sweep cantilever --grid G --humidity 0`: a dry strip 30 × 2.4 cm held flat over its "
              "first 24 cm, its last 6 cm overhanging. The bending length c is that of the heavy elastica "
              "(Peirce's cantilever, solved exactly) whose tip droops to the same chord angle below the "
              "clamp's edge; Peirce's own formula, c = L (cos(θ/2) / (8 tan θ))^(1/3), is shown beside it "
              "(it holds to about 45°). The droop's c carries the clamp's error, first order in the spacing "
              "(the pin holds the last two platform columns level, so the strip acts a grid step longer): "
              "it converges to the material's from below. The statics at mid-overhang do not: the moment "
              "of the weight beyond a section, over the strip's width and the centre line's curvature "
              "there, is B for any bend.", ""]
    if bent:
        bending = lambda b: (f"Provot springs {b['bending_k']:.3g} N/m" if b["bending_k"] is not None
                             else f"quadratic, B {b['rigidity']:.3g} N·m")
        statics = lambda b: f"{b['b_statics']:.3g}" if b["b_statics"] else "—"
        lines += [md_table(["grid", "spacing mm", "bending", "chord angle °", "bending length c mm",
                            "Peirce's formula mm", "B = c³ ρ_A g, N·m", "B from the statics, N·m"],
                           [[b["grid"], f"{b['spacing'] * 1000:.0f}", bending(b),
                             f"{math.degrees(b['chord']):.1f}", f"{b['c'] * 1000:.1f}", f"{b['peirce'] * 1000:.1f}",
                             f"{b['b_from_c']:.3g}", statics(b)]
                            for b in bent]), ""]
    what = ("the cantilever gives B back at every grid: the statics within 5 %, the droop converging "
            "to it from below")
    if len(bent) >= 2 and all(b["bending_k"] is None and b["b_statics"] for b in bent):
        ratios = [b["b_statics"] / b["rigidity"] for b in bent]
        droop = [b["b_from_c"] / b["rigidity"] for b in bent]
        ok = (all(abs(r - 1) < 0.05 for r in ratios) and all(x < y for x, y in zip(droop, droop[1:]))
              and droop[-1] < 1)
        criteria.append((what, "statics " + ", ".join(f"{b['grid']}: {r:.3f} B" for b, r in zip(bent, ratios)) +
                         "; droop " + ", ".join(f"{d:.3f}" for d in droop),
                         verdict(ok, "" if all(b["ok"] for b in bent) else "a run blew up")))
    else:
        criteria.append((what, "not run (quadratic bending on two grids or more)", "not run"))
    lines += [md_table(["criterion (issues 25, 37)", "measured", "result"],
                       [[w, m, f"**{v}**" if v.startswith(("PASS", "FAIL")) else v] for w, m, v in criteria]), ""]
    return lines, criteria


# ---------------------------------------------------------------- the report

def machine():
    try:
        uname = subprocess.run(["uname", "-a"], capture_output=True, text=True).stdout.strip()
    except OSError:
        uname = " ".join(platform.uname())
    cpu = ""
    try:
        with open("/proc/cpuinfo") as f:
            cpu = next((l.split(":", 1)[1].strip() for l in f if l.startswith("model name")), "")
    except OSError:
        pass
    return f"`{uname}`, {os.cpu_count()} cores" + (f" ({cpu})" if cpu else "")


def git_commit():
    try:
        r = subprocess.run(["git", "-C", HERE, "rev-parse", "--short", "HEAD"], capture_output=True,
                           text=True)
        return r.stdout.strip() if r.returncode == 0 else ""
    except OSError:
        return ""


def sweep_table(name, cases):
    multi = len({c.get("air_model") for c in cases}) > 1
    travel = ("force over travel N", "travel_force_n", 1, 3)
    extra = {"drag-corner": [travel, ("slid cm", "slid_m", 100, 2)],
             "pull-oblique": [travel, ("lifted at the stop cm²", "stop_lifted_m2", 1e4, 1)],
             "peel-rig": [("peak force N", "peak_force_n", 1, 3)],
             "drape-ball": [("outer diag. cm", "outer_diagonal_m", 100, 1)],
             "air-models": [("tent slope", "tent_slope", 1, 2)]}.get(name, [])
    header = (["ω"] + (["air model"] if multi else []) +
              ["status", "handle height cm", "base diag. cm", "contact cm²", "lifted cm²",
               "peak deficit Pa (any step)", "time to 5 cm s", "wrinkle rad"] +
              [e[0] for e in extra] + ["wall s"])
    hums = [c["humidity"] for c in cases if isinstance(c.get("humidity"), float)]
    decimals = next(d for d in range(2, 18) if len({f"{h:.{d}f}" for h in hums}) == len(set(hums)))
    rows = []
    for c in sorted(cases, key=lambda c: (str(c.get("air_model")), c.get("humidity") or 0)):
        t5 = c.get("time_to_5cm_s")
        rows.append([fmt(c.get("humidity"), 1, decimals)] + ([c.get("air_model", "")] if multi else []) + [
            c.get("status", "—"), fmt(c.get("handle_height_m"), 100), fmt(c.get("base_diagonal_m"), 100),
            fmt(c.get("contact_area_m2"), 1e4, 1), fmt(c.get("lifted_area_m2"), 1e4, 1),
            fmt(c.get("peak_deficit_pa"), 1, 0), "never" if t5 == -1 else fmt(t5),
            fmt(c.get("wrinkle_rad"), 1, 3)] + [fmt(c.get(e[1]), e[2], e[3]) for e in extra] +
            [fmt(number(c["summary"].get("wall_seconds")), 1, 0)])
    return md_table(header, rows)


def figures(name, folder, report_dir):
    """Copy the sweep's PNGs next to the report; Markdown image links to them."""
    if not any(os.path.exists(os.path.join(folder, f + ".png")) for f in FIGURES):
        subprocess.run([sys.executable, os.path.join(HERE, "plot_sweep.py"), folder, "--title", name],
                       capture_output=True)
    fig_dir = os.path.join(report_dir, "figures")
    links = []
    for f in FIGURES:
        src = os.path.join(folder, f + ".png")
        dst = os.path.join(fig_dir, f"{name}_{f}.png")
        if os.path.exists(src):
            os.makedirs(fig_dir, exist_ok=True)
            shutil.copyfile(src, dst)
            links.append(f"![{name} {f}]({os.path.relpath(dst, report_dir)})")
        elif os.path.exists(dst):  # a plot the sweep no longer makes: no stale copy
            os.remove(dst)
    return "\n".join(links) if links else "_No figures (tools/plot_sweep.py could not draw them)._"


def last_line(path):
    try:
        with open(path, encoding="utf-8", errors="replace") as f:
            lines = [l.strip() for l in f.read().replace("\r", "\n").splitlines() if l.strip()]
        return lines[-1] if lines else ""
    except OSError:
        return ""


def report(runs, report_path, command):
    report_dir = os.path.dirname(os.path.abspath(report_path))
    known = EXPERIMENTS + GRID_RUNS + FINE_RUNS
    others = sorted(d for d in os.listdir(runs) if d not in known
                    and os.path.exists(os.path.join(runs, d, "sweep.csv"))) if os.path.isdir(runs) else []
    names = EXPERIMENTS + [n for n in FINE_RUNS if os.path.isdir(os.path.join(runs, n))] + others
    sweeps = {n: load_sweep(os.path.join(runs, n)) for n in names + GRID_RUNS + FINE_RUNS}
    version = next((c["summary"].get("version") for cs in sweeps.values() for c in cs or []
                    if c["summary"].get("version")), "?")
    results = [(exp, paper, test, *evaluate(sweeps)) for exp, paper, test, evaluate in CLAIMS]
    count = lambda v: sum(1 for r in results if r[4].startswith(v))
    # The paper's claims again at 101 x 101: its scenes' sweeps in their place.
    fine_sweeps = dict(sweeps, **{s: sweeps.get(f"claims{FINE}-{s}") for s in PAPER})
    fine = [evaluate(fine_sweeps) if exp in PAPER and fine_sweeps[exp] else
            ("not run", "not run") if exp in PAPER else ("—", "—")
            for exp, _, _, evaluate in CLAIMS]
    count_fine = lambda v: sum(1 for _, f in fine if f.startswith(v))
    bold = lambda v: f"**{v}**" if v.startswith(("PASS", "FAIL", "INCONCLUSIVE")) else v
    laws = [(law, how, *evaluate(runs, sweeps)) for law, how, evaluate in LAWS]
    laws_kept = sum(1 for l in laws if l[4] == "PASS")
    laws_broken = sum(1 for l in laws if l[4].startswith("FAIL"))

    out = ["# wetcloth validation against the paper", "",
           f"- made by: `{command}`",
           f"- date: {datetime.datetime.now().astimezone().isoformat(timespec='seconds')}",
           f"- machine: {machine()}",
           f"- wetcloth {version}" + (f", commit {git_commit()}" if git_commit() else ""),
           f"- runs: `{runs}`", "",
           f"**Claims: {count('PASS')} pass, {count('FAIL')} fail, {count('INCONCLUSIVE')} inconclusive, "
           f"{count('not run')} not run** "
           "(docs/model.md section 11; details below). "
           f"**At {FINE} × {FINE}: {count_fine('PASS')} pass, {count_fine('FAIL')} fail, "
           f"{count_fine('INCONCLUSIVE')} inconclusive, {count_fine('not run')} not run.** "
           f"**Laws: {laws_kept} kept, {laws_broken} broken, "
           f"{len(laws) - laws_kept - laws_broken} not run.**", "",
           "## Claims", "",
           f"Each claim on the scenes' own grid (51 × 51), and again at {FINE} × {FINE} "
           f"(`claims{FINE}-<scene>`: the same sweep with `--grid {FINE}`), where a claim that "
           "held only on the coarser grid would show itself.", "",
           md_table(["experiment", "the paper reports", "we test", "we measured", "result",
                     f"at {FINE} × {FINE}", "result"],
                    [[e, p, t, m, bold(v), fm, bold(fv)]
                     for (e, p, t, m, v), (fm, fv) in zip(results, fine)]), ""]
    notes = []
    for (e, p, t, m, v), (fm, fv) in zip(results, fine):
        for grid, ran, verdict_ in ((51, sweeps, v), (FINE, fine_sweeps, fv)):
            note = CLAIM_NOTES.get(p, lambda *_: None)(ran, grid) if verdict_.startswith("FAIL") else None
            if note:
                notes.append(f"- **{e}, {p}** ({grid} × {grid}): {note}.")
    if notes:
        out += ["Why the failing claims fail, from the runs:", ""] + notes + [""]

    out += ["## Laws the model keeps", "",
            md_table(["law", "we test", "we measured", "expected", "result"],
                     [[l, h, m, e, f"**{v}**" if v.startswith(("PASS", "FAIL")) else v]
                      for l, h, m, e, v in laws]), ""]
    grid_lines, _ = grid_section(sweeps, runs)
    out += grid_lines
    # tools/work_precision.py's table and plot, when validate.sh ran it.
    wp = os.path.join(runs, "work-precision")
    if os.path.exists(os.path.join(wp, "table.md")):
        out += ["## Work against precision", "",
                "Each integrator setting's cost (CPU s per simulated s, one thread) and its worst "
                "error against the reference (symplectic Euler at 2.5e-5 s) over the scenes' "
                "metrics (tools/work_precision.py says how each is read).", "",
                open(os.path.join(wp, "table.md"), encoding="utf-8").read().rstrip(), ""]
        plot = os.path.join(wp, "work_precision.png")
        if os.path.exists(plot):
            os.makedirs(os.path.join(report_dir, "figures"), exist_ok=True)
            shutil.copyfile(plot, os.path.join(report_dir, "figures", "work_precision.png"))
            out += ["![work against precision](figures/work_precision.png)", ""]

    cmd_log = os.path.join(runs, "commands.log")
    if os.path.exists(cmd_log):
        rows = [l.rstrip("\n").split("\t") for l in open(cmd_log, encoding="utf-8") if l.strip()]
        out += ["## Runs", "", md_table(["sweep", "exit code", "wall s", "command"],
                                        [r[:3] + [f"`{r[3]}`" if len(r) > 3 else ""] for r in rows]), ""]

    for name in names:
        folder = os.path.join(runs, name)
        out += [f"## {name}", ""]
        skipped = os.path.join(runs, name + ".skipped")
        if os.path.exists(skipped):
            note = open(skipped, encoding="utf-8", errors="replace").read().strip()
            out += [f"Not run: skipped. {note}", ""]
            continue
        cases = sweeps[name]
        if cases is None:
            why = last_line(os.path.join(runs, name + ".log"))
            out += ["Not run" + (f": the sweep wrote no sweep.csv; its log ends `{why}`." if why else "."), ""]
            continue
        first = cases[0]["scene"] if cases else {}
        out += [f"Resolution {first.get('cloth', {}).get('resolution', '?')}, "
                f"{first.get('run', {}).get('duration', '?')} s simulated, "
                f"{len(cases)} cases. Lengths in cm, areas in cm², at the final frame.", "",
                sweep_table(name, cases), "",
                "_An ensemble about ω = 0.7, compared in the claims table._"
                if name.startswith(("implicit-", "explicit-")) else
                f"_An ensemble about ω = 0.7 at {FINE} × {FINE}: the scatter its claims there are read against._"
                if name in SCATTER_RUNS else
                f"_At {FINE} × {FINE}, for the claims table's last columns._"
                if name in FINE_RUNS else figures(name, folder, report_dir), ""]

    os.makedirs(report_dir, exist_ok=True)
    tmp = report_path + ".tmp"
    with open(tmp, "w", encoding="utf-8") as f:
        f.write("\n".join(out))
    os.replace(tmp, report_path)
    return count("PASS"), count("FAIL"), count("INCONCLUSIVE"), count("not run")


def main():
    parser = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    parser.add_argument("runs", help="the folder of sweep folders (validation/runs)")
    parser.add_argument("report", help="the Markdown file to write (validation/report.md)")
    parser.add_argument("--command", help="the command to credit (default: this one)")
    args = parser.parse_args()
    command = args.command or " ".join(["tools/validation_report.py"] + sys.argv[1:])
    passed, failed, inconclusive, not_run = report(args.runs, args.report, command)
    print(f"validation_report.py: wrote {args.report}: {passed} pass, {failed} fail, "
          f"{inconclusive} inconclusive, {not_run} not run")
    return 0


if __name__ == "__main__":
    sys.exit(main())
