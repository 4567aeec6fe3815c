"""2015 Figs. 3-5: what a root does to the Julia set of a factored rational (Eqn 4).

Fig. 3: a 4-root polynomial whose rightmost root is dragged towards the centre (Property 1).
Fig. 4: a 5-root rational whose bottom root is dragged towards the set (Property 2).
Fig. 5: the centre root's multiplicity 1 -> 3 -> 7 (Property 3).
The maps are experiments/gallery/maps/2015-fig{3,4,5}-*.json (roots in the z = 0 plane). Each
frame: top, `quijibo mesh -n 4` rendered by `quijibo picture render` (front view, looking down z;
`--detail 0`: the map as written, not smoothed); bottom, the z = 0 slice of the same set (`quijibo-fields`, 4 applications, escape 2000: the mesh
stage's defaults), black inside, top roots blue, bottom roots red.
Run: PYTHONPATH=build/python /usr/bin/python3 scripts/gallery/qj2015_roots.py [3 4 5]
"""
import json
import sys

import numpy as np

import gallery as g

FIGURES = {
    "3": ("abcd", "the rightmost top root moves from x = 1.4 to 0.5"),
    "4": ("abcd", "the bottom root (red) moves from y = -1.6 to -0.45"),
    "5": ("abc", "the centre root's multiplicity: 1, 3, 7"),
}
BOX = (-2.0, -2.0, 2.0, 2.0)  # the map's default meshing box (fractal frame, box centre +- radius / 2)


def frame(fig_no, letter):
    path = g.EXPERIMENTS / "maps" / f"2015-fig{fig_no}-{letter}.json"
    m = json.loads(path.read_text())
    mesh = g.work("2015-roots", f"fig{fig_no}{letter}.ply")
    g.run(g.QUIJIBO, "mesh", path, "-o", mesh, "-r", g.pick(128, 24), "-n", 4, "--detail", 0, "--allow-empty")
    image = g.render(mesh, f"2015-fig{fig_no}{letter}")
    pts, shape = g.plane(BOX, g.pick(360, 48))
    f = g.fields(g.map_spec(path), pts, f"2015-fig{fig_no}{letter}")
    inside = (f[:, 0] < 0).reshape(shape)
    return m, image, inside


def figure(fig_no):
    letters, what = FIGURES[fig_no]
    fig, axes = g.plt.subplots(2, len(letters), figsize=(2.4 * len(letters), 5.0))
    for c, letter in enumerate(letters):
        m, image, inside = frame(fig_no, letter)
        axes[0, c].imshow(image)
        axes[1, c].imshow(np.where(inside, 0.0, 0.92), cmap="gray", vmin=0, vmax=1, extent=BOX[0::2] + BOX[1::2])
        for key, colour in (("top", "tab:blue"), ("bottom", "tab:red")):
            for r in m[key]:
                axes[1, c].plot(r["root"][0], r["root"][1], "o", color=colour, ms=4 + r["exponent"])
        if fig_no == "5":
            axes[1, c].set_title(f"centre root ^{m['top'][0]['exponent']:g}", fontsize=9)
        for ax in axes[:, c]:
            g.blank(ax)
    axes[0, 0].set_ylabel("mesh, n = 4", fontsize=9)
    axes[1, 0].set_ylabel("z = 0 slice", fontsize=9)
    fig.suptitle(f"2015 Fig. {fig_no}: {what}", fontsize=10)
    fig.tight_layout()
    g.save(fig, f"2015-fig{fig_no}")


if __name__ == "__main__":
    for n in sys.argv[1:] or FIGURES:
        figure(n)
