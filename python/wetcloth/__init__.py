"""wetcloth: wet cloth on contact surfaces, from Python.

    import wetcloth
    sim = wetcloth.Simulation("drop-table", humidity=0.7)
    sim.advance_to(0.5)
    sim.positions          # (n, 3) float64, C-contiguous, a read-only copy
    sim.positions_columns  # (3, n): a read-only view of the state, no copy
    sim.metrics()          # {"time_s": ..., "contact_area_m2": ..., ...}

scenes(), load_scene(name_or_path, **overrides), params() (the table of
`wetcloth params`), Simulation(scene, overrides=None, **keywords),
run(scene, out=..., export=[...], ...) to write a run's folder as `wetcloth
run` does (resume=DIR continues one), and sweep(scene, vary={...},
client=None, out=None) for parameter studies.

Overrides are given by dotted key ({"cloth.humidity": 0.7}) or keyword
(humidity=0.7, or cloth__humidity=0.7: "__" stands for the dots); grid=G is
the same cloth G particles wide. A bad key or value raises SceneError (a
ValueError) naming the key; a blow-up raises BlowUp naming the parameter to
look at. Arrays: positions and velocities are views without a copy (strides
(8, 8 n): the library holds x, y, z in columns; np.ascontiguousarray gives
C order); normals, uvs, rest_positions, triangles, in_contact, pressure and
adhesion are C-contiguous copies. advance_to releases the GIL while it steps.

A build's module runs in the interpreter it was built for (with its NumPy):
build/python/python, or PYTHONPATH=build/python with the interpreter that
the build printed. Another one fails at import, naming both.

sim.save(path) writes the whole state with its scene; Simulation.load(path)
continues it with the same bits as the run it came from.
"""
import sys


def _wrong_interpreter(error):
    """Why the module does not load here: the interpreter it was built for, if known."""
    try:
        from ._build import PYTHON
    except ImportError:
        PYTHON = None
    here = f"{sys.executable} (Python {sys.version.split()[0]})"
    if PYTHON is None:
        return f"wetcloth cannot load in {here}: {error}"
    return (f"wetcloth was built for {PYTHON}, and this is {here}: {error}. Run it with "
            f"that interpreter (PYTHONPATH=build/python {PYTHON}, or build/python/python)")


try:
    import numpy  # noqa: F401  (the module's arrays are NumPy's)
    from ._wetcloth import (BlowUp, OutputError, Scene, SceneError, Simulation, __version__,
                            load_scene, params, run, scenes)
except ImportError as _error:
    raise ImportError(_wrong_interpreter(_error)) from _error
from ._sweep import sweep

__all__ = ["BlowUp", "OutputError", "Scene", "SceneError", "Simulation", "load_scene", "params",
           "run", "scenes", "sweep", "__version__"]
