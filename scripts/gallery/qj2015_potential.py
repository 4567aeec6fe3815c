"""2015 Fig. 8: the roots Alg. 1 places, on the surface potential (positive roots blue, negative red).

`quijibo monopoles MESH --initializer monopoles` (the paper's BEM potential and greedy monopole fit)
writes potential.png: the potential on the slice z = 0 (grey), the target's outline (green) and the
roots within two cells of the slice (top blue, bottom red). Both fits: the paper's text (fit P, the
default) and the reference code's (fit 1 - P, `--fit-target reference`, on the reference code's
target box, `--target-box reference`: on the unit box that fit's start is inverted and the command
refuses it, docs/benchmarks.md §2). A folder already holding potential.png is reused.
Run: PYTHONPATH=build/python /usr/bin/python3 scripts/gallery/qj2015_potential.py
"""
import json

import gallery as g


def main():
    shapes = ("bunny", "tooth")
    fits = (("potential", "fit P (paper text, default)", []),
            ("reference", "fit 1 - P, reference box (reference code)", ["--target-box", "reference"]))
    fig, axes = g.plt.subplots(len(fits), len(shapes), figsize=(6.6, 6.9))
    for c, shape in enumerate(shapes):
        for r, (fit, label, extra) in enumerate(fits):
            res = g.pick(97, 24)
            out = g.work("2015-fig8", f"{shape}-{fit}-r{res}", "x").parent
            if not (out / "potential.png").exists():  # the settings are in the folder's name
                g.run(g.QUIJIBO, "monopoles", g.ROOT / "data" / f"{shape}.obj", "-o", out, "--initializer",
                      "monopoles", "--fit-target", fit, *extra, "--png-size", g.pick(500, 64), "-r", res)
            m = json.loads((out / "map.json").read_text())
            ax = axes[r, c]
            ax.imshow(g.plt.imread(out / "potential.png"))
            ax.set_title(f"{shape}, {label}\n{len(m['top'])} top / {len(m['bottom'])} bottom roots", fontsize=8)
            g.blank(ax)
    fig.suptitle("2015 Fig. 8: monopole roots on the potential, slice z = 0", fontsize=10)
    fig.tight_layout()
    g.save(fig, "2015-fig8")


if __name__ == "__main__":
    main()
