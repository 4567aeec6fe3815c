"""2015 Fig. 6: one optimized map meshed at n = 1 (the broad shape) and n = 4 (details appear).

The paper shows the frog after 300 iterations; we have no frog, so the bunny: `quijibo run
experiments/gallery/bunny-quijibo.json` (the demo's 97(VF) schedule, 500 iterations at most), then
`quijibo mesh` of its optimized map at n = 1, at n = 4 and at n = 4 with `--detail 0` (the map as
optimized, without the mesh stage's smoothing), and `quijibo picture render`.
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
    rows = ((1, None, "n = 1"), (4, None, "n = 4 (the mesh's default detail 0.25)"),
            (4, 0, "n = 4, --detail 0 (the map as optimized)"))
    fig, axes = g.plt.subplots(len(rows), 1, figsize=(6.4, 9.6))
    for ax, (n, detail, title) in zip(axes, rows):
        tag = f"n{n}" + ("" if detail is None else f"-detail{detail}")
        mesh = g.work("2015-fig6", f"bunny-{tag}-r192.ply")
        if not mesh.exists() or mesh.stat().st_mtime < m.stat().st_mtime:  # reused for the same map
            g.run(g.QUIJIBO, "mesh", m, "-o", mesh, "-r", 192, "-n", n, *([] if detail is None else ["--detail", detail]))
        ax.imshow(g.render(mesh, f"2015-fig6-{tag}", size=300, views=2))
        ax.set_title(title, fontsize=10)
        g.blank(ax)
    fig.suptitle("2015 Fig. 6: the optimized bunny map at n = 1 and n = 4 (front, side)", fontsize=10)
    fig.tight_layout()
    g.save(fig, "2015-fig6")


if __name__ == "__main__":
    main()
