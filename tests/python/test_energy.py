"""The energy: the same double as `quijibo energy`, to the last bit."""
import numpy as np
import pytest

import quijibo
from conftest import cli_error, cli_json


@pytest.mark.parametrize("args", [
    {},
    {"evaluator": "cached"},
    {"evaluator": "cached", "precision": "float"},
    {"weights": "balanced", "alpha": 7.5, "resolution": 9},
    {"mode": "variable"},
])
def test_energy_equals_the_command_line(tiny_case, args):
    cli_args = ["energy", "-t", tiny_case["target"], "-m", tiny_case["map"]]
    names = {"evaluator": "--evaluator", "precision": "--precision", "weights": "--weights", "alpha": "--alpha",
             "resolution": "--resolution", "mode": "--mode"}
    for k, v in args.items():
        cli_args += [names[k], "loglinear" if v == "dense" else v]
    report = cli_json(*cli_args)
    r = quijibo.energy(tiny_case["rational_map"], tiny_case["grid"], **args)
    assert r.energy.hex() == float(report["energy"]).hex()
    g = report["gradient"]
    expected = [g["ln_C"], g["tau"], g["beta"]] + g.get("top", []) + g.get("bottom", [])
    assert r.gradient.tolist() == expected
    assert len(r.gradient) == (3 if args.get("mode") == "variable" else tiny_case["rational_map"].variable_count)
    assert r.report["cells"] == report["cells"]


def test_energy_gradient_is_the_derivative(tiny_case):
    m = tiny_case["rational_map"].copy()
    grid = tiny_case["grid"]
    r = quijibo.energy(m, grid)
    x = m.variables.copy()
    h = 1e-6
    for k in (0, 1, 4):
        x1 = x.copy()
        x1[k] += h
        m.variables = x1
        up = quijibo.energy(m, grid, gradient=False).energy
        x1[k] -= 2 * h
        m.variables = x1
        down = quijibo.energy(m, grid, gradient=False).energy
        assert abs((up - down) / (2 * h) - r.gradient[k]) < 1e-5 * max(1.0, abs(r.gradient[k]))


def test_energy_errors(tiny_case):
    m, grid = tiny_case["rational_map"], tiny_case["grid"]
    with pytest.raises(quijibo.Error) as e:
        quijibo.energy(m, grid, precision="float128")
    assert str(e.value) == cli_error("energy", "-t", tiny_case["target"], "-m", tiny_case["map"], "-p", "float128")
    with pytest.raises(quijibo.Error, match='energy: /evaluator: expected one of "loglinear", "dense", "cached", found "fast"'):
        quijibo.energy(m, grid, evaluator="fast")
    with pytest.raises(quijibo.Error, match="weight"):
        quijibo.energy(m, grid, weights="heavy")
