"""Meshing: the same mesh as `quijibo mesh` for the same map and settings."""
import numpy as np
import pytest

import quijibo
from conftest import run_cli


def test_mesh_matches_the_command_line(tiny_case, tmp_path):
    m = tiny_case["rational_map"]
    out = tmp_path / "julia.ply"
    summary = tmp_path / "summary.json"
    run_cli("mesh", tiny_case["map"], "-o", out, "-r", 24, "-n", 1, "--summary", summary)
    import json
    expected = json.loads(summary.read_text())
    vertices, faces = quijibo.mesh(m, resolution=24, iterations=1)
    assert vertices.shape == (expected["vertices"], 3)
    assert faces.shape == (expected["triangles"], 3)
    assert faces.min() >= 0 and faces.max() < len(vertices)
    # Fractal frame: the map's frame maps one to the other.
    fractal = quijibo.mesh(m, resolution=24, iterations=1, frame="fractal")
    assert np.allclose(m.frame.fractal_to_user(fractal.vertices), vertices)
    assert fractal.summary["triangles"] == expected["triangles"]


def test_mesh_of_nothing(tiny_case):
    m = tiny_case["rational_map"].copy()
    m.ln_C = 200.0  # |R| huge everywhere: no set
    with pytest.raises(quijibo.Error, match="does not cross the box"):
        quijibo.mesh(m, resolution=16, iterations=1)
    v, f = quijibo.mesh(m, resolution=16, iterations=1, allow_empty=True)
    assert v.shape == (0, 3) and f.shape == (0, 3)


class Stop(Exception):
    pass


@pytest.mark.parametrize("handler", ["default", "custom"])
def test_ctrl_c_stops_a_long_mesh(handler):
    """A long mesh (minutes) stops within a fraction of a second of SIGINT; the handler's exception arrives."""
    import os
    import signal
    import threading
    import time

    m = quijibo.random_map(top=40, bottom=30, seed=3)
    expected = KeyboardInterrupt
    old = signal.getsignal(signal.SIGINT)
    if handler == "custom":
        def raise_stop(signum, frame):
            raise Stop()
        signal.signal(signal.SIGINT, raise_stop)
        expected = Stop
    timer = threading.Timer(0.3, os.kill, (os.getpid(), signal.SIGINT))
    t0 = time.monotonic()
    try:
        timer.start()
        with pytest.raises(expected):
            quijibo.mesh(m, resolution=512, iterations=6)
    finally:
        timer.cancel()
        signal.signal(signal.SIGINT, old)
    assert time.monotonic() - t0 < 20


def test_render_with_depth_and_flat(tiny_case):
    mesh = quijibo.mesh(tiny_case["rational_map"], resolution=24, iterations=1)
    depth = quijibo.render(mesh, render_size=48, render_views=2, render_samples=2, render_ao_rays=4)
    assert depth.shape == (48, 96, 3) and depth.dtype == np.uint8
    flat = quijibo.render(mesh, render_size=48, render_views=2, render_shading="flat")
    assert flat.shape == depth.shape
    # The ray-traced picture has a ground and shading where the Lambert one is white background.
    assert not np.array_equal(depth, flat)
    assert len(np.unique(depth.reshape(-1, 3), axis=0)) > 20
    with pytest.raises(quijibo.Error, match="render_shading"):
        quijibo.render(mesh, render_shading="glossy")
