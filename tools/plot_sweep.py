#!/usr/bin/env python3
"""Plot a wetcloth humidity sweep.

Usage: plot_sweep.py DIR [--title TEXT]

Reads DIR/sweep.csv (written by `wetcloth sweep`) and every case's
DIR/<case>/metrics.csv (and the [air] p_atm of DIR/<case>/scene.toml, if
present; 101325 Pa otherwise), and writes into DIR, each as PNG and SVG:

  fig7           paper Fig. 7: (a) final pulled height and (b) base diagonal
                 against humidity, one line per air model
  pressure       inner pressure deficit p_atm - p against time, one curve per case
  contact_area   contact area against time, one curve per case
  handle_height  handle height against time, one curve per case
  fig8           only with several air models: paper Fig. 8, handle height and
                 pressure deficit against time, the air models compared at
                 each humidity

Cases whose status is not "ok" are drawn dashed, "(blew up)" in the legend.
Exit codes: 0 ok; 1 matplotlib missing; 2 a missing or malformed input file,
reported as "plot_sweep.py: error: FILE: WHAT", and no figure written (every
figure is rendered to a temporary name first, then renamed).
Needs matplotlib (Debian: python3-matplotlib, i.e. run it with /usr/bin/python3).
"""
import argparse
import csv
import json
import os
import sys

P_ATM = 101325.0
SWEEP_TEXT = ("case", "air_model", "status")
SWEEP_NUMBERS = ("humidity", "handle_height_m", "base_diagonal_m")
METRICS_NUMBERS = ("time_s", "handle_height_m", "contact_area_m2", "inner_pressure_pa")
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


def read_p_atm(case_dir):
    """[air] p_atm from the case's scene.toml, 101325 Pa when there is no file."""
    path = os.path.join(case_dir, "scene.toml")
    if not os.path.exists(path):
        return P_ATM
    section = ""
    try:
        with open(path, encoding="utf-8") as f:
            for n, line in enumerate(f, start=1):
                line = line.split("#", 1)[0].strip()
                if line.startswith("["):
                    section = line.strip("[] ")
                elif section == "air" and line.split("=", 1)[0].strip() == "p_atm":
                    try:
                        return float(line.split("=", 1)[1])
                    except (IndexError, ValueError):
                        raise InputError(f"{path}: line {n}: [air] p_atm is not a number")
    except (OSError, UnicodeDecodeError) as e:
        raise InputError(f"{path}: unreadable ({e})")
    return P_ATM


def load(sweep_dir):
    """The sweep's cases, each a dict: the sweep.csv row, plus 'metrics' (the
    metrics.csv rows), 'p_atm', 'ok' and 'label'."""
    cases = read_csv(os.path.join(sweep_dir, "sweep.csv"), SWEEP_NUMBERS, SWEEP_TEXT)
    if not cases:
        raise InputError(f"{os.path.join(sweep_dir, 'sweep.csv')}: no cases")
    models = sorted({c["air_model"] for c in cases})
    for c in cases:
        if c["case"] in ("", ".", "..") or os.path.basename(c["case"]) != c["case"]:
            raise InputError(f"{os.path.join(sweep_dir, 'sweep.csv')}: bad case name '{c['case']}'")
        case_dir = os.path.join(sweep_dir, c["case"])
        c["metrics"] = read_csv(os.path.join(case_dir, "metrics.csv"), METRICS_NUMBERS)
        c["p_atm"] = read_p_atm(case_dir)
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


def column(case, name, scale=1.0):
    return [r[name] * scale for r in case["metrics"]]


def deficit(case):
    return [case["p_atm"] - r["inner_pressure_pa"] for r in case["metrics"]]


def make_figures(cases, models, title):
    """name -> matplotlib figure."""
    import matplotlib.pyplot as plt

    cmap = plt.get_cmap("viridis")
    hue = lambda c: cmap(0.85 * min(max(c["humidity"], 0.0), 1.0))
    style = lambda c: MODEL_STYLES[models.index(c["air_model"]) % len(MODEL_STYLES)] if c["ok"] else "--"
    figs = {}

    # Fig. 7: final values against humidity, one line per air model.
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
    fig.suptitle(f"{title}: Fig. 7")
    figs["fig7"] = fig

    # Time series, one curve per case.
    series = (("pressure", "inner pressure deficit p_atm − p (Pa)", deficit),
              ("contact_area", "contact area (cm²)", lambda c: column(c, "contact_area_m2", 1e4)),
              ("handle_height", "handle height (cm)", lambda c: column(c, "handle_height_m", 100)))
    for name, ylabel, values in series:
        fig, ax = plt.subplots(figsize=(7.5, 4.5), constrained_layout=True)
        for c in cases:
            ax.plot(column(c, "time_s"), values(c), color=hue(c), linestyle=style(c), label=c["label"])
        ax.set(xlabel="time (s)", ylabel=ylabel, title=f"{title}: {ylabel.split(' (')[0]}")
        ax.grid(alpha=0.3)
        ax.legend(fontsize=8, ncol=2 if len(cases) > 6 else 1)
        figs[name] = fig

    # Fig. 8: the air models side by side, one row per humidity.
    if len(models) > 1:
        hums = sorted({round(c["humidity"], 6) for c in cases})
        fig, axes = plt.subplots(len(hums), 2, figsize=(10, 1.2 + 2.6 * len(hums)), squeeze=False,
                                 sharex=True, constrained_layout=True)
        for i, h in enumerate(hums):
            for c in (c for c in cases if round(c["humidity"], 6) == h):
                kw = dict(color=f"C{models.index(c['air_model'])}", linestyle="-" if c["ok"] else "--",
                          label=c["air_model"] + ("" if c["ok"] else " (blew up)"))
                axes[i][0].plot(column(c, "time_s"), column(c, "handle_height_m", 100), **kw)
                axes[i][1].plot(column(c, "time_s"), deficit(c), **kw)
            axes[i][0].set(title=f"ω = {h:.2f}: handle height", ylabel="handle height (cm)")
            axes[i][1].set(title=f"ω = {h:.2f}: pressure deficit", ylabel="p_atm − p (Pa)")
            for ax in axes[i]:
                ax.grid(alpha=0.3)
                ax.legend(fontsize=8)
        for ax in axes[-1]:
            ax.set_xlabel("time (s)")
        fig.suptitle(f"{title}: Fig. 8, air models")
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
    figs = make_figures(cases, models, args.title or default_title(args.dir, cases))
    save_all(figs, args.dir)
    print(f"plot_sweep.py: wrote {', '.join(figs)} (.png, .svg) into {args.dir}")
    return 0


if __name__ == "__main__":
    sys.exit(main())
