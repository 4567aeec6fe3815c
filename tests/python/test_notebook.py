"""examples/notebook.py on the results folder of a tiny `quijibo run`."""
import json
import os
import subprocess
import sys

import quijibo
from conftest import SOURCE_DIR, TINY_EXPERIMENT, run_cli


def test_notebook_plots_and_remeshes(tmp_path):
    experiment = tmp_path / "tiny.json"
    experiment.write_text(json.dumps(TINY_EXPERIMENT))
    results = tmp_path / "results"
    run_cli("run", experiment, "--out", results)
    out = tmp_path / "notebook"
    env = dict(os.environ, QUIJIBO_RESULTS=str(results), QUIJIBO_NOTEBOOK_OUT=str(out), MPLBACKEND="Agg")
    p = subprocess.run([sys.executable, str(SOURCE_DIR / "examples" / "notebook.py")], env=env, capture_output=True,
                       text=True)
    assert p.returncode == 0, p.stderr
    assert (out / "convergence.png").stat().st_size > 10000
    # The run meshed n = 2; the notebook n = 1, the same map at the same resolution.
    v, f = quijibo.read_mesh(str(out / "julia-n1.ply"))
    expected = quijibo.mesh(quijibo.read_map(str(results / "optimized" / "map.json")), 24, 1)
    assert len(v) == len(expected.vertices) and len(f) == len(expected.faces)
    assert "n = 1:" in p.stdout
    assert "intricate: " in p.stdout  # meshed, or refused with the reason
