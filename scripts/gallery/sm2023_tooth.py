"""2023 Figs. 2 and 3: a QUIJIBO tooth's modulus r(x) and versor d(x) on a slice, and orbits on r(x).

The map: `quijibo run experiments/gallery/tooth-quijibo.json` (our optimization of data/tooth.obj on
the demo schedule; the paper took the QUIJIBO code release's tooth). On the plane z = 0 of the
fractal frame (through the origin the fit puts deep inside), `quijibo-fields` gives for each pixel
log r(x) = log|R(x)| (one application), d(x) = R(x)/|R(x)| and the meshed field log|q_4| (the set's
outline, n = 4 and escape 2000 as `quijibo mesh`).
Fig. 3: four starting points x with their first step f(x) = R(x) (the arrow, drawn projected on the
plane) and the circle |q| = r(x) on which every f(x) of that modulus lies, whatever d(x):
left, a captured point whose circle lies in the basin of 0 and an escaping point whose circle lies
in the basin of infinity; right, two points with (nearly) the same r(x) whose fates differ: there
d(x) decides.
Run: PYTHONPATH=build/python /usr/bin/python3 scripts/gallery/sm2023_tooth.py [2 3]
"""
import sys

import numpy as np

import gallery as g
from qj2015_bunny import optimized_map

BOX = (-2.0, -2.0, 2.0, 2.0)
CLIP = 8.0  # the truncated log scale of r(x): |log r| above this saturates


def sample(m, size):
    pts, shape = g.plane(BOX, size)
    f, orbits = g.fields(g.map_spec(m, two_d=False), pts, "2023-tooth", orbit=1)
    return pts, shape, f, orbits


def log_r_image(ax, f, shape):
    lr = np.clip(f[:, 1], -CLIP, CLIP).reshape(shape)
    im = ax.imshow(lr, cmap="viridis", vmin=-CLIP, vmax=CLIP, extent=(BOX[0], BOX[2], BOX[1], BOX[3]))
    ax.contour(np.linspace(BOX[0], BOX[2], shape[1]), np.linspace(BOX[3], BOX[1], shape[0]),
               f[:, 0].reshape(shape), levels=[0], colors="white", linewidths=0.8)
    return im


def fig2(m, run_dir, pts, shape, f):
    fig, axes = g.plt.subplots(1, 3, figsize=(11, 3.9))
    axes[0].imshow(g.render(run_dir / "mesh" / "julia.ply", "2023-fig2-tooth", size=340))
    axes[0].set_title("Julia set, n = 4 (front view)", fontsize=9)
    im = log_r_image(axes[1], f, shape)
    fig.colorbar(im, ax=axes[1], fraction=0.046, pad=0.02).set_label("log r(x), clipped at +-8", fontsize=8)
    axes[1].set_title("modulus log r(x), set outline white", fontsize=9)
    axes[2].imshow(g.versor_rgb(f, shape), extent=(BOX[0], BOX[2], BOX[1], BOX[3]))
    axes[2].set_title("versor d(x): (i, j, k) as RGB", fontsize=9)
    for ax in axes:
        g.blank(ax)
    fig.suptitle("2023 Fig. 2: an optimized QUIJIBO tooth, slice z = 0 (fractal frame)", fontsize=10)
    fig.tight_layout()
    g.save(fig, "2023-fig2")


def circle_fate(inside, shape, r):
    """On the sampled plane: whether the circle |q| = r lies wholly inside the set (+1), wholly
    outside (-1) or crosses it (0)."""
    t = np.linspace(0, 2 * np.pi, 720, endpoint=False)
    u, v = r * np.cos(t), r * np.sin(t)
    col = np.clip(((u - BOX[0]) / (BOX[2] - BOX[0]) * shape[1]).astype(int), 0, shape[1] - 1)
    row = np.clip(((BOX[3] - v) / (BOX[3] - BOX[1]) * shape[0]).astype(int), 0, shape[0] - 1)
    m = inside.reshape(shape)[row, col]
    return 1 if m.all() else (-1 if not m.any() else 0)


def choose(pts, f, shape):
    """Indices of (captured, escaping) points for each panel; see the module's docstring. Left: a
    captured point whose circle |q| = r(x) lies inside the set on this plane and an escaping point
    whose circle lies outside it, both circles inside the picture; right: two points of the shell
    with the closest log r and different fates."""
    lr, field = f[:, 1], f[:, 0]
    inside = field < 0
    near = np.linalg.norm(pts[:, :2], axis=1) < 1.6  # the points and their circles stay in view
    picks = []
    for want, target in ((True, -1.0), (False, np.log(1.85))):
        cand = np.flatnonzero(near & (inside == want) & (np.abs(lr - target) < 0.3))
        cand = cand[np.argsort(np.abs(lr[cand] - target))][:200]
        ok = [i for i in cand if circle_fate(inside, shape, np.exp(lr[i])) == (1 if want else -1)]
        picks.append(ok[0] if ok else None)
    # Same r, different fate: pairs of shell points (|log r| < 0.5) whose log r agree best.
    shell = np.flatnonzero(near & (np.abs(lr) < 0.5))
    si, so = shell[inside[shell]], shell[~inside[shell]]
    best = None
    if len(si) and len(so):
        order = np.argsort(lr[so])
        sorted_lr = lr[so][order]
        for i in si[:: max(1, len(si) // 2000)]:
            k = np.clip(np.searchsorted(sorted_lr, lr[i]), 1, len(so) - 1)
            for j in (order[k - 1], order[k]):
                gap = abs(lr[so[j]] - lr[i])
                if best is None or gap < best[0]:
                    best = (gap, i, so[j])
    return tuple(picks), (best[1], best[2]) if best else (None, None)


def fig3(pts, shape, f, orbits):
    panels = choose(pts, f, shape)
    fig, axes = g.plt.subplots(1, 2, figsize=(8.4, 4.2))
    lines = []
    for ax, pair, title in zip(axes, panels, ("r(x) decides", "same r(x), d(x) decides")):
        log_r_image(ax, f, shape)
        for idx, colour in zip(pair, ("white", "black")):
            if idx is None:
                continue
            x, fx = orbits[idx, 0], orbits[idx, 1]
            r = np.exp(f[idx, 1])
            circle_colour = "cyan" if title.startswith("same") else colour
            ax.add_patch(g.plt.Circle((0, 0), r, fill=False, color=circle_colour, lw=1.2))
            end = np.clip(fx[:2], -1.95, 1.95)
            ax.annotate("", xy=end, xytext=x[:2], arrowprops=dict(arrowstyle="->", color=colour, lw=1.2))
            ax.plot(*x[:2], "o", color=colour, mec="grey", ms=6)
            fate = "inside" if f[idx, 0] < 0 else "escapes"
            fate += ", circle " + {1: "inside the set", -1: "outside the set", 0: "crosses the set"}[
                circle_fate(f[:, 0] < 0, shape, r)]
            lines.append(f"{title}: x = ({x[0]:.3f}, {x[1]:.3f}), log r = {f[idx, 1]:.3f}, |f(x)| = {r:.3g}, "
                         f"{fate} (log|q_4| = {f[idx, 0]:.3g})")
        ax.set_xlim(BOX[0], BOX[2])
        ax.set_ylim(BOX[1], BOX[3])
        ax.set_title(title, fontsize=9)
        g.blank(ax)
    fig.suptitle("2023 Fig. 3: x -> f(x) on log r(x) (white: captured, black: escapes; circles |q| = r(x))",
                 fontsize=9)
    fig.tight_layout()
    g.save(fig, "2023-fig3")
    print("\n".join("  " + s for s in lines))


def main(which):
    m = optimized_map("tooth-quijibo")
    pts, shape, f, orbits = sample(m, g.pick(420, 48))
    if "2" in which:
        fig2(m, g.WORK / "tooth-quijibo", pts, shape, f)
    if "3" in which:
        fig3(pts, shape, f, orbits)


if __name__ == "__main__":
    main(sys.argv[1:] or ["2", "3"])
