"""wetcloth.run writes the folder `wetcloth run` writes, byte for byte but for
summary.json's timings, through the library's one run; Ctrl-C stops it with a
checkpoint that `wetcloth run --resume` continues to the same bytes; and
wetcloth.sweep(out=...) writes the sweep's folder as `wetcloth sweep` does."""
import filecmp
import json
import os
import signal
import subprocess
import threading

import pytest

import wetcloth

TIMINGS = {"wall_seconds", "realtime_factor"}


def files(folder):
    """Every file under FOLDER, by its path relative to it."""
    found = []
    for root, _, names in os.walk(folder):
        found += [os.path.relpath(os.path.join(root, n), folder) for n in names]
    return sorted(found)


def same_folders(a, b, timings_differ=True):
    assert files(a) == files(b)
    for rel in files(a):
        if rel == "summary.json" and timings_differ:
            sa, sb = (json.loads((p / rel).read_text()) for p in (a, b))
            for s in (sa, sb):
                for k in TIMINGS:
                    s.pop(k)
            assert sa == sb
        else:
            assert filecmp.cmp(a / rel, b / rel, shallow=False), rel


def test_run_writes_the_cli_folder(cli, tmp_path):
    subprocess.run([cli, "run", "pull-straight", "--duration", "0.5", "--grid", "21", "--export",
                    "usd,pc2,vtk", "--quiet", "--out", str(tmp_path / "cli")], check=True)
    summary = wetcloth.run("pull-straight", duration=0.5, grid=21, export=["usd", "pc2", "vtk"],
                           out=tmp_path / "py")
    assert summary["status"] == "ok" and summary["simulated_seconds"] == pytest.approx(0.5)
    same_folders(tmp_path / "cli", tmp_path / "py")
    for kept in ("metrics.csv", "cloth.usda", "cloth.pc2", "cloth.pvd", "frames/frame_00000.obj",
                 "vtk/cloth_00012.vtp"):
        assert (tmp_path / "py" / kept).is_file(), kept
    assert json.loads((tmp_path / "py" / "summary.json").read_text()) == summary


def test_keyboard_interrupt_leaves_a_checkpoint_the_cli_resumes(cli, tmp_path):
    # 3 s of cloth: long enough that the SIGINT at 0.8 s of wall time finds
    # it under way on a fast machine (a 1 s run once ended before it).
    args = ["--duration", "3", "--grid", "21", "--export", "usd,pc2,vtk", "--quiet"]
    subprocess.run([cli, "run", "pull-straight", *args, "--out", str(tmp_path / "whole")], check=True)
    stopped = tmp_path / "stopped"
    # SIGINT to this process, as Ctrl-C sends it, once the run is under way.
    timer = threading.Timer(0.8, os.kill, (os.getpid(), signal.SIGINT))
    timer.start()
    try:
        with pytest.raises(KeyboardInterrupt):
            wetcloth.run("pull-straight", duration=3, grid=21, export="usd,pc2,vtk", out=stopped)
    finally:
        timer.cancel()
    summary = json.loads((stopped / "summary.json").read_text())
    assert summary["status"] == "interrupted" and summary["signal"] == "SIGINT"
    assert 0 < summary["simulated_seconds"] < 3
    assert (stopped / "checkpoint.state").is_file()
    subprocess.run([cli, "run", "--resume", str(stopped), "--quiet"], check=True)
    assert not (stopped / "checkpoint.state").exists()
    whole = json.loads((tmp_path / "whole" / "summary.json").read_text())
    resumed = json.loads((stopped / "summary.json").read_text())
    assert resumed.pop("resumed_at_s") == summary["simulated_seconds"]
    for s in (whole, resumed):
        for k in TIMINGS:
            s.pop(k)
    assert resumed == whole
    (stopped / "summary.json").unlink()
    (tmp_path / "whole" / "summary.json").unlink()
    same_folders(tmp_path / "whole", stopped, timings_differ=False)


def test_resume_from_python(cli, tmp_path):
    out = tmp_path / "r"
    subprocess.run([cli, "run", "hang", "--grid", "7", "--duration", "0.2", "--quiet",
                    "--checkpoint-every", "0.1", "--out", str(out)], check=True)
    # A whole run: nothing to resume, its summary.
    assert wetcloth.run(resume=out)["status"] == "ok"
    with pytest.raises(wetcloth.SceneError, match="would change it"):
        wetcloth.run("hang", resume=out)
    with pytest.raises(wetcloth.SceneError, match="humidity would change it"):
        wetcloth.run(resume=out, humidity=0.5)


def test_run_errors(tmp_path):
    (tmp_path / "afile").write_text("x")
    with pytest.raises(wetcloth.SceneError, match="exists and is not a folder"):
        wetcloth.run("hang", grid=5, duration=0.05, out=tmp_path / "afile")
    with pytest.raises(wetcloth.SceneError, match="a scene is needed"):
        wetcloth.run(out=tmp_path / "x")
    with pytest.raises(wetcloth.SceneError, match="no such scene|not a built-in"):
        wetcloth.run("no-such-scene", out=tmp_path / "y")
    with pytest.raises(wetcloth.SceneError, match=r"checkpoint_every: value -1\.0 is out of range"):
        wetcloth.run("hang", checkpoint_every=-1, out=tmp_path / "z")
    with pytest.raises(wetcloth.BlowUp, match="integrator.dt"):
        wetcloth.run("hang", duration=1, overrides={"integrator.dt": 2e-3}, out=tmp_path / "boom")
    assert json.loads((tmp_path / "boom" / "summary.json").read_text())["status"] == "blew up"


def test_sweep_writes_the_cli_folder(cli, tmp_path):
    args = ["--grid", "9", "--duration", "0.05", "--humidity", "0.3,0.7", "--quiet"]
    subprocess.run([cli, "sweep", "pull-straight", *args, "--no-plots", "--out", str(tmp_path / "cli")],
                   check=True)
    table = wetcloth.sweep("pull-straight", {"cloth.humidity": [0.3, 0.7]}, grid=9,
                           overrides={"duration": 0.05}, processes=1, out=tmp_path / "py")
    assert list(table["case"]) == ["omega_0.30", "omega_0.70"]
    for rel in ("sweep.csv", "cases.csv", "omega_0.30/sweep_row.csv", "omega_0.70/metrics.csv",
                "omega_0.70/frames/frame_00001.obj"):
        assert filecmp.cmp(tmp_path / "cli" / rel, tmp_path / "py" / rel, shallow=False), rel
    # The plots the command line makes, by the same script.
    assert (tmp_path / "py" / "fig7.png").is_file()
    # A folder of someone else's files is refused, as the command line refuses
    # it, and left as it was; force=True writes beside them.
    theirs = tmp_path / "theirs"
    theirs.mkdir()
    (theirs / "thesis.tex").write_text("mine")
    small = dict(grid=9, overrides={"duration": 0.02}, processes=1, plots=False)
    with pytest.raises(wetcloth.SceneError, match="holds files no wetcloth sweep wrote"):
        wetcloth.sweep("hang", {"cloth.humidity": [0.5]}, out=theirs, **small)
    assert [p.name for p in theirs.iterdir()] == ["thesis.tex"]
    wetcloth.sweep("hang", {"cloth.humidity": [0.5]}, out=theirs, force=True, **small)
    assert (theirs / "thesis.tex").read_text() == "mine" and (theirs / "sweep.csv").is_file()
    wetcloth.sweep("hang", {"cloth.humidity": [0.5]}, out=theirs, **small)  # its own folder now
