"""2024 Fig. 2, right (a Menger sponge), Fig. 3 (a base set, one portal copy, nested copies) and Figs. 7-8 (the Koch snowflake's
modulus and versor fields).

Fig. 3: the base set M is the bunny's z = 0 slice (we have no triangle target) as a 2D shape modulus
  (alpha 3000: a sharp set). experiments/gallery/portal-one-copy.json adds a disc portal whose
  transform T maps the disc onto a disc that holds the bunny but not the portal itself: one scaled,
  rotated copy (the paper's Eqn 1). portal-nested.json scales more, so that T's image holds the
  portal too: copies of copies (Eqn 2). Arrows: x -> T(x) for a few points of the disc (T from
  the spec). The sets are `quijibo-fields`'s log|q_n| < 0 (the spec's 30 applications).
Figs. 7, 8: `quijibo-fields --koch` (alpha 3000, `quijibo portal --koch`) and `--koch --turbulent`
  (alpha 30, noise versor): the set, log r(x) of one application of F_F (portals included) and
  its versor (2D: its angle as a hue).
Fig. 2, right: the Menger sponge is an iterated function system (20 scaled copies of the cube), not a
  Julia set: menger_mesh() writes its exposed faces at level 3 (level 2 at test scale) as a PLY and
  `quijibo picture render` draws it (three-quarter view) beside 2024 Fig. 2 left, the q^2 + c set of
  experiments/gallery/schor2024-fig2-julia.json.
Run: PYTHONPATH=build/python /usr/bin/python3 scripts/gallery/portals2024.py [2 3 7 8]
"""
import json
import sys

import numpy as np

import gallery as g


def bunny_spec(name):
    spec = json.loads((g.EXPERIMENTS / name).read_text())
    grid = g.work("2024-fig3", "bunny.qgrid")
    if not grid.exists():
        g.run(g.QUIJIBO, "sdf", g.ROOT / "data" / "bunny.obj", "-r", g.pick(100, 24), "-o", grid)
    spec["target"] = str(grid)
    return spec


def transform(p, x):
    """The portal's affine transform (no noise in these specs): T(x) = R(s (x - c)) + t, 2D."""
    t = p["transform"]
    c = np.array(t.get("center", p["mask"]["center"])[:2])
    a = np.radians(t.get("rotation", {}).get("angle_deg", 0.0))
    rot = np.array([[np.cos(a), -np.sin(a)], [np.sin(a), np.cos(a)]])
    return (t["scale"] * (x - c)) @ rot.T + np.array(t.get("translation", [0, 0])[:2])


def menger_mesh(level, path):
    """The Menger sponge of `level` (3^level cells a side, unit cube) as a binary little-endian PLY:
    two triangles for every face between a solid cell and an empty one or the outside, so the
    surface is closed and its vertices shared."""
    n = 3 ** level
    idx = np.arange(n)
    d = np.zeros((n,) * 3, dtype=bool)
    # A cell is removed when, at some scale, two of its three digits are the middle one.
    for s in range(level):
        mid = (idx // 3 ** s) % 3 == 1
        x, y, z = np.meshgrid(mid, mid, mid, indexing="ij")
        d |= (x & y) | (y & z) | (x & z)
    solid = np.pad(~d, 1)
    quads = []
    for axis in range(3):
        for side in (0, 1):
            shift = np.roll(solid, -1 if side else 1, axis=axis)
            cells = np.argwhere(solid & ~shift) - 1  # solid cells whose neighbour this way is empty
            base = cells.astype(np.int64)
            base[:, axis] += side
            u, v = [a for a in range(3) if a != axis]
            corners = np.repeat(base[:, None, :], 4, axis=1)
            for k, (du, dv) in enumerate(((0, 0), (1, 0), (1, 1), (0, 1))):
                corners[:, k, u] += du
                corners[:, k, v] += dv
            if (side == 1) == (axis == 1):  # wind every face outwards
                corners = corners[:, ::-1, :]
            quads.append(corners)
    quads = np.concatenate(quads)
    keys = quads.reshape(-1, 3)
    verts, inverse = np.unique(keys, axis=0, return_inverse=True)
    q = inverse.reshape(-1, 4)
    tris = np.concatenate([q[:, [0, 1, 2]], q[:, [0, 2, 3]]])
    with open(path, "wb") as f:
        f.write((f"ply\nformat binary_little_endian 1.0\nelement vertex {len(verts)}\n"
                 "property float x\nproperty float y\nproperty float z\n"
                 f"element face {len(tris)}\nproperty list uchar int vertex_indices\nend_header\n").encode())
        f.write((verts / n - 0.5).astype("<f4").tobytes())
        rec = np.zeros(len(tris), dtype=[("n", "u1"), ("i", "<i4", 3)])
        rec["n"], rec["i"] = 3, tris
        f.write(rec.tobytes())
    return len(tris)


def fig2():
    """Fig. 2: the q^2 + c set of c = -0.2 + 0.4i - 0.4j - 0.4k beside a Menger sponge."""
    run_dir = g.work("2024-fig2", "julia")
    spec = json.loads((g.EXPERIMENTS / "schor2024-fig2-julia.json").read_text())
    if g.TEST:
        spec["julia"]["output"]["resolution"] = 48
    exp = g.work("2024-fig2", "experiment.json")
    exp.write_text(json.dumps(spec))
    if not (run_dir / "julia" / "julia.ply").exists():
        g.run(g.QUIJIBO, "run", exp, "--out", run_dir)
    level = g.pick(3, 2)
    sponge = g.work("2024-fig2", f"menger-{level}.ply")
    triangles = menger_mesh(level, sponge)
    fig, axes = g.plt.subplots(1, 2, figsize=(8, 4))
    def three_quarter(mesh, name):  # the last of the renderer's four views
        img = g.render(mesh, name, size=g.pick(400, 64), views=4)
        return img[:, 3 * img.shape[1] // 4:]

    axes[0].imshow(three_quarter(run_dir / "julia" / "julia.ply", "2024-fig2-julia"))
    axes[0].set_title("q² + c, c = −0.2 + 0.4i − 0.4j − 0.4k", fontsize=9)
    axes[1].imshow(three_quarter(sponge, "2024-fig2-menger"))
    axes[1].set_title(f"Menger sponge, level {level} ({triangles:,} triangles)", fontsize=9)
    for ax in axes:
        g.blank(ax)
    fig.tight_layout()
    g.save(fig, "2024-fig2")


def fig3():
    zoom = (0.6, 0.02, 0.96, 0.38)  # around the portal disc
    panels = (("base set M (no portal)", "portal-one-copy.json", False, None),
              ("one portal: one copy", "portal-one-copy.json", True, None),
              ("nested copies", "portal-nested.json", True, None),
              ("nested copies, the portal zoomed", "portal-nested.json", True, zoom))
    fig, axes = g.plt.subplots(1, 4, figsize=(13.6, 3.6), gridspec_kw={"width_ratios": [1.4, 1.4, 1.4, 1]})
    for i, (ax, (title, name, with_portal, view)) in enumerate(zip(axes, panels)):
        spec = bunny_spec(name)
        portals = spec["portals"]
        if not with_portal:
            spec["portals"] = []
        box = view or tuple(spec["box"])
        pts, shape = g.plane(box, g.pick(420, 48))
        f = g.fields(spec, pts, f"2024-fig3-{i}")
        ax.imshow(np.where(f[:, 0].reshape(shape) < 0, 0.0, 0.93), cmap="gray", vmin=0, vmax=1,
                  extent=(box[0], box[2], box[1], box[3]))
        if with_portal and view is None:
            for p in portals:
                c, r = np.array(p["mask"]["center"][:2]), p["mask"]["radius"]
                ax.add_patch(g.plt.Circle(c, r, fill=False, color="tab:orange", lw=1))
                for k in range(3):
                    a = 2 * np.pi * k / 3 + 0.4
                    x = c + 0.6 * r * np.array([np.cos(a), np.sin(a)])
                    y = transform(p, x)
                    ax.annotate("", xy=y, xytext=x, arrowprops=dict(arrowstyle="->", color="tab:red", lw=0.9,
                                                                   connectionstyle="arc3,rad=0.25"))
        ax.set_xlim(box[0], box[2])
        ax.set_ylim(box[1], box[3])
        ax.set_title(title, fontsize=9)
        g.blank(ax)
    fig.suptitle("2024 Fig. 3: a portal on the bunny slice (orange: the portal disc; red: x -> T(x))", fontsize=10)
    fig.tight_layout()
    g.save(fig, "2024-fig3")


def koch(fig_no):
    turbulent = fig_no == "8"
    box = (-0.62, -0.62, 0.62, 0.62)
    pts, shape = g.plane(box, g.pick(520, 48))
    koch = ["--koch", "--turbulent"] if turbulent else ["--koch"]
    f = g.fields(koch, pts, f"2024-fig{fig_no}")
    # The versor with alpha 1e-6 (r = 1 everywhere): e^(3000 phi) leaves double's range away from the
    # star, where F_F's own direction is then lost; outside the portals' feather d(x) is the same.
    d = g.fields(koch, pts, f"2024-fig{fig_no}-versor", alpha=1e-6)
    fig, axes = g.plt.subplots(1, 3, figsize=(11.4, 4.0))
    ext = (box[0], box[2], box[1], box[3])
    axes[0].imshow(np.where(f[:, 0].reshape(shape) < 0, 0.0, 0.93), cmap="gray", vmin=0, vmax=1, extent=ext)
    axes[0].set_title(("turbulent " if turbulent else "") + "Koch snowflake", fontsize=9)
    clip = 6 if turbulent else 60
    im = axes[1].imshow(np.clip(f[:, 1], -clip, clip).reshape(shape), cmap="viridis", vmin=-clip, vmax=clip,
                        extent=ext)
    fig.colorbar(im, ax=axes[1], fraction=0.046, pad=0.02).set_label(f"log r(x), clipped at +-{clip}", fontsize=8)
    axes[1].set_title("modulus log r(x)", fontsize=9)
    axes[2].imshow(g.versor_hue(d, shape), extent=ext)
    axes[2].set_title("versor d(x): hue = its angle in the complex plane", fontsize=9)
    for ax in axes:
        g.blank(ax)
    alpha = 30 if turbulent else 3000
    fig.suptitle(f"2024 Fig. {fig_no}: Koch snowflake by portals, alpha {alpha} (our frame), "
                 f"{'noise' if turbulent else 'polynomial'} versor; fields of one application of F_F", fontsize=9)
    fig.tight_layout()
    g.save(fig, f"2024-fig{fig_no}")


if __name__ == "__main__":
    for n in sys.argv[1:] or ["2", "3", "7", "8"]:
        {"2": fig2, "3": fig3}.get(n, lambda: koch(n))()
