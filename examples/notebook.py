# %% [markdown]
# # A quijibo run, from Python
#
# Loads the results folder of a `quijibo run` (by default the demo's, `results/bunny-demo`, which
# README command 1 makes), plots the optimizer's convergence from its `log.jsonl` with matplotlib,
# and meshes the optimized map again at another iteration count.
#
# A script in the percent format: Jupyter (with jupytext), VS Code and Spyder open it as a notebook;
# from the source folder it also runs as it is:
#
#     PYTHONPATH=build/python /usr/bin/python3 examples/notebook.py
#
# Settings come from the environment (a notebook has no command line):
# `QUIJIBO_RESULTS` (the results folder), `QUIJIBO_ITERATIONS` (the iteration count of the new mesh;
# default: one fewer than the experiment's, or 2), `QUIJIBO_NOTEBOOK_OUT` (where the plot and the
# mesh go; default `<results>/notebook`). See docs/python.md.

# %%
import json
import os
import pathlib

import matplotlib

matplotlib.use(os.environ.get("MPLBACKEND", "Agg"))  # headless unless asked otherwise
import matplotlib.pyplot as plt
import numpy as np

import quijibo

results = pathlib.Path(os.environ.get("QUIJIBO_RESULTS", "results/bunny-demo"))
out = pathlib.Path(os.environ.get("QUIJIBO_NOTEBOOK_OUT", results / "notebook"))
if not (results / "experiment.resolved.json").exists():
    raise SystemExit(f"{results}: not a results folder of `quijibo run` (no experiment.resolved.json); "
                     "make one with ./scripts/quickstart.sh or set QUIJIBO_RESULTS")
out.mkdir(parents=True, exist_ok=True)
experiment = json.loads((results / "experiment.resolved.json").read_text())
print(f"{results}: experiment {experiment.get('name', '?')!r}, method {experiment.get('method', 'quijibo')}")

# %% [markdown]
# ## Convergence
#
# Each optimizer writes `<name>/log.jsonl`, one JSON record per line (docs/formats.md): `iteration`
# records carry the pass's energy ψ on its level (relative: that level's grid and weights), `absolute`
# records ψ on the finest grid with the original weights, the number the runs compare by.

# %%
def read_log(path):
    with open(path) as f:
        return [json.loads(line) for line in f if line.strip()]


optimizers = experiment["optimizer"] if isinstance(experiment["optimizer"], list) else [experiment["optimizer"]]
fig, ax = plt.subplots(figsize=(8, 4.5))
for opt in optimizers:
    name = opt.get("name", "optimized")
    records = read_log(results / name / "log.jsonl")
    it = [r for r in records if r["type"] == "iteration"]
    ab = [r for r in records if r["type"] in ("absolute", "pass_end", "run")]
    # A pass_end record's absolute energy is `absolute_end`; the run record's `absolute_energy`.
    ab_energy = [r.get("energy", r.get("absolute_end", r.get("absolute_energy"))) for r in ab]
    line, = ax.plot([r["step"] for r in it], [r["energy"] for r in it], lw=0.8, alpha=0.6,
                    label=f"{name}: level energy")
    ax.plot([r["step"] for r in ab], ab_energy, "o-", ms=3, color=line.get_color(), label=f"{name}: absolute ψ")
    passes = [r for r in records if r["type"] == "pass_start"]
    for p in passes:
        ax.axvline(p["step"], color="0.85", lw=0.6, zorder=0)
    summary = json.loads((results / name / "summary.json").read_text())
    print(f"{name}: {len(it)} iterations in {len(passes)} passes, absolute ψ "
          f"{summary['absolute_start']:.4f} -> {summary['absolute_end']:.4f}")
ax.set_xlabel("step (L-BFGS iterations over the run; grey lines: pass starts)")
ax.set_ylabel("ψ (−1 is a perfect fit)")
ax.set_title(f"{experiment.get('name', results.name)}: convergence")
ax.legend(fontsize=8)
fig.tight_layout()
fig.savefig(out / "convergence.png", dpi=120)
print(f"wrote {out / 'convergence.png'}")

# %% [markdown]
# ## The optimized map, meshed at another iteration count
#
# The run meshed the Julia set after `mesh.iterations` applications of the map (the paper shows 1
# and 4); here the same map is meshed after another count, at the run's resolution, in the input
# mesh's coordinates.

# %%
first = optimizers[0].get("name", "optimized")
rational_map = quijibo.read_map(str(results / first / "map.json"))
print(rational_map)
mesh_settings = experiment.get("mesh", {})
n_run = int(mesh_settings.get("iterations", 4))
iterations = int(os.environ.get("QUIJIBO_ITERATIONS", max(1, n_run - 1) if n_run > 1 else 2))
resolution = int(mesh_settings.get("resolution", 128))
mesh = quijibo.mesh(rational_map, resolution=resolution, iterations=iterations, allow_empty=True)
vertices, faces = mesh
print(f"n = {iterations}: {len(vertices)} vertices, {len(faces)} triangles, "
      f"{mesh.summary['components']} components, {mesh.summary['seconds']:.2f} s")
if len(faces):
    path = out / f"julia-n{iterations}.ply"
    quijibo.write_mesh(mesh, str(path))
    lo, hi = vertices.min(axis=0), vertices.max(axis=0)
    print(f"wrote {path}; bounding box {np.round(lo, 3)} .. {np.round(hi, 3)}")
if (results / "mesh" / "summary.json").exists():
    run_mesh = json.loads((results / "mesh" / "summary.json").read_text())
    print(f"the run's mesh, n = {n_run}: {run_mesh['vertices']} vertices, {run_mesh['triangles']} triangles")

# %% [markdown]
# The same map made intricate (docs/meshing.md "Root translation by potential"): fractal detail 4,
# and the roots translated along z by the length that leaves the potential L = -2 at -t, where the
# map sends the inside of the set. The one-step set stays; the surface grows ridges, pits and lobes.

# %%
try:
    intricate = quijibo.mesh(rational_map, resolution=resolution, iterations=4, detail=4, translate_potential=-2,
                             allow_empty=True)
    t = intricate.summary["julia"]["root_translation"]
    print(f"intricate: translation z = {t[2]:.4f}, {len(intricate.faces)} triangles, "
          f"{intricate.summary['components']} components")
    if len(intricate.faces):
        quijibo.write_mesh(intricate, str(out / "julia-intricate.ply"))
except quijibo.Error as e:  # e.g. the frame's origin is not inside the set
    print(f"intricate: not meshed: {e}")
