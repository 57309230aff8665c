"""The examples in examples/python run (headless matplotlib, a small grid,
a short time) and write their pictures."""
import os
import subprocess
import sys

import pytest

EXAMPLES = {
    "flag.py": ["--grid", "9", "--duration", "0.1", "--fps", "20", "--out", "flag.gif"],
    "fig7.py": ["--humidity", "0.3,0.8", "--grid", "9", "--duration", "0.1", "--processes", "1", "--out", "fig7.png"],
    "pressure_live.py": ["--grid", "9", "--duration", "0.1", "--every", "0.02", "--out", "pressure.png"],
}


@pytest.mark.parametrize("name", sorted(EXAMPLES))
def test_example_runs(source_dir, tmp_path, name):
    args = EXAMPLES[name]
    env = dict(os.environ, MPLBACKEND="Agg")
    script = os.path.join(source_dir, "examples", "python", name)
    r = subprocess.run([sys.executable, script, *args], cwd=tmp_path, env=env, capture_output=True, text=True,
                       timeout=120)
    assert r.returncode == 0, r.stderr
    out = tmp_path / args[-1]
    assert out.stat().st_size > 1000
    assert "wrote" in r.stdout
