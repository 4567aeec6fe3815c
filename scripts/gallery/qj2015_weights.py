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


def signed_colour(v):
    """Inside (v < 0) blue, outside red, brightness |v| over the largest |v| of its own sign (the
    inside's distances are a few cells, the outside's reach the box)."""
    a = np.abs(v) / np.where(v < 0, np.abs(v[v < 0]).max(), np.abs(v[v >= 0]).max())
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
    # The picture: the tooth's cells on this slice and a margin of a quarter of their extent.
    ii, jj = np.nonzero(phi[:, :, k] < 0)
    m = max(2, (max(ii.ptp(), jj.ptp()) + 1) // 4)
    crop = (slice(max(0, ii.min() - m), ii.max() + m + 1), slice(max(0, jj.min() - m), jj.max() + m + 1), k)
    panels = [
        ("SDF phi", signed_colour(phi[crop].T[::-1])),
        ("inverse weight 1/phi (the paper)", None),
        ("layer weight 1/k (reference; our default\n\"balanced\" differs by one factor per side)", None),
    ]
    for i, kind in ((1, "inverse"), (2, "layer")):
        w = grids[kind].values[crop].T[::-1]
        # The weights span orders of magnitude: brightness on a log scale over two decades below
        # the largest |W| of the same sign.
        a = np.abs(w)
        top = np.where(w < 0, a[w < 0].max(), a[w >= 0].max())
        b = np.clip(1 + np.log10(np.maximum(a / top, 1e-2)) / 2, 0, 1)
        panels[i] = (panels[i][0], signed_colour(np.where(w < 0, -b, b)))
    fig, axes = g.plt.subplots(1, 3, figsize=(9.6, 3.6))
    for ax, (title, img) in zip(axes, panels):
        ax.imshow(img, interpolation="nearest")
        ax.set_title(title, fontsize=9)
        g.blank(ax)
    fig.suptitle(f"2015 Fig. 7: tooth, z slice {k} of {phi.shape[2]} (weights: log |W| over two decades)",
                 fontsize=10)
    fig.tight_layout()
    g.save(fig, "2015-fig7")


if __name__ == "__main__":
    main()
