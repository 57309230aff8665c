"""The module's API: scenes, parameters, a Simulation, its arrays, and bad
input raising Python exceptions (never a crash)."""
import os
import subprocess
import sys
import threading

import numpy as np
import pytest

import wetcloth

SMALL = {"grid": 9}  # a 9 x 9 cloth: quick


def test_scenes_and_params():
    scenes = wetcloth.scenes()
    assert "drop-table" in scenes and "flag" in scenes
    keys = [p["key"] for p in wetcloth.params()]
    assert "cloth.humidity" in keys and "handle.*.force" in keys
    row = next(p for p in wetcloth.params() if p["key"] == "cloth.humidity")
    assert row["range"] == "[0, 1]" and row["unit"]


def test_load_scene_overrides():
    s = wetcloth.load_scene("pull-straight", {"cloth.humidity": 0.3}, air__model="sealed")
    assert s.name == "pull-straight"
    assert s.get("cloth.humidity") == 0.3 and s.get("air.model") == "sealed"
    assert s.get("cloth.resolution") == [51, 51]
    assert wetcloth.load_scene("pull-straight", grid=11).get("cloth.resolution") == [11, 11]
    assert "humidity = 0.3" in s.toml()
    sim = wetcloth.Simulation(s, humidity=0.9)  # a Scene, overridden again
    assert sim.get("cloth.humidity") == 0.9 and sim.get("air.model") == "sealed"


def test_step_arrays_and_metrics():
    sim = wetcloth.Simulation("drop-table", **SMALL)
    n = sim.n
    assert sim.grid == (9, 9) and n == 81
    x = sim.positions
    assert x.shape == (n, 3) and x.dtype == np.float64 and not x.flags.writeable
    assert x.flags.c_contiguous and x.strides == (24, 8)
    columns = sim.positions_columns
    assert columns.shape == (3, n) and columns.flags.c_contiguous and not columns.flags.writeable
    assert np.array_equal(columns.T, x)
    z0 = x[:, 2].copy()
    sim.step()
    assert sim.steps == 1 and sim.time == pytest.approx(sim.dt)
    sim.advance_to(0.05)
    assert sim.time == pytest.approx(0.05)
    assert (columns[2] < z0).all()  # the view follows the state: the cloth falls
    assert (x[:, 2] == z0).all()  # the copy does not
    assert np.array_equal(sim.positions, columns.T)
    assert sim.velocities.shape == (n, 3) and (sim.velocities[:, 2] < 0).all()
    assert np.array_equal(sim.velocities_columns.T, sim.velocities)
    assert np.shares_memory(columns, sim.positions_columns)
    tri = sim.triangles
    assert tri.shape == (2 * 8 * 8, 3) and tri.min() == 0 and tri.max() == n - 1
    assert sim.in_contact.dtype == bool and sim.in_contact.shape == (n,)
    assert sim.pressure.shape == (n,) and sim.adhesion.shape == (n,)
    m = sim.metrics()
    assert list(m) == wetcloth._wetcloth._metrics_columns()
    assert m["time_s"] == sim.time and m["centroid_x_m"] == pytest.approx(x[:, 0].mean(), abs=1e-9)
    sim.advance_to(0.3)  # on the table by now
    assert sim.in_contact.any() and sim.metrics()["contact_area_m2"] > 0


def test_set_between_steps_and_handles():
    sim = wetcloth.Simulation("pull-straight", humidity=0.5, **SMALL)
    assert sim.handles["pull"]["type"] == "force"
    assert sim.handles["pull"]["force"] == (0.0, 0.0, 1.0)
    assert len(sim.handles["pull"]["particles"]) > 0
    sim.advance_to(0.01)
    sim.set("cloth.humidity", 0.8)
    sim.set("handle.pull.force", np.array([0.0, 0.0, 2.0]))
    assert sim.get("cloth.humidity") == 0.8 and sim.handles["pull"]["force"] == (0.0, 0.0, 2.0)
    sim.advance_to(0.02)
    assert sim.time == pytest.approx(0.02)


def test_obstacle_keys_get_and_set():
    # obstacle.NAME.KEY as handle.NAME.KEY: read, set between steps (the
    # obstacle is rebuilt where it now is), and named in errors.
    sim = wetcloth.Simulation("towel-rail", {"run.duration": 0.1}, grid=9)
    assert sim.get("obstacle.rail.translate") == [0.0, 0.0, 0.6]
    assert sim.get("obstacle.rail.mesh") == "meshes/rail.obj"
    sim.advance_to(0.05)
    sim.set("obstacle.rail.translate", [0.0, 0.0, 0.5])
    assert sim.get("obstacle.rail.translate") == [0.0, 0.0, 0.5]
    sim.advance_to(0.1)
    with pytest.raises(wetcloth.SceneError, match="obstacle.nope.scale: the scene has no such obstacle"):
        sim.get("obstacle.nope.scale")
    with pytest.raises(wetcloth.SceneError, match="obstacle.nope: the scene has no such obstacle"):
        wetcloth.Simulation("towel-rail", {"obstacle.nope.scale": [1, 1, 1]}, grid=9)
    # A Scene loaded once keeps where its meshes are.
    scene = wetcloth.load_scene("towel-rail")
    assert wetcloth.Simulation(scene, {"obstacle.rail.translate": [0, 0, 0.55]}, grid=9).get(
        "obstacle.rail.translate") == [0.0, 0.0, 0.55]


def test_material_preset_is_a_key():
    # By name, over a loaded Scene (whose resolved values would hide it) and
    # set between steps: each sets the preset's values; a name that is none
    # raises naming the key.
    sim = wetcloth.Simulation("drop-table", {"material.preset": "silk"}, **SMALL)
    assert sim.get("material.preset") == "silk" and sim.get("cloth.areal_density") == 0.061
    scene = wetcloth.load_scene("drop-table", {"friction.mu": 0.9})
    denim = wetcloth.Simulation(scene, {"material.preset": "denim", "air.d_delta": 0.002}, **SMALL)
    assert denim.get("cloth.areal_density") == 0.4 and denim.get("air.d_delta") == 0.002
    sim.advance_to(0.01)
    sim.set("material.preset", "denim")
    assert sim.get("material.preset") == "denim" and sim.get("cloth.areal_density") == 0.4
    sim.advance_to(0.02)
    with pytest.raises(wetcloth.SceneError, match="material.preset: 'wool' is not one of"):
        wetcloth.Simulation("drop-table", {"material.preset": "wool"}, **SMALL)


def test_normals_uvs_and_rest_positions():
    sim = wetcloth.Simulation("hang", **SMALL)
    for name, columns in (("normals", 3), ("uvs", 2), ("rest_positions", 3)):
        a = getattr(sim, name)
        assert a.shape == (81, columns) and a.dtype == np.float64 and a.flags["C_CONTIGUOUS"], name
    assert np.allclose(np.linalg.norm(sim.normals, axis=1), 1)
    assert np.allclose(sim.uvs[[0, 8, 80]], [[0, 0], [1, 0], [1, 1]])
    start = sim.positions.copy()
    assert np.allclose(sim.rest_positions, start)
    sim.advance_to(0.05)
    assert np.allclose(sim.rest_positions, start) and not np.allclose(sim.positions, start)


def test_positions_assignment():
    sim = wetcloth.Simulation("hang", **SMALL)
    x = sim.positions.copy()
    x[:, 0] += 0.01
    sim.positions = x
    assert (sim.positions == x).all()
    with pytest.raises(wetcloth.SceneError, match=r"positions: expected shape \(81, 3\), got \(81, 2\)"):
        sim.positions = np.zeros((81, 2))
    with pytest.raises(wetcloth.SceneError, match="velocities"):
        sim.velocities = np.zeros(243)
    with pytest.raises(TypeError):
        sim.positions = "no"


@pytest.mark.parametrize("overrides, text", [
    ({"cloth.humidty": 0.5}, "cloth.humidty: unknown key"),
    ({"cloth.humidity": 1.5}, r"cloth.humidity: value 1.5 is out of range \[0, 1\]"),
    ({"cloth.humidity": "wet"}, "cloth.humidity: expected a number"),
    ({"cloth.resolution": [10]}, "cloth.resolution: expected an array of 2"),
    ({"cloth.resolution": np.zeros((2, 2))}, "cloth.resolution: expected a flat list"),
    ({"air.model": "leaky"}, "air.model: 'leaky' is not one of"),
    ({"handle.nope.force": [0, 0, 1]}, "handle.nope: the scene has no such handle"),
    ({"cloth.humidity\n[x]": 1}, "not a parameter key"),
    ({"integrator.dt": float("nan")}, "integrator.dt: value is not finite|out of range"),
])
def test_bad_values_raise_scene_error(overrides, text):
    with pytest.raises(wetcloth.SceneError, match=text):
        wetcloth.Simulation("pull-straight", overrides, **SMALL)
    assert issubclass(wetcloth.SceneError, ValueError)


def test_bad_types_and_scenes():
    with pytest.raises(TypeError, match="cloth.humidity: a value of type dict"):
        wetcloth.Simulation("hang", {"cloth.humidity": {}})
    with pytest.raises(TypeError):
        wetcloth.Simulation(42)
    with pytest.raises(TypeError):
        wetcloth.Simulation("hang", [("cloth.humidity", 0.5)])
    with pytest.raises(TypeError):
        wetcloth.Simulation("hang", grid="9")
    with pytest.raises(wetcloth.SceneError, match="not a file and not a built-in scene"):
        wetcloth.Simulation("no-such-scene")
    with pytest.raises(wetcloth.SceneError, match="grid: .*each side must be"):
        wetcloth.Simulation("hang", grid=1)
    sim = wetcloth.Simulation("hang", **SMALL)
    with pytest.raises(TypeError):
        sim.advance_to("soon")
    for t in (float("nan"), float("inf"), -1.0, 1e300):
        with pytest.raises(wetcloth.SceneError, match="advance_to"):
            sim.advance_to(t)
    with pytest.raises(wetcloth.SceneError, match=r"cloth.humidity: value 2\.0 is out of range"):
        sim.set("cloth.humidity", 2)
    with pytest.raises(wetcloth.SceneError, match="the grid cannot change"):
        sim.set("cloth.resolution", [11, 11])
    with pytest.raises(wetcloth.SceneError, match="unknown key"):
        sim.get("cloth.colour")
    with pytest.raises(wetcloth.SceneError, match="not a wetcloth checkpoint"):
        wetcloth.Simulation.load(__file__)
    sim.step()  # still usable after every error above
    assert sim.steps == 1


def test_save_and_load_continue_with_the_same_bits(tmp_path):
    sim = wetcloth.Simulation("drape-ball", **SMALL)
    sim.advance_to(0.2)
    sim.save(str(tmp_path / "ball.state"))
    sim.advance_to(0.3)
    again = wetcloth.Simulation.load(str(tmp_path / "ball.state"))
    assert again.time == pytest.approx(0.2)
    again.advance_to(0.3)
    assert np.array_equal(again.positions, sim.positions)
    assert np.array_equal(again.velocities, sim.velocities)
    assert again.metrics() == sim.metrics()


def test_save_replaces_a_file_and_nothing_else(tmp_path):
    sim = wetcloth.Simulation("hang", **SMALL)
    (tmp_path / "old.state").write_text("an older file")
    sim.save(str(tmp_path / "old.state"))  # a file: replaced
    assert wetcloth.Simulation.load(str(tmp_path / "old.state")).steps == 0
    (tmp_path / "folder").mkdir()
    (tmp_path / "kept").write_text("kept")
    (tmp_path / "link").symlink_to(tmp_path / "kept")
    os.mkfifo(tmp_path / "fifo")
    for name in ("folder", "link", "fifo"):
        with pytest.raises(wetcloth.SceneError, match="not a regular file"):
            sim.save(str(tmp_path / name))
    assert (tmp_path / "kept").read_text() == "kept" and (tmp_path / "link").is_symlink()


def test_odd_arguments_raise_scene_error():
    with pytest.raises(wetcloth.SceneError, match="grid: 18446744073709551616 is not"):
        wetcloth.Simulation("hang", grid=2**64)
    with pytest.raises(wetcloth.SceneError, match=r"holds a NUL character"):
        wetcloth.load_scene("\x00")
    with pytest.raises(wetcloth.SceneError, match=r".+"):
        wetcloth.Simulation("a\x00b.toml")
    sim = wetcloth.Simulation("hang", **SMALL)
    sim.advance_to(0.01)
    with pytest.raises(wetcloth.SceneError, match="advance_to: t = 0.005 s is before"):
        sim.advance_to(0.005)
    sim.advance_to(0.01)  # where it is: nothing to do
    assert sim.time == pytest.approx(0.01)


def test_an_interpreter_without_numpy_is_told_which_one(tmp_path):
    """Another python3 first on the PATH (pyenv's, without NumPy) fails at the
    import naming the interpreter the module was built for."""
    (tmp_path / "numpy").mkdir()
    (tmp_path / "numpy" / "__init__.py").write_text("raise ImportError(\"No module named 'numpy'\")\n")
    env = dict(os.environ, PYTHONPATH=os.pathsep.join([str(tmp_path), os.environ["PYTHONPATH"]]))
    r = subprocess.run([sys.executable, "-c", "import wetcloth"], env=env, capture_output=True,
                       text=True)
    assert r.returncode != 0
    assert "wetcloth was built for " in r.stderr and "No module named 'numpy'" in r.stderr, r.stderr
    assert "build/python/python" in r.stderr
    wrapper = os.path.join(os.environ["PYTHONPATH"].split(os.pathsep)[0], "python")
    if os.access(wrapper, os.X_OK):  # a build's, not an installed module
        out = subprocess.run([wrapper, "-c", "import wetcloth; print(wetcloth.__version__)"],
                             capture_output=True, text=True, check=True).stdout
        assert out.strip() == wetcloth.__version__


def test_blow_up_names_the_parameter():
    sim = wetcloth.Simulation("hang", {"integrator.dt": 0.004}, **SMALL)
    with pytest.raises(wetcloth.BlowUp, match="integrator.dt"):
        sim.advance_to(1.0)
    assert issubclass(wetcloth.BlowUp, RuntimeError)
    with pytest.raises(wetcloth.BlowUp):  # and stays blown up
        sim.step()


def test_advance_to_releases_the_gil():
    """While advance_to runs in one thread, another runs Python: it finds the
    simulation busy (which it could not see if the GIL were held)."""
    sim = wetcloth.Simulation("drop-table", grid=15)
    done = threading.Event()
    worker = threading.Thread(target=lambda: (sim.advance_to(0.2), done.set()))
    worker.start()
    seen_busy = False
    while not done.is_set() and worker.is_alive():
        try:
            sim.step()
        except RuntimeError as e:
            assert "busy" in str(e)
            seen_busy = True
            break
    worker.join()
    assert seen_busy
    assert sim.time >= 0.2


def test_humidity_field_reads_and_sets():
    sim = wetcloth.Simulation("wet-patch", **SMALL)
    w = sim.humidity
    assert w.shape == (sim.n,) and w.max() == 1.0 and w.min() == 0.0
    half = np.where(np.arange(sim.n) % 9 < 4, 1.0, 0.0)
    sim.humidity = half
    assert (sim.humidity == half).all()
    m = sim.metrics()
    assert m["humidity_max"] == 1.0 and m["humidity_min"] == 0.0 and m["water_kg"] > 0
    sim.advance_to(0.05)  # wicking spreads it, keeping the water
    assert sim.metrics()["water_kg"] == pytest.approx(m["water_kg"], rel=1e-12)
    with pytest.raises(ValueError):
        sim.humidity = np.full(sim.n, 1.5)
    with pytest.raises(ValueError):
        sim.humidity = np.zeros(3)
