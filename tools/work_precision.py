#!/usr/bin/env python3
"""Work against precision: what each integrator setting costs and how far it
lands from the converged reference, on the built-in scenes.

Usage: work_precision.py BUILD_DIR [--scenes A,B] [--humidity 0,0.7,1]
                         [--settings NAME,...] [--grid G] [--duration S]
                         [--jobs N] [--out DIR] [--table FILE]

For every scene and humidity it runs the reference (symplectic Euler at
a quarter of the default step at 51 x 51, 2.5e-5 s) and every setting, each
`wetcloth run SCENE --threads 1` in a process of its own, and records:

  cpu_per_s   the run's CPU seconds (user + system, from the child's rusage)
              per simulated second;
  error       the worst, over the scene's metrics (METRICS below), of
              |value - reference| / max(|reference|, floor): a metric near
              zero is measured against its floor (2 mm, 5 cm^2, 0.01 N),
              not against itself.

A metric is the mean over the last fifth of the frames (a settled state,
robust to a flag's flutter), or for a hand or a rig the mean force over the
whole run (a peel test's reading, as ASTM D903 takes it: the dry rig's peak
is one stick-and-slip event, which scatters by 10 % between reference steps
4 % apart). Runs already in DIR (same command) are reused:
delete DIR to measure again. It writes DIR/work_precision.csv (a row per
scene, humidity and setting), a markdown table per setting (median CPU s per
simulated s, median and worst error over every scene and humidity, then each
case) to --table or standard output, and DIR/work_precision.png when matplotlib is present.
Exit codes: 0 ok, 2 bad arguments or a run that failed (named).
"""
import argparse
import csv
import json
import os
import resource
import shlex
import statistics
import subprocess
import sys
from concurrent.futures import ThreadPoolExecutor

# The settings measured. `reference` is what the others are compared with.
SETTINGS = {
    "reference": ["integrator.type=\"symplectic-euler\"", "integrator.dt=2.5e-5"],
    "symplectic-1.25e-5": ["integrator.type=\"symplectic-euler\"", "integrator.dt=1.25e-5"],
    "symplectic-5e-5": ["integrator.type=\"symplectic-euler\"", "integrator.dt=5e-5"],
    "symplectic-7.5e-5": ["integrator.type=\"symplectic-euler\"", "integrator.dt=7.5e-5"],
    "symplectic-1e-4": ["integrator.type=\"symplectic-euler\"", "integrator.dt=1e-4"],
}
LARGE = "integrator.dt=0.004166666666666667"  # 1/240 s
for strain in ("0.2", "0.1", "0.05", "0.025"):
    SETTINGS[f"implicit-{strain}"] = ["integrator.type=\"implicit-euler\"", LARGE,
                                      f"integrator.max_step_strain={strain}"]
for substeps in (10, 20, 40, 80):
    SETTINGS[f"xpbd-{substeps}"] = ["integrator.type=\"xpbd\"", LARGE,
                                    f"integrator.substeps={substeps}"]

# Each scene's metrics: (column of metrics.csv, how it is read, floor).
# "settled": mean over the last fifth of the frames; "mean": over the run.
MM, CM2, N = 2e-3, 5e-4, 0.01
METRICS = {
    "pull-straight": [("handle_height_m", "settled", MM), ("contact_area_m2", "settled", CM2),
                      ("base_diagonal_m", "settled", MM)],
    "pull-oblique": [("handle_force_n", "mean", N), ("contact_area_m2", "settled", CM2)],
    "pull-corner": [("handle_height_m", "settled", MM), ("contact_area_m2", "settled", CM2)],
    "drag-corner": [("handle_force_n", "mean", N), ("centroid_x_m", "settled", MM),
                    ("contact_area_m2", "settled", CM2)],
    "peel-rig": [("handle_force_n", "mean", N), ("lifted_area_m2", "settled", CM2)],
    "drape-ball": [("contact_area_m2", "settled", CM2), ("base_diagonal_m", "settled", MM),
                   ("outer_diagonal_m", "settled", MM)],
    "drape-disc": [("contact_area_m2", "settled", CM2), ("max_height_m", "settled", MM)],
    "drop-ball": [("contact_area_m2", "settled", CM2), ("max_height_m", "settled", MM)],
    "drop-table": [("contact_area_m2", "settled", CM2), ("outer_diagonal_m", "settled", MM)],
    "bowl-drape": [("contact_area_m2", "settled", CM2), ("max_height_m", "settled", MM)],
    "towel-rail": [("contact_area_m2", "settled", CM2), ("max_height_m", "settled", MM)],
    "mannequin-drape": [("contact_area_m2", "settled", CM2), ("max_height_m", "settled", MM)],
    "sleeve-pull": [("contact_area_m2", "settled", CM2), ("centroid_x_m", "settled", MM)],
    "hang": [("max_height_m", "settled", MM), ("outer_diagonal_m", "settled", MM)],
    "flag": [("max_height_m", "settled", MM), ("outer_diagonal_m", "settled", MM)],
    "cantilever": [("max_strain", "settled", 1e-4), ("outer_diagonal_m", "settled", MM)],
}


def fail(message):
    print(f"work_precision.py: error: {message}", file=sys.stderr)
    sys.exit(2)


def run(program, scene, humidity, setting, grid, duration, out):
    """One run into `out` (reused when its command is the same); returns its CPU s."""
    command = [program, "run", scene, "--humidity", str(humidity), "--threads", "1", "--quiet",
               "--out", out]
    if grid:
        command += ["--grid", str(grid)]
    if duration:
        command += ["--duration", str(duration)]
    for s in SETTINGS[setting]:
        command += ["--set", s]
    line = shlex.join(command)
    stamp = os.path.join(out, "work_precision.json")
    try:
        with open(stamp) as f:
            done = json.load(f)
        if done["command"] == line:
            return done["cpu_s"]
    except (OSError, ValueError, KeyError):
        pass
    child = subprocess.Popen(command, stdout=subprocess.DEVNULL, stderr=subprocess.PIPE, text=True)
    _, status, usage = os.wait4(child.pid, 0)
    child.returncode = os.waitstatus_to_exitcode(status)
    if child.returncode != 0:
        fail(f"{line}: exit code {child.returncode}: {child.stderr.read().strip()[:400]}")
    cpu = usage.ru_utime + usage.ru_stime
    with open(stamp, "w") as f:
        json.dump({"command": line, "cpu_s": cpu}, f)
    return cpu


def measure(folder, scene):
    with open(os.path.join(folder, "metrics.csv")) as f:
        rows = list(csv.DictReader(f))
    if not rows:
        fail(f"{folder}/metrics.csv: no frames")
    values = {}
    for key, how, _ in METRICS[scene]:
        column = [float(r[key]) for r in rows]
        if how == "settled":
            tail = column[len(column) - max(1, len(column) // 5):]
            values[key] = sum(tail) / len(tail)
        else:
            values[key] = sum(column) / len(column)
    with open(os.path.join(folder, "summary.json")) as f:
        simulated = json.load(f)["simulated_seconds"]
    return values, simulated


def main():
    parser = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    parser.add_argument("build")
    parser.add_argument("--scenes", default=",".join(METRICS))
    parser.add_argument("--humidity", default="0,0.7,1")
    # The accurate tier (symplectic-1e-4) and the live one (xpbd-10) first.
    parser.add_argument("--settings", default="symplectic-1e-4,xpbd-10,symplectic-5e-5,"
                        "implicit-0.1,implicit-0.05,xpbd-20,xpbd-40,xpbd-80")
    parser.add_argument("--grid", type=int, default=0)
    parser.add_argument("--duration", type=float, default=0)
    parser.add_argument("--jobs", type=int, default=os.cpu_count() or 1)
    parser.add_argument("--out", default="out/work-precision")
    parser.add_argument("--table")
    args = parser.parse_args()
    program = os.path.join(args.build, "wetcloth")
    if not os.access(program, os.X_OK):
        fail(f"{program}: no such program (build first)")
    scenes = args.scenes.split(",")
    settings = args.settings.split(",")
    for s in scenes:
        if s not in METRICS:
            fail(f"--scenes: unknown scene '{s}' (one of: {', '.join(METRICS)})")
    for s in settings:
        if s not in SETTINGS:
            fail(f"--settings: unknown setting '{s}' (one of: {', '.join(SETTINGS)})")
    try:
        humidities = [float(h) for h in args.humidity.split(",")]
    except ValueError:
        fail(f"--humidity: not a list of numbers: '{args.humidity}'")

    jobs = [(scene, h, setting) for scene in scenes for h in humidities
            for setting in ["reference"] + settings]
    folder = {j: os.path.join(args.out, j[0], f"w{j[1]:g}", j[2]) for j in jobs}
    for path in folder.values():
        os.makedirs(path, exist_ok=True)
    with ThreadPoolExecutor(max(1, args.jobs)) as pool:
        cpu = dict(zip(jobs, pool.map(
            lambda j: run(program, j[0], j[1], j[2], args.grid, args.duration, folder[j]), jobs)))

    rows = []
    for scene in scenes:
        floors = {key: floor for key, _, floor in METRICS[scene]}
        for h in humidities:
            ref, _ = measure(folder[(scene, h, "reference")], scene)
            for setting in ["reference"] + settings:
                values, simulated = measure(folder[(scene, h, setting)], scene)
                errors = {k: abs(values[k] - ref[k]) / max(abs(ref[k]), floors[k]) for k in ref}
                worst = max(errors, key=errors.get)
                rows.append({"scene": scene, "humidity": h, "setting": setting,
                             "cpu_per_s": cpu[(scene, h, setting)] / simulated,
                             "error": errors[worst], "worst_metric": worst,
                             **{k: values[k] for k in values}})
    os.makedirs(args.out, exist_ok=True)
    keys = list(dict.fromkeys(k for r in rows for k in r))
    with open(os.path.join(args.out, "work_precision.csv"), "w", newline="") as f:
        writer = csv.DictWriter(f, keys)
        writer.writeheader()
        writer.writerows(rows)

    lines = ["| setting | median CPU s per simulated s | median error | worst error | where |",
             "|---|---|---|---|---|"]
    summary = []
    for setting in ["reference"] + settings:
        mine = [r for r in rows if r["setting"] == setting]
        worst = max(mine, key=lambda r: r["error"])
        cost = statistics.median(r["cpu_per_s"] for r in mine)
        typical = statistics.median(r["error"] for r in mine)
        summary.append((setting, cost, worst["error"], typical))
        lines.append(f"| {setting} | {cost:.2f} | {100 * typical:.1f} % | {100 * worst['error']:.1f} % | "
                     f"{worst['scene']} ω={worst['humidity']:g} {worst['worst_metric']} |")
    lines.append("")
    lines.append("| scene | ω | " + " | ".join(settings) + " |")
    lines.append("|---|---|" + "---|" * len(settings))
    for scene in scenes:
        for h in humidities:
            cells = []
            for setting in settings:
                r = next(r for r in rows if (r["scene"], r["humidity"], r["setting"]) == (scene, h, setting))
                cells.append(f"{100 * r['error']:.1f} % ({r['cpu_per_s']:.2f} s)")
            lines.append(f"| {scene} | {h:g} | " + " | ".join(cells) + " |")
    text = "\n".join(lines) + "\n"
    if args.table:
        with open(args.table, "w") as f:
            f.write(text)
    else:
        sys.stdout.write(text)

    try:
        import matplotlib
        matplotlib.use("Agg")
        import matplotlib.pyplot as plt
    except ImportError:
        print("work_precision.py: no matplotlib: no plot", file=sys.stderr)
        return
    fig, ax = plt.subplots(figsize=(6, 4.5))
    for k, (setting, cost, error, typical) in enumerate(summary):
        if setting == "reference":
            continue
        colour = f"C{k % 10}"
        ax.scatter(cost, max(error, 1e-4) * 100, color=colour)
        ax.scatter(cost, max(typical, 1e-4) * 100, facecolors="none", edgecolors=colour)
        ax.annotate(setting, (cost, max(error, 1e-4) * 100), fontsize=8)
    ax.scatter([], [], color="grey", label="worst error")
    ax.scatter([], [], facecolors="none", edgecolors="grey", label="median error")
    ax.legend(fontsize=8)
    ax.axhline(5, color="grey", linestyle="--", linewidth=0.8)
    ax.set_xscale("log")
    ax.set_yscale("log")
    ax.set_xlabel("median CPU s per simulated s (one thread)")
    ax.set_ylabel("worst error against the reference, %")
    ax.set_title(f"work against precision: {len(scenes)} scenes, ω = {args.humidity}")
    fig.tight_layout()
    fig.savefig(os.path.join(args.out, "work_precision.png"), dpi=110)


if __name__ == "__main__":
    main()
