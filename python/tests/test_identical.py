"""The Python and C++ results of the same scene are bit-identical: every
metric of every frame of `wetcloth run` (metrics.csv keeps each value's
shortest exact text, and the time as the frame's decimal time, steps x dt
to 12 digits) and the peak deficit at any step (summary.json)."""
import csv
import json
import subprocess

import pytest

import wetcloth


@pytest.mark.parametrize("scene, grid, duration", [("drop-table", 13, 0.2), ("pull-straight", 11, 0.15)])
def test_python_matches_cli(cli, tmp_path, scene, grid, duration):
    out = tmp_path / scene
    subprocess.run([cli, "run", scene, "--grid", str(grid), "--duration", str(duration), "--quiet",
                    "--out", str(out)], check=True)
    with open(out / "metrics.csv", newline="") as f:
        rows = [{k: float(v) for k, v in r.items()} for r in csv.DictReader(f)]
    assert len(rows) > 3
    sim = wetcloth.Simulation(scene, grid=grid, duration=duration)
    for row in rows:
        sim.advance_to(row["time_s"])
        m = sim.metrics()
        assert m.pop("time_s") == pytest.approx(row.pop("time_s"), rel=1e-12, abs=0)
        assert m == row  # exact: the same doubles
    summary = json.loads((out / "summary.json").read_text())
    assert sim.peak_deficit == summary["peak_pressure_deficit_pa"]
    assert sim.steps == summary["steps"]
