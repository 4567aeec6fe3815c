"""Shared helpers of the gallery scripts (docs/gallery.md): where the binaries, the work folder and
the pictures are, running the toolkit, sampling a map on a plane with `quijibo-fields`, and saving
a panel PNG small enough for a doc page.

Environment:
  QUIJIBO_BUILD_DIR   build folder (default build/)
  GALLERY_WORK        scratch folder for meshes, runs and arrays (default results/gallery)
  GALLERY_IMAGES      where the PNGs go (default docs/images/gallery)
  GALLERY_SCALE       "full" (the checked-in pictures) or "test" (tiny, for tests/python/test_gallery.py)
The Julia sets, fields, weights and meshes all come from the toolkit (`quijibo`, `quijibo-fields`);
numpy and matplotlib only arrange, colour and annotate them.
"""
import json
import os
import pathlib
import subprocess
import sys
import time

import numpy as np
import matplotlib

matplotlib.use("Agg")
import matplotlib.pyplot as plt  # noqa: E402

ROOT = pathlib.Path(__file__).resolve().parents[2]
BUILD = pathlib.Path(os.environ.get("QUIJIBO_BUILD_DIR", ROOT / "build"))
if not BUILD.is_absolute():
    BUILD = ROOT / BUILD
QUIJIBO = BUILD / "experiments" / "quijibo"
FIELDS = BUILD / "experiments" / "fields" / "quijibo-fields"
WORK = pathlib.Path(os.environ.get("GALLERY_WORK", ROOT / "results" / "gallery"))
IMAGES = pathlib.Path(os.environ.get("GALLERY_IMAGES", ROOT / "docs" / "images" / "gallery"))
SCALE = os.environ.get("GALLERY_SCALE", "full")
if SCALE not in ("full", "test"):
    sys.exit(f"GALLERY_SCALE: expected full or test, found {SCALE!r}")
TEST = SCALE == "test"
EXPERIMENTS = ROOT / "experiments" / "gallery"
MAX_PNG_BYTES = 400_000


def pick(full, test):
    """The full-scale or the test-scale value of a setting."""
    return test if TEST else full


def run(*args, quiet=True):
    """Runs a command (paths allowed), failing loudly; returns its stdout."""
    args = [str(a) for a in args]
    if quiet and args[0] == str(QUIJIBO):
        args.insert(1, "--quiet")
    t = time.time()
    p = subprocess.run(args, capture_output=True, text=True, cwd=ROOT)
    if p.returncode != 0:
        sys.exit(f"gallery: failed ({p.returncode}): {' '.join(args)}\n{p.stderr}")
    print(f"  {time.time() - t:6.1f} s  {' '.join(a.replace(str(ROOT) + '/', '') for a in args)}", flush=True)
    return p.stdout


def work(*parts):
    p = WORK.joinpath(*parts)
    p.parent.mkdir(parents=True, exist_ok=True)
    return p


def plane(box, size, at=0.0, axis="z"):
    """Pixel centres of a plane as (N, 3) points and the image shape (rows top to bottom).

    box = (u0, v0, u1, v1) in the plane's two coordinates (x, y for axis z; x, z for y; y, z for x)."""
    u0, v0, u1, v1 = box
    w = size if u1 - u0 >= v1 - v0 else max(2, round(size * (u1 - u0) / (v1 - v0)))
    h = size if v1 - v0 >= u1 - u0 else max(2, round(size * (v1 - v0) / (u1 - u0)))
    u = u0 + (np.arange(w) + 0.5) * (u1 - u0) / w
    v = v1 - (np.arange(h) + 0.5) * (v1 - v0) / h
    U, V = np.meshgrid(u, v)
    A = np.full_like(U, at)
    pts = {"z": (U, V, A), "y": (U, A, V), "x": (A, U, V)}[axis]
    return np.stack([c.ravel() for c in pts], axis=1), (h, w)


def fields(spec, points, name, orbit=0, seeds=0, **options):
    """`quijibo-fields` on `points` for a portal spec (dict, path, or a list of arguments such as
    ["--koch"]); options are the tool's (alpha=1e-6 -> --alpha 1e-6). Returns the (N, 7) array
    [field_n, log|F(q)|, versor w i j k, applications]; with orbit K also the (N, K+1, 4) orbits,
    with seeds S the (N,) fraction of the S random-versor sets holding each point."""
    pts = work("fields", f"{name}-points.npy")
    np.save(pts, np.ascontiguousarray(points, dtype=np.float64))
    if isinstance(spec, list):
        pass
    elif isinstance(spec, dict):
        path = work("fields", f"{name}-spec.json")
        path.write_text(json.dumps(spec, indent=1) + "\n")
        spec = [path]
    else:
        spec = [spec]
    out = work("fields", f"{name}.npy")
    args = [FIELDS, *spec, "--points", pts, "-o", out]
    for k, v in options.items():
        args += ["--" + k.replace("_", "-"), v]
    if orbit:
        args += ["--orbit", orbit, "--orbit-out", work("fields", f"{name}-orbits.npy")]
    if seeds:
        args += ["--seeds", seeds, "--average-out", work("fields", f"{name}-average.npy")]
    run(*args)
    res = [np.load(out)]
    if orbit:
        res.append(np.load(work("fields", f"{name}-orbits.npy")))
    if seeds:
        res.append(np.load(work("fields", f"{name}-average.npy")))
    return res[0] if len(res) == 1 else tuple(res)


def map_spec(map_path, two_d=True, iterations=4, escape=2000.0):
    """A portal spec without portals over a QUIJIBO map.json: the map itself (fractal frame),
    iterated as `quijibo mesh` does by default (4 applications, escape radius 2000)."""
    return {"format": "quijibo-portals", "version": 1, "map": str(map_path),
            "dimension": 2 if two_d else 3, "iterations": iterations, "escape_radius": escape}


def versor_rgb(v, shape):
    """The versor's imaginary parts (i, j, k) as RGB in [0, 1], as the 2023 paper draws d(x)."""
    return np.clip(0.5 + 0.5 * v[:, 3:6], 0, 1).reshape(*shape, 3)


def versor_hue(v, shape):
    """A 2D versor d = [w, i, 0, 0] (the iteration stays in the complex plane) as the hue of its
    angle atan2(i, w): RGB of (i, j, k) would show only i."""
    from matplotlib.colors import hsv_to_rgb
    hue = (np.arctan2(v[:, 3], v[:, 2]) / (2 * np.pi)) % 1.0
    return hsv_to_rgb(np.stack([hue, np.full_like(hue, 0.75), np.full_like(hue, 0.95)], axis=1)).reshape(*shape, 3)


def render(mesh, name, size=None, views=1):
    """`quijibo picture render` of a mesh (one view by default): the image array."""
    out = work("render", f"{name}.png")
    run(QUIJIBO, "picture", "render", mesh, "-o", out, "--size", size or pick(320, 64),
        "--views", views)
    return plt.imread(out)


def save(fig, name, dpi=None):
    """Saves a figure to IMAGES/name.png, lowering the resolution until it fits MAX_PNG_BYTES."""
    IMAGES.mkdir(parents=True, exist_ok=True)
    path = IMAGES / f"{name}.png"
    dpi = dpi or pick(100, 40)
    while True:
        fig.savefig(path, dpi=dpi)
        if path.stat().st_size <= MAX_PNG_BYTES or dpi <= 40:
            break
        dpi = int(dpi * 0.85)
    plt.close(fig)
    print(f"  -> {path.relative_to(ROOT) if path.is_relative_to(ROOT) else path} ({path.stat().st_size // 1000} KB)")
    return path


def blank(ax):
    ax.set_xticks([])
    ax.set_yticks([])
