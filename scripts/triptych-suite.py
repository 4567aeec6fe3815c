#!/usr/bin/python3
"""The triptych on every shape of the suite: what the default intricate surface gives.

    /usr/bin/python3 scripts/triptych-suite.py [--quijibo build/experiments/quijibo] [--out results/triptych-suite]
        [--shapes bunny,tooth,hand,...] [--intricate '{"translate_potential": -2}'] [--markdown table.md]

For each shape (the shipped bunny and tooth, and data/suite/suite.json's shapes whose mesh is present,
fetched ones included after scripts/fetch-shapes.sh), runs the demo experiment on it (`quijibo run`:
the demo schedule, the mesh at 128^3, the intricate surface with its defaults or `--intricate`'s
settings) into <out>/<name>, then prints one Markdown row per shape from its triptych/triptych.json:
the set's and the intricate surface's area ratio, box dimension, closed IoU, n-step IoU and
components, and the translation found. A rerun reuses every unchanged stage (the stage cache).
"""
import argparse
import json
import os
import subprocess
import sys
import time

HERE = os.path.dirname(os.path.abspath(__file__))
ROOT = os.path.dirname(HERE)


def shapes():
    out = [("bunny", os.path.join(ROOT, "data/bunny.obj")), ("tooth", os.path.join(ROOT, "data/tooth.obj"))]
    suite = json.load(open(os.path.join(ROOT, "data/suite/suite.json")))
    for s in suite:
        path = os.path.join(ROOT, "data/suite", s["mesh"])
        if os.path.exists(path):
            out.append((s["name"], path))
    return out


def main():
    ap = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    ap.add_argument("--quijibo", default=os.path.join(ROOT, "build/experiments/quijibo"))
    ap.add_argument("--out", default="results/triptych-suite")
    ap.add_argument("--shapes", default="", help="comma-separated names (default: all present)")
    ap.add_argument("--intricate", default="{}", help="JSON object: the experiment's intricate section")
    ap.add_argument("--markdown", default="", help="also write the table to this file")
    a = ap.parse_args()
    wanted = [s for s in a.shapes.split(",") if s]
    os.makedirs(a.out, exist_ok=True)
    rows = []
    for name, mesh in shapes():
        if wanted and name not in wanted:
            continue
        exp = {
            "name": name,
            "seed": 1,
            "target": {"mesh": mesh, "resolution": 97},
            "optimizer": {"schedule": os.path.join(ROOT, "experiments/schedules/demo.json"), "absolute_every": 50},
            "mesh": {"resolution": 128, "iterations": 4, "vdb": False},
            "intricate": json.loads(a.intricate),
            "pictures": {"slice_iterations": 1},
        }
        path = os.path.join(a.out, name + ".json")
        with open(path, "w") as f:
            json.dump(exp, f, indent=1)
        t0 = time.time()
        r = subprocess.run([a.quijibo, "run", path, "--out", os.path.join(a.out, name), "--quiet"],
                           stderr=subprocess.PIPE, text=True)
        seconds = time.time() - t0
        if r.returncode != 0:
            print(f"{name}: quijibo run failed: {r.stderr.strip()}", file=sys.stderr)
            rows.append(f"| {name} | run failed: {r.stderr.strip()[:120]} |")
            continue
        t = json.load(open(os.path.join(a.out, name, "triptych/triptych.json")))
        isum = json.load(open(os.path.join(a.out, name, "intricate/summary.json")))
        msum = json.load(open(os.path.join(a.out, name, "mesh/summary.json")))
        fset = json.load(open(os.path.join(a.out, name, "fidelity/fidelity.json")))
        fint = t["figures"].get("intricate", {}).get("fidelity", {})

        def cells(summary, fid):
            d = summary.get("detail", {})
            n = fid.get("n_step", {})
            return (f"{d.get('area_ratio', 0):.2f}", f"{d.get('box_dimension', 0):.3f}",
                    f"{n.get('closed_iou', 0):.3f}", f"{n.get('iou', 0):.3f}", str(d.get("components", "–")))

        s, i = cells(msum, fset), cells(isum, fint)
        tr = isum.get("julia", {}).get("root_translation")
        tlen = f"{(tr[0] ** 2 + tr[1] ** 2 + tr[2] ** 2) ** 0.5:.3f}" if tr else isum.get("skipped", "–")
        rows.append(f"| {name} | {s[0]} / {i[0]} | {s[1]} / {i[1]} | {s[2]} / {i[2]} | {s[3]} / {i[3]} | "
                    f"{s[4]} / {i[4]} | {tlen} | {seconds:.0f} |")
        print(rows[-1], flush=True)
    head = ("| shape | area / target's (set / intricate) | box dimension | closed IoU | n = 4 IoU | components | "
            "translation t | run s |\n|---|---|---|---|---|---|---|---|")
    table = head + "\n" + "\n".join(rows) + "\n"
    print(table)
    if a.markdown:
        with open(a.markdown, "w") as f:
            f.write(table)


if __name__ == "__main__":
    main()
