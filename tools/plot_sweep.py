#!/usr/bin/env python3
"""Plot a wetcloth humidity sweep.

Usage: plot_sweep.py DIR [--title TEXT]

Reads DIR/sweep.csv (written by `wetcloth sweep`) and every case's
DIR/<case>/metrics.csv and DIR/<case>/scene.toml (the resolved scene: its
[air] model and p_atm, [contact] surface, [table]/[ball] enabled,
[handle.NAME] types and a driven handle's path), and writes into DIR, each
as PNG and SVG, the plots whose quantities mean something for the scene:

  fig7           paper Fig. 7: (a) final pulled height and (b) base diagonal
                 against humidity, one line per air model; only for a handle
                 pulled by a force (type = "force") over a contact surface
  pressure       inner pressure deficit p_atm - p against time, one curve per
                 case; only with a contact surface and an air model not "off".
                 It shows the output frames: a case whose peak at any step
                 (sweep.csv's peak_deficit_pa) is higher, e.g. at the
                 breakthrough cap as a peel starts, between frames, says so
                 in the legend (in fig8 too)
  contact_area   contact area against time, one curve per case; only with a
                 contact surface
  handle_height  handle height against time, one curve per case; only for a
                 handle pulled by a force
  handle_force   instead of handle_height for a driven handle (type = "move",
                 e.g. peel-rig): the force it takes, handle_force_n, against
                 how far it has moved since the first frame, one curve per
                 case (a rig's force-displacement curve): the change of
                 handle_height_m for a vertical path (measured), else the
                 distance along its path, |velocity| times its time on it
                 (from [handle.NAME] velocity, start, max_travel: the metrics
                 give only its height)
  fig8           only with several air models and the pressure plot: paper
                 Fig. 8, the handle's height (or force, for a driven handle;
                 no column without a handle) and the pressure deficit against
                 time, the air models compared at each humidity

The handle is the one the metrics follow: the first, by name, that is not a
pin (pins alone make no handle plots). Without scene.toml the metrics decide: a handle if handle_height_m is
ever nonzero (taken as force-driven), a contact surface if contact_area_m2 or
base_diagonal_m is, air if the pressure deficit is, and p_atm = 101325 Pa.
It prints the plots it wrote and those it did not make, with why, and removes
older copies of the latter from DIR. time_to_5cm_s = -1 in sweep.csv means
"never reached"; it is read as None.

Cases whose status is not "ok" are drawn dashed, "(blew up)" in the legend.
Exit codes: 0 ok (also when no plot applies); 1 matplotlib missing; 2 a
missing or malformed input file, reported as "plot_sweep.py: error: FILE:
WHAT", and no figure written or removed (every figure is rendered to a
temporary name first, then renamed).
Needs matplotlib (Debian: python3-matplotlib, i.e. run it with /usr/bin/python3).
"""
import argparse
import csv
import json
import os
import sys
import tomllib

P_ATM = 101325.0
SWEEP_TEXT = ("case", "air_model", "status")
SWEEP_NUMBERS = ("humidity", "handle_height_m", "base_diagonal_m")
METRICS_NUMBERS = ("time_s", "handle_height_m", "handle_force_n", "contact_area_m2", "inner_pressure_pa")
FIGURES = ("fig7", "pressure", "contact_area", "handle_height", "handle_force", "fig8")
MODEL_STYLES = ["-", ":", "-.", (0, (3, 1, 1, 1, 1, 1))]  # "--" is kept for blown-up cases
MARKERS = ["o", "s", "^", "D"]


class InputError(Exception):
    """A missing or malformed input file: str() is 'FILE: WHAT'."""


def read_csv(path, numbers, texts=()):
    """Rows of a CSV file as dicts. The columns in `numbers` must exist and be
    numbers, those in `texts` must exist; other columns are kept as numbers
    when they parse, as text otherwise."""
    try:
        with open(path, newline="", encoding="utf-8") as f:
            lines = list(csv.reader(f))
    except OSError as e:
        raise InputError(f"{path}: {(e.strerror or str(e)).lower()}")
    except (UnicodeDecodeError, csv.Error) as e:
        raise InputError(f"{path}: unreadable ({e})")
    if not lines:
        raise InputError(f"{path}: empty file, no header")
    header = [h.strip() for h in lines[0]]
    missing = [c for c in (*texts, *numbers) if c not in header]
    if missing:
        raise InputError(f"{path}: header lacks column(s) {', '.join(missing)}")
    rows = []
    for n, line in enumerate(lines[1:], start=2):
        if not line:
            continue
        if len(line) != len(header):
            raise InputError(f"{path}: line {n}: {len(line)} fields, the header has {len(header)}")
        row = {}
        for name, value in zip(header, (v.strip() for v in line)):
            try:
                row[name] = value if name in texts else float(value)
            except ValueError:
                if name in numbers:
                    raise InputError(f"{path}: line {n}: {name} = '{value}' is not a number")
                row[name] = value
        rows.append(row)
    return rows


def read_scene(case_dir):
    """The case's scene.toml as nested dicts (tomllib), None when there is no
    file."""
    path = os.path.join(case_dir, "scene.toml")
    if not os.path.exists(path):
        return None
    try:
        with open(path, "rb") as f:
            return tomllib.load(f)
    except (OSError, tomllib.TOMLDecodeError) as e:
        raise InputError(f"{path}: unreadable ({e})")


def scene_value(scene, path, section, key, default, kind):
    """scene[section][key] (section dotted, as in "handle.pull"), checked to be
    a `kind`: str, bool, float (an integer counts as a number) or list."""
    table = scene
    for part in section.split("."):
        table = table.get(part, {})
    value = table.get(key, default)
    ok = isinstance(value, (int, float)) and not isinstance(value, bool) if kind is float \
        else isinstance(value, kind)
    if not ok:
        what = {float: "a number", bool: "true or false", str: "a quoted string", list: "a list"}[kind]
        raise InputError(f"{path}: [{section}] {key} is not {what}")
    return float(value) if kind is float else value


def describe(case_dir, metrics):
    """What the case's plots can show: {'p_atm', 'handle' ("force", "move" or
    None), 'path' (a driven handle's (velocity, start, max_travel), else
    None), 'surface' (bool), 'air' (bool)}, from scene.toml (the defaults of
    `wetcloth params` for missing keys), from the metrics without it."""
    scene = read_scene(case_dir)
    if scene is None:
        nonzero = lambda name: any(r[name] != 0 for r in metrics if isinstance(r.get(name), float))
        return {"p_atm": P_ATM, "handle": "force" if nonzero("handle_height_m") else None, "path": None,
                "surface": nonzero("contact_area_m2") or nonzero("base_diagonal_m"),
                "air": any(r["inner_pressure_pa"] != P_ATM for r in metrics), "setup": None}
    path = os.path.join(case_dir, "scene.toml")
    get = lambda section, key, default, kind=str: scene_value(scene, path, section, key, default, kind)
    surface = get("contact", "surface", "table")
    surface = ((surface == "table" and get("table", "enabled", True, bool)) or
               (surface == "ball" and get("ball", "enabled", False, bool)))
    handle, handle_path, force = None, None, None
    for section in sorted(f"handle.{h}" for h in scene.get("handle", {})):  # the metrics' order
        kind = get(section, "type", "force")
        if kind not in ("force", "move", "pin"):
            raise InputError(f"{path}: [{section}] type = '{kind}' is not force, move or pin")
        if kind != "pin":
            handle = kind
            if kind == "move":
                velocity = get(section, "velocity", [0.0, 0.0, 0.0], list)
                if len(velocity) != 3 or not all(isinstance(v, (int, float)) and not isinstance(v, bool)
                                                 for v in velocity):
                    raise InputError(f"{path}: [{section}] velocity is not three numbers")
                handle_path = ([float(v) for v in velocity], get(section, "start", 0.0, float),
                               get(section, "max_travel", 0.0, float))
            else:
                force = (section.split(".", 1)[1], get(section, "force", [0.0, 0.0, 0.0], list))
            break
    mesh = get("cloth", "mesh", "")
    grid = (f"mesh {mesh}" if mesh else
            " × ".join(f"{v:g}" for v in get("cloth", "resolution", [31, 31], list)))
    setup = {"duration": f"{get('run', 'duration', 2.0, float):g} s", "grid": grid,
             "force": (f"handle {force[0]} {'[' + ', '.join(f'{v:g}' for v in force[1]) + ']'} N"
                       if force else "no force handle")}
    return {"p_atm": get("air", "p_atm", P_ATM, float), "handle": handle, "path": handle_path,
            "surface": surface, "air": surface and get("air", "model", "exchange") != "off",
            "setup": setup}


def load(sweep_dir):
    """The sweep's cases, each a dict: the sweep.csv row (time_to_5cm_s None
    for -1, "never reached"), plus 'metrics' (the metrics.csv rows), the keys
    of describe(), 'ok' and 'label'."""
    cases = read_csv(os.path.join(sweep_dir, "sweep.csv"), SWEEP_NUMBERS, SWEEP_TEXT)
    if not cases:
        raise InputError(f"{os.path.join(sweep_dir, 'sweep.csv')}: no cases")
    models = sorted({c["air_model"] for c in cases})
    for c in cases:
        if c["case"] in ("", ".", "..") or os.path.basename(c["case"]) != c["case"]:
            raise InputError(f"{os.path.join(sweep_dir, 'sweep.csv')}: bad case name '{c['case']}'")
        case_dir = os.path.join(sweep_dir, c["case"])
        c["metrics"] = read_csv(os.path.join(case_dir, "metrics.csv"), METRICS_NUMBERS)
        c.update(describe(case_dir, c["metrics"]))
        if isinstance(c.get("time_to_5cm_s"), float) and c["time_to_5cm_s"] < 0:
            c["time_to_5cm_s"] = None  # -1: the handle never reached 5 cm
        c["ok"] = c["status"] == "ok"
        c["label"] = f"ω={c['humidity']:.2f}" + (f", {c['air_model']}" if len(models) > 1 else "")
        c["label"] += "" if c["ok"] else " (blew up)"
    cases.sort(key=lambda c: (models.index(c["air_model"]), c["humidity"]))
    return cases, models


def default_title(sweep_dir, cases):
    """The scene name from a case's summary.json, else the folder's name."""
    for c in cases:
        try:
            with open(os.path.join(sweep_dir, c["case"], "summary.json"), encoding="utf-8") as f:
                return str(json.load(f)["scene"])
        except (OSError, ValueError, KeyError, TypeError):
            pass
    return os.path.basename(os.path.abspath(sweep_dir))


def setup_caption(cases):
    """The duration, grid and force the cases ran with (from their scene.toml),
    each once where the cases share it, else "varied"; '' without scene.toml."""
    setups = [c["setup"] for c in cases if c.get("setup")]
    if not setups:
        return ""
    shown = []
    for key in ("duration", "grid", "force"):
        values = sorted({s[key] for s in setups})
        shown.append(values[0] if len(values) == 1 else f"{key} varied")
    return "\n" + ", ".join(shown)


def column(case, name, scale=1.0):
    return [r[name] * scale for r in case["metrics"]]


def deficit(case):
    return [case["p_atm"] - r["inner_pressure_pa"] for r in case["metrics"]]


def step_peak_note(case):
    """' (peak at any step: N Pa)' when sweep.csv's peak deficit over every step is
    above the largest at the frames the plots show, else ''."""
    step = case.get("peak_deficit_pa")
    if not isinstance(step, float):
        return ""  # a sweep.csv without the column
    shown = max(deficit(case), default=0.0)
    return f" (peak at any step: {step:.0f} Pa)" if step > shown + max(1.0, 0.01 * abs(shown)) else ""


def vertical_path(case):
    """Whether a driven handle moves straight up or down: then its height,
    which the metrics measure, tells how far it has gone."""
    velocity = case["path"][0] if case["path"] else [0.0, 0.0, 0.0]
    return velocity[0] == velocity[1] == 0 and velocity[2] != 0


def displacement(case):
    """How far a driven handle has moved since the first frame, mm, at every
    frame: measured from its height on a vertical path; else the distance
    along its path, which the handle follows exactly (|velocity| times its
    time on the path, from `start` until `max_travel`)."""
    if vertical_path(case):
        sign = 1.0 if case["path"][0][2] > 0 else -1.0
        first = case["metrics"][0]["handle_height_m"]
        return [sign * (h - first) * 1000 for h in column(case, "handle_height_m")]
    velocity, start, max_travel = case["path"] or ([0.0, 0.0, 0.0], 0.0, 0.0)
    speed = sum(v * v for v in velocity) ** 0.5
    on_path = [max(0.0, t - start) for t in column(case, "time_s")]
    if max_travel > 0 and speed > 0:
        on_path = [min(t, max_travel / speed) for t in on_path]
    return [speed * t * 1000 for t in on_path]


def plan(cases, models):
    """The figures that mean something for the sweep, in FIGURES' order, and
    {name: why not} for the others (handle_height and handle_force stand for
    each other: only one of them is ever listed). The handle is the first
    case's (a sweep's cases are one scene)."""
    handle = cases[0]["handle"]
    surface = any(c["surface"] for c in cases)
    air = any(c["air"] for c in cases)
    why = {}
    if handle != "force":
        why["fig7"] = "the handle is driven, its height fixed" if handle == "move" else "no handle"
        if handle is None:
            why["handle_height"] = "no handle"
    elif not surface:
        why["fig7"] = "no contact surface"
    if not air:
        why["pressure"] = "no contact surface" if not surface else "air model off"
    if not surface:
        why["contact_area"] = "no contact surface"
    if len(models) < 2:
        why["fig8"] = "one air model"
    elif not air:
        why["fig8"] = why["pressure"]
    handle_plot = {"force": "handle_height", "move": "handle_force"}.get(handle)
    made = [f for f in FIGURES if f not in why and (f not in ("handle_height", "handle_force") or f == handle_plot)]
    return made, why


def make_figures(cases, models, title, made):
    """name -> matplotlib figure, for the names in `made`."""
    import matplotlib.pyplot as plt

    cmap = plt.get_cmap("viridis")
    hue = lambda c: cmap(0.85 * min(max(c["humidity"], 0.0), 1.0))
    style = lambda c: MODEL_STYLES[models.index(c["air_model"]) % len(MODEL_STYLES)] if c["ok"] else "--"
    figs = {}
    caption = setup_caption(cases)  # under each title: what the cases ran

    # Fig. 7: final values against humidity, one line per air model.
    if "fig7" in made:
        fig, axes = plt.subplots(1, 2, figsize=(10, 4), constrained_layout=True)
        for key, ax, what, ylabel in (
                ("handle_height_m", axes[0], "(a) pulled height", "final pulled height (cm)"),
                ("base_diagonal_m", axes[1], "(b) base diagonal", "final base diagonal (cm)")):
            for i, model in enumerate(models):
                mine = [c for c in cases if c["air_model"] == model]
                ax.plot([c["humidity"] for c in mine], [c[key] * 100 for c in mine],
                        marker=MARKERS[i % len(MARKERS)], label=model if len(models) > 1 else None)
            bad = [c for c in cases if not c["ok"]]
            if bad:
                ax.scatter([c["humidity"] for c in bad], [c[key] * 100 for c in bad], s=110,
                           facecolors="none", edgecolors="red", zorder=3, label="(blew up): last value")
            ax.set(title=what, xlabel="humidity ω", ylabel=ylabel, xlim=(-0.03, 1.03))
            ax.set_xticks([0, 0.2, 0.4, 0.6, 0.8, 1.0])
            ax.grid(alpha=0.3)
            if ax.get_legend_handles_labels()[0]:
                ax.legend(fontsize=8)
        fig.suptitle(f"{title}: Fig. 7{caption}")
        figs["fig7"] = fig

    # One curve per case: against time, the handle's force against its displacement.
    handle = {"handle_height": ("handle height (cm)", lambda c: column(c, "handle_height_m", 100)),
              "handle_force": ("handle force (N)", lambda c: column(c, "handle_force_n"))}
    series = {"pressure": ("inner pressure deficit p_atm − p (Pa)", deficit),
              "contact_area": ("contact area (cm²)", lambda c: column(c, "contact_area_m2", 1e4)),
              **handle}
    for name in (f for f in made if f in series):
        ylabel, values = series[name]
        # A driven handle is a measuring rig: its force against how far it has
        # moved (docs/model.md section 9), not against time.
        rig = name == "handle_force"
        fig, ax = plt.subplots(figsize=(7.5, 4.5), constrained_layout=True)
        for c in cases:
            ax.plot(displacement(c) if rig else column(c, "time_s"), values(c), color=hue(c),
                    linestyle=style(c), label=c["label"] + (step_peak_note(c) if name == "pressure" else ""))
        xlabel = "time (s)"
        if rig:
            xlabel = ("handle displacement since the first frame, from its height (mm)"
                      if vertical_path(cases[0]) else
                      "handle displacement along its path, |velocity| × time on it (mm)")
        what = ylabel.split(" (")[0] + (" against displacement" if rig else "")
        ax.set(xlabel=xlabel, ylabel=ylabel, title=f"{title}: {what}{caption}")
        ax.grid(alpha=0.3)
        ax.legend(fontsize=8, ncol=2 if len(cases) > 6 else 1)
        figs[name] = fig

    # Fig. 8: the air models side by side, one row per humidity: the handle's
    # height or force (when there is a handle) and the pressure deficit.
    if "fig8" in made:
        hums = sorted({round(c["humidity"], 6) for c in cases})
        panels = [handle[f] for f in made if f in handle]
        panels.append(("p_atm − p (Pa)", deficit))
        fig, axes = plt.subplots(len(hums), len(panels), figsize=(5 * len(panels), 1.2 + 2.6 * len(hums)),
                                 squeeze=False, sharex=True, constrained_layout=True)
        for i, h in enumerate(hums):
            for c in (c for c in cases if round(c["humidity"], 6) == h):
                kw = dict(color=f"C{models.index(c['air_model'])}", linestyle="-" if c["ok"] else "--",
                          label=c["air_model"] + ("" if c["ok"] else " (blew up)"))
                for ax, (_, values) in zip(axes[i], panels):
                    note = step_peak_note(c) if values is deficit else ""
                    ax.plot(column(c, "time_s"), values(c), **{**kw, "label": kw["label"] + note})
            for ax, (ylabel, _) in zip(axes[i], panels):
                what = "pressure deficit" if ylabel.startswith("p_atm") else ylabel.split(" (")[0]
                ax.set(title=f"ω = {h:.2f}: {what}", ylabel=ylabel)
                ax.grid(alpha=0.3)
                ax.legend(fontsize=8)
        for ax in axes[-1]:
            ax.set_xlabel("time (s)")
        fig.suptitle(f"{title}: Fig. 8, air models{caption}")
        figs["fig8"] = fig
    return figs


def save_all(figs, out_dir):
    """Render every figure to a temporary name, then rename them all."""
    done = []
    try:
        for name, fig in figs.items():
            for ext in ("png", "svg"):
                tmp = os.path.join(out_dir, f".{name}.{ext}.tmp")
                done.append((tmp, os.path.join(out_dir, f"{name}.{ext}")))
                fig.savefig(tmp, format=ext, dpi=120, metadata={"Date": None} if ext == "svg" else None)
        for tmp, final in done:
            os.replace(tmp, final)
    finally:
        for tmp, _ in done:
            if os.path.exists(tmp):
                os.remove(tmp)


def main():
    parser = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    parser.add_argument("dir", help="the sweep folder (holds sweep.csv)")
    parser.add_argument("--title", help="figure title (default: the scene name)")
    args = parser.parse_args()
    try:
        import matplotlib
        matplotlib.use("Agg")
        matplotlib.rcParams["svg.hashsalt"] = "wetcloth"  # reproducible SVG ids
    except ImportError:
        sys.exit(f"plot_sweep.py: error: matplotlib is not installed for {sys.executable} "
                 "(Debian: apt-get install python3-matplotlib, run with /usr/bin/python3)")
    try:
        cases, models = load(args.dir)
    except InputError as e:
        print(f"plot_sweep.py: error: {e}", file=sys.stderr)
        return 2
    made, why = plan(cases, models)
    figs = make_figures(cases, models, args.title or default_title(args.dir, cases), made)
    save_all(figs, args.dir)
    stale = []  # an older sweep's plots that no longer apply
    for name in (f for f in FIGURES if f not in figs):
        paths = [os.path.join(args.dir, f"{name}.{ext}") for ext in ("png", "svg")]
        if any(os.path.exists(p) for p in paths):
            stale.append(name)
        for p in (p for p in paths if os.path.exists(p)):
            os.remove(p)
    print(f"plot_sweep.py: wrote {', '.join(figs) + ' (.png, .svg)' if figs else 'no plots'} into {args.dir}")
    notes = ([", ".join(f"{f} ({why[f]})" for f in FIGURES if f in why)] if why else []) + \
        ([f"removed the older {', '.join(stale)}"] if stale else [])
    if notes:
        print(f"plot_sweep.py: {'not made: ' if why else ''}{'; '.join(notes)}")
    return 0


if __name__ == "__main__":
    sys.exit(main())
