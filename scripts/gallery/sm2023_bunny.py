"""2023 Figs. 9-12: the shape modulus on the bunny (and the tooth): the versor's rings on a slice and
on the target's surface, one polynomial on two shapes, one r(x) with several d(x).

Fig. 9: `quijibo modulus data/bunny.obj --poly experiments/gallery/clustered-poly6.json` (six roots
  clustered tightly inside the bunny, as the paper says of its Figs. 1, 9 and 11), rendered, and the
  versor d(x) on the slices z = 0 and x = 0.2 (`quijibo-fields`, RGB = i, j, k) with the target's outline.
Fig. 10: d(x) at the bunny's surface (the paper uses a hand; `quijibo-fields` at the centroids of the
  unit-frame bunny's faces, each cut into 16, drawn with matplotlib), beside the target and the set.
Fig. 11: the same polynomial on the bunny and on the tooth.
Fig. 12: the bunny with four generated versors (seeds 1-4: 10 roots in the bunny's box).
All at alpha 30, beta -0.02 (the authors' baseline), 3 applications, escape 20, unit frame.
Run: PYTHONPATH=build/python /usr/bin/python3 scripts/gallery/sm2023_bunny.py [9 10 11 12]
"""
import sys

import numpy as np
from mpl_toolkits.mplot3d.art3d import Poly3DCollection

import gallery as g
import quijibo

POLY = g.EXPERIMENTS / "clustered-poly6.json"
ALPHA, BETA = 30, -0.02


def modulus_mesh(shape, name, *versor):
    """`quijibo modulus` of a shape; a mesh this process or an earlier figure made with the same
    settings (the file name holds them) is reused."""
    res = g.pick(192, 24)
    out = g.work("2023-bunny", f"{name}-a{ALPHA}-b{BETA}-r{res}.ply")
    if out.exists():
        return out
    g.run(g.QUIJIBO, "modulus", g.ROOT / "data" / f"{shape}.obj", *versor, "--alpha", ALPHA, "--beta", BETA,
          "-r", res, "-o", out)
    return out


def spec(shape, versor):
    return {"format": "quijibo-portals", "version": 1, "target": str(g.ROOT / "data" / f"{shape}.obj"),
            "alpha": ALPHA, "beta": BETA, "versor": versor, "iterations": 3, "escape_radius": 20}


def versor_slice(ax, box, at, axis, name, title):
    """d(x) on a plane (RGB = i, j, k), the target's outline (white) and the set's (black)."""
    pts, shape = g.plane(box, g.pick(400, 40), at=at, axis=axis)
    f = g.fields(spec("bunny", {"polynomial": str(POLY)}), pts, name)
    ax.imshow(g.versor_rgb(f, shape), extent=(box[0], box[2], box[1], box[3]))
    # The target's outline: phi + beta = log r / alpha = 0 at one application.
    u = np.linspace(box[0], box[2], shape[1])
    v = np.linspace(box[3], box[1], shape[0])
    ax.contour(u, v, f[:, 1].reshape(shape), levels=[0], colors="white", linewidths=0.8)
    ax.contour(u, v, f[:, 0].reshape(shape), levels=[0], colors="black", linewidths=0.5)
    ax.set_title(title, fontsize=8)


def fig9():
    box = (-0.5, -0.5, 0.5, 0.5)
    fig, axes = g.plt.subplots(1, 3, figsize=(11.4, 4.1))
    axes[0].imshow(g.render(modulus_mesh("bunny", "bunny-clustered", "--poly", POLY), "2023-fig9", size=360))
    axes[0].set_title("shape modulus Julia set (front view)", fontsize=9)
    versor_slice(axes[1], box, 0.0, "z", "2023-fig9-z", "d(x) on z = 0 (x right, y up)")
    versor_slice(axes[2], box, 0.2, "x", "2023-fig9-x", "d(x) on x = 0.2 (y right, z up)")
    for ax in axes:
        g.blank(ax)
    fig.suptitle("2023 Fig. 9: a clustered-root versor on the bunny (RGB = i, j, k; white: phi = -beta, black: "
                 "the set)", fontsize=9)
    fig.tight_layout()
    g.save(fig, "2023-fig9")


def unit_frame_bunny():
    """data/bunny.obj in the unit frame (bounding box centred at 0, longest side 100/110), as
    methods/modulus_target.h normalizes a mesh target; checked below against phi = 0."""
    v, faces = quijibo.read_mesh(str(g.ROOT / "data" / "bunny.obj"))
    lo, hi = v.min(axis=0), v.max(axis=0)
    return (v - 0.5 * (lo + hi)) * ((100 / 110) / (hi - lo).max()), np.asarray(faces)


def subdivide(tri, levels):
    """Each triangle (T, 3, 3) into 4^levels by midpoints: the versor varies faster than the
    bunny's faces are wide."""
    for _ in range(levels):
        a, b, c = tri[:, 0], tri[:, 1], tri[:, 2]
        ab, bc, ca = (a + b) / 2, (b + c) / 2, (c + a) / 2
        tri = np.concatenate([np.stack(t, axis=1) for t in ((a, ab, ca), (ab, b, bc), (ca, bc, c), (ab, bc, ca))])
    return tri


def shaded(ax, tri, colours):
    """Triangles (T, 3, 3) as a matplotlib 3D collection, looking along -z (the render's front view)."""
    n = np.cross(tri[:, 1] - tri[:, 0], tri[:, 2] - tri[:, 0])
    n /= np.linalg.norm(n, axis=1, keepdims=True) + 1e-30
    light = np.clip(np.abs(n @ np.array([-0.35, 0.45, 0.82])), 0.25, 1)[:, None]
    ax.add_collection3d(Poly3DCollection(tri, facecolors=np.clip(colours * light, 0, 1), edgecolor="none"))
    ax.set_xlim(-0.5, 0.5), ax.set_ylim(-0.5, 0.5), ax.set_zlim(-0.5, 0.5)
    ax.view_init(elev=90, azim=-90)
    ax.set_proj_type("ortho")
    ax.set_axis_off()


def fig10():
    v, faces = unit_frame_bunny()
    tri = subdivide(v[faces], g.pick(2, 0))
    centroids = tri.mean(axis=1)
    f = g.fields(spec("bunny", {"polynomial": str(POLY)}), centroids, "2023-fig10")
    phi = g.fields(spec("bunny", {"polynomial": str(POLY)}) | {"alpha": 1, "beta": 0}, v, "2023-fig10-phi")[:, 1]
    # The normalization must put the mesh on the target's zero set (within the SDF's cell, 1/100).
    if np.abs(phi).max() > 0.02:
        sys.exit(f"fig10: the unit-frame bunny is off the target's surface (max |phi| {np.abs(phi).max():.3f})")
    fig = g.plt.figure(figsize=(10.5, 3.9))
    ax = fig.add_subplot(1, 3, 1, projection="3d")
    shaded(ax, v[faces], np.full((len(faces), 3), 0.8))
    ax.set_title("target", fontsize=9)
    ax = fig.add_subplot(1, 3, 2, projection="3d")
    shaded(ax, tri, np.clip(0.5 + 0.5 * f[:, 3:6], 0, 1))
    ax.set_title("d(x) on the target's surface (RGB = i, j, k)", fontsize=9)
    ax = fig.add_subplot(1, 3, 3)
    mesh = modulus_mesh("bunny", "bunny-clustered", "--poly", POLY)
    ax.imshow(g.render(mesh, "2023-fig10", size=360))
    ax.set_title("the Julia set", fontsize=9)
    g.blank(ax)
    fig.suptitle(f"2023 Fig. 10: the versor on the surface (bunny, not the paper's hand; max |phi| at the "
                 f"vertices {np.abs(phi).max():.4f})", fontsize=9)
    fig.tight_layout()
    g.save(fig, "2023-fig10")


def fig11():
    fig, axes = g.plt.subplots(1, 2, figsize=(8.2, 4.3))
    for ax, shape in zip(axes, ("bunny", "tooth")):
        ax.imshow(g.render(modulus_mesh(shape, f"{shape}-clustered", "--poly", POLY), f"2023-fig11-{shape}",
                           size=360))
        ax.set_title(f"{shape}", fontsize=9)
        g.blank(ax)
    fig.suptitle("2023 Fig. 11: one versor polynomial (clustered-poly6.json) on two targets", fontsize=10)
    fig.tight_layout()
    g.save(fig, "2023-fig11")


def fig12():
    seeds = (1, 2, 3, 4)
    fig, axes = g.plt.subplots(1, len(seeds), figsize=(12, 3.5))
    for ax, seed in zip(axes, seeds):
        ax.imshow(g.render(modulus_mesh("bunny", f"bunny-seed{seed}", "--seed", seed), f"2023-fig12-{seed}",
                           size=320))
        ax.set_title(f"--seed {seed}", fontsize=9)
        g.blank(ax)
    fig.suptitle("2023 Fig. 12: one r(x) (bunny, alpha 30, beta -0.02), four generated versors d(x)", fontsize=10)
    fig.tight_layout()
    g.save(fig, "2023-fig12")


if __name__ == "__main__":
    which = sys.argv[1:] or ["9", "10", "11", "12"]
    for n in which:
        {"9": fig9, "10": fig10, "11": fig11, "12": fig12}[n]()
