"""2015 Fig. 7: a slice through the tooth's SDF (inside blue, outside red, brightness the distance)
and the weight the energy puts on it: the paper's inverse SDF (Eqn 6, `weights: "inverse"`) and,
for comparison, the layer weight this toolkit uses by default (the reference code's).

`quijibo sdf data/tooth.obj -r 97` writes the SDF; `quijibo-fields --weights-of` writes the weight
field exactly as the optimizer builds it (quijibo/target.h ComputeWeights).
Run: PYTHONPATH=build/python /usr/bin/python3 scripts/gallery/qj2015_weights.py
"""
import numpy as np

import gallery as g
import quijibo


def signed_colour(v, scale):
    """Inside (v < 0) blue, outside red, brightness |v| / scale (clipped to 1)."""
    a = np.clip(np.abs(v) / scale, 0, 1)
    rgb = np.zeros(v.shape + (3,))
    rgb[..., 2] = np.where(v < 0, a, 0)
    rgb[..., 0] = np.where(v >= 0, a, 0)
    return rgb


def main():
    res = g.pick(97, 24)
    sdf = g.work("2015-fig7", "tooth.qgrid")
    g.run(g.QUIJIBO, "sdf", g.ROOT / "data" / "tooth.obj", "-r", res, "-o", sdf)
    grids = {"sdf": quijibo.read_grid(str(sdf))}
    for kind in ("inverse", "layer"):
        w = g.work("2015-fig7", f"tooth-weights-{kind}.qgrid")
        g.run(g.FIELDS, "--weights-of", sdf, "--weights", kind, "--weights-out", w)
        grids[kind] = quijibo.read_grid(str(w))
    phi = grids["sdf"].values
    k = phi.shape[2] // 2  # the middle z slice
    panels = [
        ("SDF phi", signed_colour(phi[:, :, k].T[::-1], np.abs(phi[:, :, k]).max())),
        ("inverse weight 1/phi (the paper)", None),
        ("layer weight (our default)", None),
    ]
    for i, kind in ((1, "inverse"), (2, "layer")):
        w = grids[kind].values[:, :, k].T[::-1]
        # The weights span orders of magnitude: brightness on a log scale over three decades.
        a = np.abs(w)
        lo = a.max() * 1e-3
        b = np.clip(np.log(np.maximum(a, lo) / lo) / np.log(1e3), 0, 1)
        panels[i] = (panels[i][0], signed_colour(np.sign(w) * b, 1.0))
    fig, axes = g.plt.subplots(1, 3, figsize=(9.6, 3.6))
    for ax, (title, img) in zip(axes, panels):
        ax.imshow(img, interpolation="nearest")
        ax.set_title(title, fontsize=9)
        g.blank(ax)
    fig.suptitle(f"2015 Fig. 7: tooth, z slice {k} of {phi.shape[2]} (weights: brightness log |W| over 3 decades)",
                 fontsize=10)
    fig.tight_layout()
    g.save(fig, "2015-fig7")


if __name__ == "__main__":
    main()
