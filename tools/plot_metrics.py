#!/usr/bin/env python3
"""Plot one run's metrics against time.

Usage: plot_metrics.py DIR/metrics.csv OUT.png --panel COLS [--panel COLS ...]
                       [--title TEXT] [--width INCHES]

Reads the metrics.csv a `wetcloth run` writes (one row per output frame,
SI units in the header) and draws one panel per --panel, stacked over a
shared time axis: COLS is a comma-separated list of column names drawn
together (e.g. humidity_mean,humidity_min,humidity_max), with an optional
":LABEL" for the panel's y axis (default: the first column's name). A
column named with a "*SCALE" suffix is drawn times SCALE (e.g.
water_kg*1000:water (g)). The guide's metrics plots are made with it
(docs/guide.md, "Built-in scenes"), small PNGs for the repository.

Exit codes: 0 ok; 1 matplotlib missing; 2 a missing or malformed input
file or an unknown column, reported as "plot_metrics.py: error: FILE: WHAT",
and nothing written (the figure goes to a temporary name, then is renamed).
Needs matplotlib (Debian: python3-matplotlib, i.e. run it with /usr/bin/python3).
"""
import argparse
import csv
import math
import os
import sys


def fail(path, what):
    print(f"plot_metrics.py: error: {path}: {what}", file=sys.stderr)
    sys.exit(2)


def read_metrics(path):
    """column name -> list of floats."""
    try:
        with open(path, newline="") as f:
            rows = list(csv.reader(f))
    except OSError as e:
        fail(path, e.strerror or str(e))
    if not rows or "time_s" not in rows[0]:
        fail(path, "not a wetcloth metrics.csv (no time_s column in its header)")
    header = rows[0]
    data = {name: [] for name in header}
    for number, row in enumerate(rows[1:], start=2):
        if len(row) != len(header):
            fail(path, f"line {number}: {len(row)} values for {len(header)} columns")
        for name, text in zip(header, row):
            try:
                data[name].append(float(text))
            except ValueError:
                fail(path, f"line {number}: {name} = {text!r} is not a number")
    if not data["time_s"]:
        fail(path, "no rows")
    return data


def parse_panel(spec, data, path):
    """'a,b*1000:label' -> ([(name, scale), ...], label)."""
    cols, _, label = spec.partition(":")
    series = []
    for item in cols.split(","):
        name, _, scale = item.strip().partition("*")
        if name not in data:
            fail(path, f"no column {name!r} (it has: {', '.join(data)})")
        try:
            factor = float(scale) if scale else 1.0
        except ValueError:
            fail(path, f"--panel {spec!r}: {scale!r} is not a number")
        series.append((name, factor))
    return series, label or (series[0][0] + (f" ×{scale}" if scale else ""))


def main():
    ap = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    ap.add_argument("metrics")
    ap.add_argument("out")
    ap.add_argument("--panel", action="append", required=True)
    ap.add_argument("--title", default="")
    ap.add_argument("--width", type=float, default=6.4)
    args = ap.parse_args()
    try:
        import matplotlib
        matplotlib.use("Agg")
        import matplotlib.pyplot as plt
    except ImportError:
        sys.exit(f"plot_metrics.py: error: matplotlib is not installed for {sys.executable} "
                 "(Debian: apt-get install python3-matplotlib, run with /usr/bin/python3)")
    data = read_metrics(args.metrics)
    panels = [parse_panel(spec, data, args.metrics) for spec in args.panel]
    t = data["time_s"]
    fig, axes = plt.subplots(len(panels), 1, sharex=True, squeeze=False,
                             figsize=(args.width, 0.6 + 1.7 * len(panels)))
    for ax, (series, label) in zip(axes[:, 0], panels):
        for name, factor in series:
            values = [v * factor if math.isfinite(v) else float("nan") for v in data[name]]
            ax.plot(t, values, label=name + (f" ×{factor:g}" if factor != 1 else ""))
        ax.set_ylabel(label, fontsize=8)
        ax.tick_params(labelsize=7)
        ax.grid(alpha=0.3)
        if len(series) > 1:
            ax.legend(fontsize=7, loc="best")
    axes[-1, 0].set_xlabel("time (s)", fontsize=8)
    if args.title:
        fig.suptitle(args.title, fontsize=9)
    fig.tight_layout()
    tmp = f"{args.out}.{os.getpid()}.tmp.png"
    try:
        fig.savefig(tmp, dpi=80)
        os.replace(tmp, args.out)
    except OSError as e:
        if os.path.exists(tmp):
            os.remove(tmp)
        fail(args.out, e.strerror or str(e))
    print(f"wrote {args.out}")


if __name__ == "__main__":
    main()
