"""wetcloth.sweep: the cases of `wetcloth sweep SCENE --vary ...`, planned and
run by the library as the command line's are, from Python on a
dask.distributed client, or on local processes without one."""
import os
from concurrent.futures import ProcessPoolExecutor
from multiprocessing import get_context

import numpy as np

from . import _wetcloth


def _run(scene, sets, grid, out, extra, case):
    return _wetcloth._run_case(scene, sets, grid, out, extra, case)


def sweep(scene, vary, client=None, overrides=None, grid=None, processes=None, out=None,
          plots=True, force=False):
    """Runs SCENE over the cartesian product of `vary` ({"key": [values], ...},
    the first key outermost, as `wetcloth sweep --vary` orders the cases) and
    returns the table `wetcloth sweep` writes as sweep.csv: a NumPy structured
    array, a row per case (pandas.DataFrame(table) makes a data frame of it).

    overrides: {"key": value} for every case (duration=... as "run.duration");
    grid: the same cloth G particles wide. client: a dask.distributed Client
    to run the cases on (each case is one task); without one, local processes
    (`processes` at once, default all cores). Raises SceneError on a bad key or
    value before anything runs; a case that blows up has status "blew_up".

    out: a folder to write the sweep into as `wetcloth sweep --out` does: a
    run's outputs in out/<case>/ with its row (sweep_row.csv), cases.csv,
    sweep.csv and, unless plots=False, the plots (tools/plot_sweep.py; a
    failure of the plots raises RuntimeError once sweep.csv is written). The
    workers write into it: on a cluster, a folder they all see. A folder that
    holds files of no earlier wetcloth sweep raises SceneError, as `wetcloth
    sweep` refuses it, unless force=True.
    """
    if not isinstance(vary, dict) or not vary:
        raise TypeError("vary: expected a dict {\"key\": [values], ...}")
    if not isinstance(scene, (str, os.PathLike)):
        raise TypeError("scene: expected a built-in scene's name or a path (the workers load it)")
    scene = os.fspath(scene)
    base, base_grid = _wetcloth._override_texts(overrides)
    grid = grid if grid is not None else base_grid
    extra, cases, header, cases_csv = _wetcloth._plan_sweep(scene, list(vary.items()), base, grid)
    if out is not None:
        out = os.fspath(out)
        marks = ["cases.csv", "sweep.csv"] + [c["name"] for c in cases]
        _wetcloth._make_sweep_folder(out, marks, force)
        _wetcloth._write_shared(os.path.join(out, "cases.csv"), cases_csv)
    jobs = [(scene, base + c["sets"], grid, out, extra, c) for c in cases]
    if client is not None:
        futures = client.map(_run, *zip(*jobs), pure=False)
        results = client.gather(futures)
    elif len(jobs) == 1 or processes == 1:
        results = [_run(*j) for j in jobs]
    else:
        with ProcessPoolExecutor(max_workers=processes or os.cpu_count(),
                                 mp_context=get_context("spawn")) as pool:
            results = list(pool.map(_run, *zip(*jobs)))
    if out is not None:
        _wetcloth._write_file(os.path.join(out, "sweep.csv"), header + "".join(r["row"] for r in results))
        failed = _wetcloth._plot_sweep(out) if plots else ""
        if failed:
            raise RuntimeError(f"the plots failed ({failed}); sweep.csv is written")
    columns = _wetcloth._metrics_columns()
    names = (["case"] + list(extra) + ["air_model", "humidity", "status", "peak_deficit_pa",
                                        "frame_peak_deficit_pa", "time_to_5cm_s"] + columns)
    rows = []
    for c, r in zip(cases, results):
        rows.append(tuple([c["name"]] + list(c["columns"]) +
                          [c["air_model"], c["humidity"], r["status"], r["peak_deficit_pa"],
                           r["frame_peak_deficit_pa"], r["time_to_5cm_s"]] +
                          [r["final"][k] for k in columns]))
    def numbers(i):  # a varied key's column is numbers where every value is one
        try:
            [float(row[i]) for row in rows]
            return True
        except ValueError:
            return False

    texts = {0, len(extra) + 1, len(extra) + 3} | {1 + k for k in range(len(extra)) if not numbers(1 + k)}
    dtype = [(n, object if i in texts else np.float64) for i, n in enumerate(names)]
    return np.array([tuple(v if i in texts else float(v) for i, v in enumerate(row)) for row in rows],
                    dtype=dtype)
