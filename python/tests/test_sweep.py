"""wetcloth.sweep gives the table `wetcloth sweep` writes: on a Dask
LocalCluster of 2 workers, and on local processes."""
import csv
import subprocess

import numpy as np
import pytest

import wetcloth

VARY = {"cloth.humidity": [0.3, 0.5, 0.7], "material.stretch_stiffness": [100, 200]}
ARGS = ["--vary", "cloth.humidity=0.3,0.5,0.7", "--vary", "material.stretch_stiffness=100,200",
        "--grid", "9", "--duration", "0.05", "--no-plots", "--quiet"]


@pytest.fixture(scope="module")
def cli_table(cli, tmp_path_factory):
    out = tmp_path_factory.mktemp("sweep") / "s"
    subprocess.run([cli, "sweep", "pull-straight", *ARGS, "--out", str(out)], check=True)
    with open(out / "sweep.csv", newline="") as f:
        return list(csv.DictReader(f))


def same(table, rows):
    assert list(table.dtype.names) == list(rows[0].keys())
    assert len(table) == len(rows) == 6
    for got, want in zip(table, rows):
        for name in table.dtype.names:
            value = got[name]
            if isinstance(value, (float, np.floating)):
                assert value == float(want[name]), name
            else:
                assert str(value) == want[name] or float(value) == float(want[name]), name


def test_local_processes(cli_table):
    table = wetcloth.sweep("pull-straight", VARY, overrides={"run.duration": 0.05}, grid=9, processes=2)
    same(table, cli_table)
    assert [r["case"] for r in cli_table][:2] == ["omega_0.30_stretch_stiffness=100",
                                                   "omega_0.30_stretch_stiffness=200"]
    assert table["material.stretch_stiffness"].dtype == np.float64


def test_dask_local_cluster(cli_table):
    distributed = pytest.importorskip("distributed")
    with distributed.LocalCluster(n_workers=2, threads_per_worker=1, processes=True,
                                  dashboard_address=None) as cluster, distributed.Client(cluster) as client:
        table = wetcloth.sweep("pull-straight", VARY, client=client, overrides={"run.duration": 0.05}, grid=9)
    same(table, cli_table)


def test_bad_sweeps_raise():
    with pytest.raises(wetcloth.SceneError, match=r"cloth.humidity: value 2\.0 is out of range"):
        wetcloth.sweep("hang", {"cloth.humidity": [0.5, 2]})
    with pytest.raises(wetcloth.SceneError, match="0.5 is given twice"):
        wetcloth.sweep("hang", {"cloth.humidity": [0.5, 0.50]})
    with pytest.raises(TypeError):
        wetcloth.sweep("hang", {"cloth.humidity": 0.5})
    with pytest.raises(TypeError):
        wetcloth.sweep("hang", [("cloth.humidity", [0.5])])
