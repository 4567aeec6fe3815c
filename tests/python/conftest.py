"""Fixtures of the Python tests: the module (PYTHONPATH=<build>/python) and the command line binary.

ctest sets QUIJIBO_BINARY and QUIJIBO_SOURCE_DIR; run by hand from the source folder,
    PYTHONPATH=build/python /usr/bin/python3 -m pytest tests/python
finds build/experiments/quijibo.
"""
import json
import os
import pathlib
import subprocess

import pytest

SOURCE_DIR = pathlib.Path(os.environ.get("QUIJIBO_SOURCE_DIR", pathlib.Path(__file__).resolve().parents[2]))
BINARY = pathlib.Path(os.environ.get("QUIJIBO_BINARY", SOURCE_DIR / "build" / "experiments" / "quijibo"))

# A whole experiment that runs in seconds: a sphere on 12^3 cells, a random 5 + 4 root map, a short
# schedule, a coarse mesh and no pictures (`quijibo run` and quijibo.run read it alike).
TINY_EXPERIMENT = {
    "name": "tiny",
    "target": {"analytic": "sphere", "resolution": 12},
    "initial": {"kind": "random", "top": 5, "bottom": 4},
    "optimizer": {"schedule": "12(VF)", "max_iterations": {"V": 5, "F": 10}},
    "mesh": {"resolution": 24, "iterations": 2, "vdb": False},
    "pictures": {"enabled": False},
}


def run_cli(*args, check=True):
    """Runs `quijibo --quiet <args>`; returns the CompletedProcess (text)."""
    p = subprocess.run([str(BINARY), "--quiet", *map(str, args)], capture_output=True, text=True)
    if check and p.returncode != 0:
        raise AssertionError(f"quijibo {' '.join(map(str, args))} failed ({p.returncode}): {p.stderr}")
    return p


def cli_error(*args):
    """The message `quijibo <args>` prints after 'quijibo: error: ' (exit code 1)."""
    p = run_cli(*args, check=False)
    assert p.returncode == 1, (p.returncode, p.stderr)
    line = p.stderr.strip().splitlines()[-1]
    prefix = "quijibo: error: "
    assert line.startswith(prefix), line
    return line[len(prefix):]


def cli_json(*args):
    return json.loads(run_cli(*args).stdout)


@pytest.fixture(scope="session")
def source_dir():
    return SOURCE_DIR


@pytest.fixture(scope="session")
def tiny_case(tmp_path_factory):
    """A sphere target on 12^3 cells and a random map of 5 + 4 roots centred on it, as files."""
    import quijibo

    tmp_path = tmp_path_factory.mktemp("tiny")
    target = tmp_path / "sphere.qgrid"
    map_path = tmp_path / "map.json"
    run_cli("target", "sphere:radius=1", "-r", 12, "-o", target)
    run_cli("map", "random", "--top", 5, "--bottom", 4, "--seed", 7, "--center-on", target, "-o", map_path)
    # Tests copy the map and grid before changing them.
    return {"target": target, "map": map_path, "grid": quijibo.read_grid(str(target)),
            "rational_map": quijibo.read_map(str(map_path))}
