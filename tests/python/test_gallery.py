"""The gallery's tool and scripts (docs/gallery.md): `quijibo-fields` against maps whose fields are
known in closed form, its weight output against the definition, and a cheap subset of
scripts/gallery/make-all.sh at test scale, so the scripts keep working."""
import json
import os
import pathlib
import subprocess

import numpy as np
import pytest

from conftest import BINARY, SOURCE_DIR

BUILD = pathlib.Path(os.environ.get("QUIJIBO_BUILD_DIR", SOURCE_DIR / "build"))
FIELDS = BUILD / "experiments" / "fields" / "quijibo-fields"


def fields(tmp_path, spec, points, *args, check=True):
    (tmp_path / "spec.json").write_text(json.dumps(spec))
    np.save(tmp_path / "p.npy", np.asarray(points, dtype=np.float64))
    p = subprocess.run([str(FIELDS), str(tmp_path / "spec.json"), "--points", str(tmp_path / "p.npy"),
                        "-o", str(tmp_path / "f.npy"), *map(str, args)], capture_output=True, text=True)
    if check:
        assert p.returncode == 0, p.stderr
        return np.load(tmp_path / "f.npy")
    return p


def square_map(tmp_path):
    """R(q) = q^2 as a QUIJIBO map: one top root at 0 with exponent 2 (its Julia set: the unit ball)."""
    doc = {"format": "quijibo-map", "version": 1, "ln_C": 0.0, "tau": 1.0, "beta": 1.0,
           "top": [{"root": [0, 0, 0, 0], "exponent": 2.0}], "bottom": []}
    (tmp_path / "sq.json").write_text(json.dumps(doc))
    return {"format": "quijibo-portals", "version": 1, "map": str(tmp_path / "sq.json"),
            "iterations": 3, "escape_radius": 100}


def qmul(a, b):
    w1, x1, y1, z1 = a.T
    w2, x2, y2, z2 = b.T
    return np.stack([w1 * w2 - x1 * x2 - y1 * y2 - z1 * z2, w1 * x2 + x1 * w2 + y1 * z2 - z1 * y2,
                     w1 * y2 - x1 * z2 + y1 * w2 + z1 * x2, w1 * z2 + x1 * y2 - y1 * x2 + z1 * w2], axis=1)


def test_fields_of_q_squared_are_the_closed_form(tmp_path):
    rng = np.random.default_rng(3)
    pts = rng.uniform(-1.5, 1.5, size=(400, 3))
    f = fields(tmp_path, square_map(tmp_path), pts, "--orbit", 2, "--orbit-out", tmp_path / "o.npy")
    assert f.shape == (400, 7)
    r = np.linalg.norm(pts, axis=1)
    q = np.concatenate([pts, np.zeros((400, 1))], axis=1)
    q2 = qmul(q, q)
    # One application: log r = 2 log|q|, versor q^2 / |q|^2.
    np.testing.assert_allclose(f[:, 1], 2 * np.log(r), rtol=1e-9, atol=1e-12)
    np.testing.assert_allclose(f[:, 2:6], q2 / (r ** 2)[:, None], atol=1e-9)
    # Three applications unless |q| reaches 100 first: log|q_n| = 2^n log|q|.
    n = f[:, 6]
    expect = np.where(n == 3, 8 * np.log(r), 2 ** n * np.log(r))
    np.testing.assert_allclose(f[:, 0], expect, rtol=1e-9, atol=1e-12)
    assert ((f[:, 0] < 0) == (r < 1)).all()
    o = np.load(tmp_path / "o.npy")
    assert o.shape == (400, 3, 4)
    np.testing.assert_allclose(o[:, 0], q, atol=0)
    np.testing.assert_allclose(o[:, 1], q2, rtol=1e-9, atol=1e-12)


def test_seed_average_is_the_fraction_of_sets(tmp_path):
    # alpha 3000 on a disc: every versor gives the disc (the shell is far below the sampling), so the
    # average over any seeds is 1 inside and 0 outside, away from the edge.
    spec = {"format": "quijibo-portals", "version": 1, "target": "disc:radius=0.3", "alpha": 3000,
            "versor": {"generate": {"roots": 4}}, "iterations": 3, "escape_radius": 20}
    pts = np.array([[0.0, 0.0, 0.0], [0.1, 0.15, 0.0], [0.4, 0.0, 0.0], [0.0, -0.45, 0.0]])
    fields(tmp_path, spec, pts, "--seeds", 3, "--average-out", tmp_path / "a.npy")
    np.testing.assert_array_equal(np.load(tmp_path / "a.npy"), [1, 1, 0, 0])


def test_weights_are_the_inverse_sdf(tmp_path):
    grid = tmp_path / "s.qgrid"
    subprocess.run([str(BINARY), "-q", "target", "sphere", "-r", "16", "-o", str(grid)], check=True)
    out = tmp_path / "w.qgrid"
    p = subprocess.run([str(FIELDS), "--weights-of", str(grid), "--weights", "inverse", "--weights-out", str(out)],
                       capture_output=True, text=True)
    assert p.returncode == 0, p.stderr
    import quijibo
    phi, w = quijibo.read_grid(str(grid)), quijibo.read_grid(str(out))
    h = phi.spacing
    inv = 1 / np.maximum(np.abs(phi.values), h / 2) * np.sign(phi.values)
    # Normalized halves: the inside sums to -1/2, the outside to +1/2 (quijibo/target.h).
    inside = phi.values < 0
    assert w.values[inside].sum() == pytest.approx(-0.5) and w.values[~inside].sum() == pytest.approx(0.5)
    for part in (inside, ~inside):
        ratio = w.values[part] / inv[part]
        np.testing.assert_allclose(ratio, ratio[0], rtol=1e-9)


def test_bad_points_file_is_named(tmp_path):
    np.save(tmp_path / "p.npy", np.zeros((3, 3), dtype=np.float32))
    (tmp_path / "s.json").write_text(json.dumps({"format": "quijibo-portals", "version": 1, "target": "disc"}))
    p = subprocess.run([str(FIELDS), str(tmp_path / "s.json"), "--points", str(tmp_path / "p.npy"), "-o",
                        str(tmp_path / "f.npy")], capture_output=True, text=True)
    assert p.returncode == 1
    assert "p.npy: dtype '<f4' (expected float64, '<f8')" in p.stderr
    assert not (tmp_path / "f.npy").exists()


def test_gallery_scripts_at_test_scale(tmp_path):
    """A cheap subset of make-all.sh: every figure kind that needs no optimization run."""
    env = dict(os.environ, GALLERY_SCALE="test", GALLERY_IMAGES=str(tmp_path / "img"),
               GALLERY_WORK=str(tmp_path / "work"), QUIJIBO_BUILD_DIR=str(BUILD))
    figures = ["2015-3", "2015-7", "2023-8", "2023-12", "2024-3", "2024-7"]
    p = subprocess.run([str(SOURCE_DIR / "scripts" / "gallery" / "make-all.sh"), *figures], env=env,
                       capture_output=True, text=True, timeout=300)
    assert p.returncode == 0, p.stdout + p.stderr
    for name in ["2015-fig3", "2015-fig7", "2023-fig8", "2023-fig12", "2024-fig3", "2024-fig7"]:
        png = tmp_path / "img" / f"{name}.png"
        assert png.exists() and png.read_bytes()[:8] == b"\x89PNG\r\n\x1a\n", name


@pytest.mark.parametrize("level", [1, 2])
def test_menger_sponge_mesh_is_closed_outward_and_has_its_volume(tmp_path, level):
    """2024 Fig. 2's sponge (scripts/gallery/portals2024.py): every edge shared by two triangles,
    the faces wound outwards, and the enclosed volume (20/27)^level of the unit cube."""
    import sys
    sys.path.insert(0, str(SOURCE_DIR / "scripts" / "gallery"))
    import portals2024
    path = tmp_path / "sponge.ply"
    triangles = portals2024.menger_mesh(level, path)
    data = path.read_bytes()
    start = data.index(b"end_header\n") + len(b"end_header\n")
    nv = int(data.split(b"element vertex ")[1].split(b"\n")[0])
    v = np.frombuffer(data[start:start + 12 * nv], "<f4").reshape(-1, 3).astype(np.float64)
    t = np.frombuffer(data[start + 12 * nv:], dtype=[("n", "u1"), ("i", "<i4", 3)])["i"]
    assert len(t) == triangles
    a, b, c = v[t[:, 0]], v[t[:, 1]], v[t[:, 2]]
    assert np.einsum("ij,ij->i", a, np.cross(b, c)).sum() / 6 == pytest.approx((20 / 27) ** level, rel=1e-6)
    edges = np.sort(np.concatenate([t[:, [0, 1]], t[:, [1, 2]], t[:, [2, 0]]]), axis=1)
    _, count = np.unique(edges, axis=0, return_counts=True)
    assert set(count.tolist()) == {2}
