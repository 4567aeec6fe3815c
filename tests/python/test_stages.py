"""The pipeline's stages from Python: the same results as the command line's."""
import json

import numpy as np
import pytest

import quijibo
from conftest import SOURCE_DIR, TINY_EXPERIMENT, cli_json, run_cli

BUNNY = SOURCE_DIR / "data" / "bunny.obj"


def test_target_equals_quijibo_target(tmp_path):
    path = tmp_path / "t.qgrid"
    run_cli("target", "torus", "-r", 10, "-o", path)
    expected = quijibo.read_grid(str(path))
    t = quijibo.target(analytic="torus", resolution=10)
    assert np.array_equal(t.grid.values, expected.values)
    assert t.grid.min_corner == expected.min_corner and t.grid.spacing == expected.spacing
    with pytest.raises(quijibo.Error, match="target: /resolutoin: unknown key"):
        quijibo.target(analytic="torus", resolutoin=10)


def test_initial_guess_equals_quijibo_monopoles(tmp_path):
    settings = {"resolution": 24, "roots": 40, "max_roots": 40}
    guess = quijibo.initial_guess(str(BUNNY), **settings)
    m, grid = guess
    out = tmp_path / "cli"
    run_cli("monopoles", BUNNY, "-o", out, "-r", 24, "--roots", 40, "--max-roots", 40)
    expected = quijibo.read_map(str(out / "map.json"))
    for name in ("top_roots", "bottom_roots", "variables"):
        assert np.array_equal(getattr(m, name), getattr(expected, name)), name
    assert np.array_equal(grid.values, quijibo.read_grid(str(out / "target.qgrid")).values)
    assert guess.summary["start"]["inverted"] is False
    assert guess.picture.ndim == 3 and guess.picture.shape[2] == 3
    # The frame maps the bunny's own coordinates into the fractal frame.
    bunny, _ = quijibo.read_mesh(str(BUNNY))
    assert np.allclose(guess.frame.fractal_to_user(guess.frame.user_to_fractal(bunny)), bunny)


def test_modulus_and_portal_equal_the_commands(tmp_path):
    product = quijibo.modulus("sphere", output={"resolution": 24})
    assert product.kind == "ply"
    report = cli_json("modulus", "sphere", "-o", tmp_path / "m.ply", "-r", 24)
    v, f = quijibo.read_mesh(str(tmp_path / "m.ply"))
    assert product.mesh.vertices.shape == v.shape and product.mesh.faces.shape == f.shape
    koch = quijibo.portal(koch=True, output={"png_size": 48}, out=str(tmp_path / "k.png"))
    assert koch.kind == "png" and koch.image.shape == (48, 48, 3)
    import matplotlib.image
    written = matplotlib.image.imread(str(tmp_path / "k.png"))
    assert np.array_equal(np.round(written[:, :, :3] * 255).astype(np.uint8), koch.image)
    run_cli("portal", "--koch", "-o", tmp_path / "k-cli.png", "--png-size", 48)
    assert (tmp_path / "k-cli.png").read_bytes() == (tmp_path / "k.png").read_bytes()


def test_run_equals_quijibo_run(tmp_path):
    path = tmp_path / "tiny.json"
    path.write_text(json.dumps(TINY_EXPERIMENT))
    summary = quijibo.run(str(path), out=str(tmp_path / "py"), quiet=True)
    assert {s["status"] for s in summary["stages"]} == {"ran"}
    run_cli("run", path, "--out", tmp_path / "cli")
    for f in ("optimized/map.json", "initial/map.json"):
        assert (tmp_path / "py" / f).read_bytes() == (tmp_path / "cli" / f).read_bytes(), f
    # The document itself: every stage reused.
    again = quijibo.run(TINY_EXPERIMENT, out=str(tmp_path / "py"), quiet=True)
    assert {s["status"] for s in again["stages"]} == {"reused"}
    assert quijibo.run(TINY_EXPERIMENT, check=True)["resolved"]["optimizer"][0]["schedule"]
    bad = dict(TINY_EXPERIMENT, mesh={"resolutoin": 24})
    with pytest.raises(quijibo.Error, match=r'experiment: /mesh/resolutoin: unknown key'):
        quijibo.run(bad, check=True)


def test_julia_of_a_map_kind_equals_quijibo_julia(tmp_path):
    """Any map kind from Python, as `quijibo julia` makes it: the basilica (q^2 - 1) as a picture and a mesh."""
    basilica = {"kind": "polynomial", "c": [-1.0, 0.0]}
    path = tmp_path / "basilica.json"
    path.write_text(json.dumps(basilica))
    image = quijibo.julia(basilica, output={"png_size": 64}, out=str(tmp_path / "b.png"))
    assert image.kind == "png" and image.image.shape == (64, 64, 3)
    run_cli("julia", path, "-o", tmp_path / "b-cli.png", "--png-size", 64)
    assert (tmp_path / "b-cli.png").read_bytes() == (tmp_path / "b.png").read_bytes()
    # Inside and outside both drawn: the filled set is neither empty nor the whole picture.
    assert len(np.unique(image.image.reshape(-1, 3), axis=0)) >= 2
    mesh = quijibo.julia(str(path), output={"format": "ply", "resolution": 24})
    assert mesh.kind == "ply"
    run_cli("julia", path, "-o", tmp_path / "b.ply", "-r", 24)
    v, f = quijibo.read_mesh(str(tmp_path / "b.ply"))
    assert mesh.mesh.vertices.shape == v.shape and mesh.mesh.faces.shape == f.shape
    with pytest.raises(quijibo.Error, match="kind"):
        quijibo.julia({"kind": "no-such-kind"})
