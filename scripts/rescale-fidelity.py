#!/usr/bin/python3
"""The n-step set against the fractal frame's scale (docs/fidelity.md §3b).

Rescales a `quijibo run` result's optimized map and its target by s about the fractal origin:
roots s t_i, ln C - (tau sum T - beta sum B) log s, the target grid's box and distances times s.
The one-step set is unchanged; only the iteration sees the scale. Prints `quijibo fidelity` for
each s, and the depth of the origin (distance to the surface, from the target grid) so that the
ball radius s * depth can be read off.

  /usr/bin/python3 scripts/rescale-fidelity.py RUN_FOLDER WORK_FOLDER [s ...]

RUN_FOLDER holds optimized/map.json and initial/target.qgrid. Needs the Python module and the
binary of a build (QUIJIBO_BUILD_DIR, default build/; QUIJIBO_BINARY overrides the binary).
"""
import json
import math
import os
import subprocess
import sys

ROOT = os.path.dirname(os.path.dirname(os.path.abspath(__file__)))
BUILD = os.environ.get("QUIJIBO_BUILD_DIR", os.path.join(ROOT, "build"))
BINARY = os.environ.get("QUIJIBO_BINARY", os.path.join(BUILD, "experiments", "quijibo"))
sys.path.insert(0, os.path.join(BUILD, "python"))
import numpy as np  # noqa: E402
import quijibo  # noqa: E402


def main():
    if len(sys.argv) < 3:
        sys.exit(__doc__)
    run, work = sys.argv[1], sys.argv[2]
    scales = [float(x) for x in sys.argv[3:]] or [1.0, 2.0, 4.0, 8.0]
    os.makedirs(work, exist_ok=True)
    with open(os.path.join(run, "optimized", "map.json")) as f:
        m = json.load(f)
    g = quijibo.read_grid(os.path.join(run, "initial", "target.qgrid"))
    depth = float(-g.sample(np.zeros((1, 3)))[0])
    print(json.dumps({"run": run, "fractal_radius": m["frame"]["fractal_radius"], "depth": depth}))
    top = sum(r["exponent"] for r in m["top"])
    bottom = sum(r["exponent"] for r in m["bottom"])
    for s in scales:
        mm = json.loads(json.dumps(m))
        for side in ("top", "bottom"):
            for r in mm[side]:
                r["root"] = [s * x for x in r["root"]]
        mm["ln_C"] = m["ln_C"] - (m["tau"] * top - m["beta"] * bottom) * math.log(s)
        mm["frame"]["fractal_radius"] = m["frame"]["fractal_radius"] * s
        map_path = os.path.join(work, f"map_s{s:g}.json")
        with open(map_path, "w") as f:
            json.dump(mm, f)
        grid = quijibo.Grid(np.asarray(g.values) * s, min_corner=[s * c for c in g.min_corner], spacing=g.spacing * s)
        grid_path = os.path.join(work, f"target_s{s:g}.qgrid")
        quijibo.write_grid(grid, grid_path)
        r = subprocess.run([BINARY, "fidelity", "-m", map_path, "-t", grid_path],
                           capture_output=True, text=True)
        if r.returncode:
            sys.exit(r.stderr)
        fid = json.loads(r.stdout)
        print(json.dumps({"s": s, "ball": s * depth, "one_step": fid["one_step"], "n_step": fid["n_step"]}))


if __name__ == "__main__":
    main()
