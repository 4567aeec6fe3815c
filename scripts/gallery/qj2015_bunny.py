"""2015 Fig. 6: one optimized map meshed at n = 1 (the broad shape) and n = 4 (details appear).

The paper shows the frog after 300 iterations; we have no frog, so the bunny: `quijibo run
experiments/gallery/bunny-quijibo.json` (the demo's 97(VF) schedule, 500 iterations at most), then
`quijibo mesh` of its optimized map at n = 1 and n = 4 and `quijibo picture render`.
Run: PYTHONPATH=build/python /usr/bin/python3 scripts/gallery/qj2015_bunny.py
"""
import gallery as g


def optimized_map(name):
    """Runs experiments/gallery/<name>.json once (the run's cache reuses it) and returns its map."""
    out = g.WORK / name
    g.run(g.QUIJIBO, "run", g.EXPERIMENTS / f"{name}.json", "--out", out)
    return out / "optimized" / "map.json"


def main():
    m = optimized_map("bunny-quijibo")
    fig, axes = g.plt.subplots(2, 1, figsize=(6.4, 6.6))
    for ax, n in zip(axes, (1, 4)):
        mesh = g.work("2015-fig6", f"bunny-n{n}.ply")
        g.run(g.QUIJIBO, "mesh", m, "-o", mesh, "-r", 192, "-n", n)
        ax.imshow(g.render(mesh, f"2015-fig6-n{n}", size=300, views=2))
        ax.set_title(f"n = {n}", fontsize=10)
        g.blank(ax)
    fig.suptitle("2015 Fig. 6: the optimized bunny map at n = 1 and n = 4 (front, side)", fontsize=10)
    fig.tight_layout()
    g.save(fig, "2015-fig6")


if __name__ == "__main__":
    main()
