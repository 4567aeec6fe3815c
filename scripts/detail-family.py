#!/usr/bin/env python3
"""The detail family of a map (docs/meshing.md "Detail", "Root translation"): for each setting,
`quijibo mesh`, `quijibo fidelity` and a render; then a Markdown table and one picture with a row
per setting. A setting is a detail value, or detail:potential for a root translation along z by
potential (`--translate-potential`).

  /usr/bin/python3 scripts/detail-family.py --map results/bunny-paper/optimized/map.json \
      --target results/bunny-paper/initial/target.qgrid --shape data/bunny.obj \
      --details 0,2,8,16 -r 256 --out results/detail-family --figure docs/images/detail-family.png
  ... --details 0.25,4,4:-3,4:-2.5,4:-2 --iteration-frame reference   (smooth to intricate)

Existing meshes in --out are reused (delete them to mesh again)."""
import argparse, json, os, subprocess, sys

def main():
    p = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    p.add_argument("--map", required=True)
    p.add_argument("--target", required=True, help="the run's initial/target.qgrid")
    p.add_argument("--shape", required=True, help="the target mesh")
    p.add_argument("--details", default="0,2,8,16")
    p.add_argument("--iteration-frame", default="map", choices=["map", "reference"])
    p.add_argument("-r", "--resolution", type=int, default=256)
    p.add_argument("-n", "--iterations", type=int, default=4)
    p.add_argument("--out", default="results/detail-family")
    p.add_argument("--figure", help="the picture (PNG) with a row of views per detail value")
    p.add_argument("--quijibo", default=os.path.join(os.path.dirname(__file__), "..", "build", "experiments", "quijibo"))
    a = p.parse_args()
    os.makedirs(a.out, exist_ok=True)
    rows, pictures = [], []
    for setting in a.details.split(","):
        d, _, pot = setting.partition(":")
        d = float(d)
        extra = ["--detail", f"{d:g}", "--iteration-frame", a.iteration_frame]
        if pot:
            extra += ["--translate-potential", pot]
        name = os.path.join(a.out, f"detail-{d:g}" + (f"-potential{pot}" if pot else "") +
                            ("-reference" if a.iteration_frame == "reference" else ""))
        if not os.path.exists(name + ".ply"):
            subprocess.run([a.quijibo, "--quiet", "mesh", a.map, "-r", str(a.resolution), "-n", str(a.iterations),
                            "-o", name + ".ply", "--summary", name + ".summary.json"] + extra, check=True)
        fid = subprocess.run([a.quijibo, "--quiet", "fidelity", "-m", a.map, "-t", a.target, "--julia", name + ".ply",
                              "--shape", a.shape, "-n", str(a.iterations)] + extra,
                             check=True, capture_output=True, text=True).stdout
        f, s = json.loads(fid), json.load(open(name + ".summary.json"))
        subprocess.run([a.quijibo, "--quiet", "picture", "render", name + ".ply", "-o", name + ".png", "--size", "300"],
                       check=True, capture_output=True)
        pictures.append(name + ".png")
        t = s["julia"]["root_translation"][2]
        rows.append((f"{d:g}" + (f" : {pot}" if pot else ""), s["iteration_frame"]["lambda"], f"{t:.3f}",
                     s["triangles"], f["detail"]["components"], f["detail"]["area_ratio"],
                     f["detail"]["box_dimension"], f["one_step"]["iou"], f["n_step"]["iou"], f["n_step"]["closed_iou"],
                     f["n_step"]["leak"], s["seconds"]))
    print(f"| detail (% of size) : potential | λ | translation z | triangles | components | area / target's | "
          f"box dimension | one-step IoU | n = {a.iterations} IoU | closed IoU | leak | mesh s |")
    print("|---|---:|---:|---:|---:|---:|---:|---:|---:|---:|---:|---:|")
    for r in rows:
        print(f"| {r[0]} | {r[1]:.4f} | {r[2]} | {r[3]:,} | {r[4]} | {r[5]:.2f} | {r[6]:.3f} | {r[7]:.3f} | "
              f"{r[8]:.3f} | {r[9]:.3f} | {r[10]:.3f} | {r[11]:.0f} |")
    if a.figure:
        from PIL import Image
        ims = [Image.open(x).convert("RGB") for x in pictures]
        w, h = max(i.width for i in ims), sum(i.height for i in ims)
        sheet = Image.new("RGB", (w, h), "white")
        y = 0
        for i in ims:
            sheet.paste(i, (0, y))
            y += i.height
        sheet.save(a.figure)
        print(f"\n{a.figure}: rows top to bottom: detail {a.details}", file=sys.stderr)

if __name__ == "__main__":
    main()
