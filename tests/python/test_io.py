"""Maps and grids: NumPy in and out, file round trips, errors as quijibo.Error."""
import numpy as np
import pytest

import quijibo
from conftest import cli_error, cli_json, run_cli


def test_map_round_trip(tmp_path):
    m = quijibo.random_map(top=6, bottom=3, seed=11, ln_C=-0.25)
    assert m.top_roots.shape == (6, 4) and m.bottom_roots.shape == (3, 4)
    m.tau = 1.5
    m.beta = 0.75
    m.top_exponents = np.linspace(0.5, 2.0, 6)
    m.provenance = {"made_by": "test", "n": 3}
    path = tmp_path / "m.json"
    quijibo.write_map(m, str(path))
    back = quijibo.read_map(str(path))
    for name in ("top_roots", "bottom_roots", "top_exponents", "bottom_exponents", "variables"):
        assert np.array_equal(getattr(back, name), getattr(m, name)), name
    assert (back.ln_C, back.tau, back.beta) == (-0.25, 1.5, 0.75)
    assert back.provenance == {"made_by": "test", "n": 3}
    # The command line reads the file the module wrote.
    info = cli_json("map", "info", path)
    assert (info["top_roots"], info["bottom_roots"], info["tau"]) == (6, 3, 1.5)


def test_map_from_arrays_and_variables():
    top = np.array([[0.1, 0.2, 0.3, 0.0], [-0.5, 0.0, 0.25, 0.0]])
    m = quijibo.RationalMap(top_roots=top, bottom_roots=np.zeros((1, 3)) + 0.5, ln_C=0.3)
    assert np.array_equal(m.top_roots, top)
    assert np.array_equal(m.bottom_roots, [[0.5, 0.5, 0.5, 0.0]])  # (R, 3): points with k = 0
    assert np.array_equal(m.variables, [0.3, 1.0, 1.0, 1.0, 1.0, 1.0])
    m.variables = [0.0, 2.0, 1.0, 3.0, 4.0, 5.0]
    assert np.array_equal(m.top_exponents, [3.0, 4.0]) and m.bottom_exponents[0] == 5.0 and m.tau == 2.0
    with pytest.raises(ValueError):
        m.top_exponents[0] = 1.0  # read-only copy: assign the whole array
    doc = m.to_json()
    assert quijibo.RationalMap.from_json(doc).variables.tolist() == m.variables.tolist()


def test_grid_round_trip(tmp_path):
    values = np.arange(4 * 3 * 2, dtype=float).reshape(4, 3, 2)
    g = quijibo.Grid(values, min_corner=(-1.0, -0.5, 0.0), spacing=0.25)
    assert g.dims == [4, 3, 2]
    assert np.array_equal(g.values, values)
    # values[i, j, k] sits at min_corner + spacing * (i, j, k) + spacing / 2.
    assert np.allclose(g.cell_centers()[3, 2, 1], [-1.0 + 0.875, -0.5 + 0.625, 0.375])
    g.values[1, 2, 0] = -7.0  # a view: writes go to the grid
    path = tmp_path / "g.qgrid"
    quijibo.write_grid(g, str(path))
    back = quijibo.read_grid(str(path))
    assert back.values[1, 2, 0] == -7.0
    assert np.array_equal(back.values, g.values)
    assert back.min_corner == [-1.0, -0.5, 0.0] and back.spacing == 0.25 and back.quantity == "signed-distance"


def test_errors_carry_the_command_line_message(tmp_path):
    bad = tmp_path / "bad.json"
    bad.write_text('{"format": "quijibo-map", "version": 1, "ln_C": "x"}')
    with pytest.raises(quijibo.Error) as e:
        quijibo.read_map(str(bad))
    assert str(e.value) == cli_error("map", "info", bad)
    not_grid = tmp_path / "not.qgrid"
    not_grid.write_bytes(b"hello")
    with pytest.raises(quijibo.Error) as e:
        quijibo.read_grid(str(not_grid))
    assert "not a .qgrid file" in str(e.value)
    with pytest.raises(quijibo.Error, match="top roots and exponents differ"):
        quijibo.RationalMap(top_roots=np.zeros((2, 4)), top_exponents=[1.0])
    with pytest.raises(quijibo.Error):
        quijibo.Grid(np.zeros((2, 2, 2)), (0, 0, 0), spacing=-1.0)
    assert issubclass(quijibo.Error, Exception)
