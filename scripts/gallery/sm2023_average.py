"""2023 Fig. 8: the average of many 2D shape-modulus Julia sets with random versors, for two targets,
and the average of phi over circles about the origin against their radius.

Targets: the hexagram (analytic) and the bunny's z = 0 slice (`quijibo sdf data/bunny.obj`). Each set
is experiments/gallery/average-*.json's map with a versor generated with seed s (10 roots in the
target's box, integer powers 2..12), s = 1..1000; `quijibo-fields --seeds 1000` counts, per pixel,
the sets that hold it (3 applications, escape 20: the shape modulus's defaults). phi comes from the
same map with alpha 1, beta 0: log r(x) = phi(x).
Run: PYTHONPATH=build/python /usr/bin/python3 scripts/gallery/sm2023_average.py
"""
import json

import numpy as np

import gallery as g

TARGETS = (("hexagram", "average-hexagram.json"), ("bunny (z = 0 slice)", "average-bunny.json"))


def spec_for(name):
    spec = json.loads((g.EXPERIMENTS / name).read_text())
    if spec["target"].endswith(".qgrid"):
        grid = g.work("2023-fig8", "bunny.qgrid")
        g.run(g.QUIJIBO, "sdf", g.ROOT / "data" / "bunny.obj", "-r", g.pick(100, 24), "-o", grid)
        spec["target"] = str(grid)
    return spec


def main():
    seeds = g.pick(1000, 4)
    size = g.pick(240, 40)
    fig, axes = g.plt.subplots(2, 2, figsize=(7.6, 7.2), gridspec_kw={"height_ratios": [1.25, 1]})
    for c, (label, name) in enumerate(TARGETS):
        spec = spec_for(name)
        box = tuple(spec["box"])
        pts, shape = g.plane(box, size)
        _, avg = g.fields(spec, pts, f"2023-fig8-{c}", seeds=seeds)
        ax = axes[0, c]
        ax.imshow(1 - avg.reshape(shape), cmap="gray", vmin=0, vmax=1, extent=(box[0], box[2], box[1], box[3]))
        ax.set_title(f"{label}: {seeds} random versors", fontsize=9)
        g.blank(ax)
        # phi averaged over circles about the origin (the origin is inside both targets).
        unit = dict(spec, alpha=1.0, beta=0.0)
        radii = np.linspace(0.0, 0.5 * (box[2] - box[0]), g.pick(120, 12))
        ang = np.linspace(0, 2 * np.pi, g.pick(720, 36), endpoint=False)
        circle = np.stack([(r * np.cos(ang), r * np.sin(ang)) for r in radii])  # (R, 2, A)
        cpts = np.zeros((len(radii) * len(ang), 3))
        cpts[:, 0] = circle[:, 0, :].ravel()
        cpts[:, 1] = circle[:, 1, :].ravel()
        phi = g.fields(unit, cpts, f"2023-fig8-{c}-phi", iterations=1)[:, 1].reshape(len(radii), len(ang))
        ax = axes[1, c]
        ax.plot(radii, phi.mean(axis=1), color="k")
        ax.axhline(0, color="grey", lw=0.6)
        ax.set_xlabel("circle radius (unit frame)", fontsize=8)
        ax.set_ylabel("mean phi on the circle", fontsize=8)
        ax.tick_params(labelsize=7)
    fig.suptitle("2023 Fig. 8: average of random 2D sets (black: always inside) and mean phi over radius",
                 fontsize=9)
    fig.tight_layout()
    g.save(fig, "2023-fig8")


if __name__ == "__main__":
    main()
