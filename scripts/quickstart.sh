#!/usr/bin/env bash
# README command 1: install what is missing, build, and run the main job on the shipped default:
# the bunny from mesh to fractal on a short schedule (a few minutes on 2 cores). Results in
# results/bunny/. (The JSON experiment runner of issue 7 will replace this script's stages.)
set -euo pipefail
cd "$(dirname "$0")/.."
./scripts/install-deps.sh
./scripts/build.sh
Q=./build/experiments/quijibo
OUT=results/bunny
rm -rf "$OUT"
mkdir -p "$OUT/initial"
echo "quijibo: 1/5 initial guess (SDF, BEM, monopoles, ln C scan)"
$Q monopoles data/bunny.obj -o "$OUT/initial" > "$OUT/initial/monopoles.out"
echo "quijibo: 2/5 optimization, schedule experiments/schedules/demo.json"
$Q optimize -t "$OUT/initial/target.qgrid" -m "$OUT/initial/map.json" \
  -s experiments/schedules/demo.json -o "$OUT/optimized" --absolute-every 50 > "$OUT/optimized.out"
echo "quijibo: 3/5 convergence plot"
$Q plot "$OUT/optimized/log.jsonl" -o "$OUT/convergence"
echo "quijibo: 4/5 meshing the Julia set (n = 4, 192^3)"
$Q mesh "$OUT/optimized/map.json" -n 4 -r 192 -o "$OUT/julia.ply" --vdb "$OUT/julia.vdb" --summary "$OUT/mesh-summary.json"
echo "quijibo: 5/5 pictures"
$Q picture render "$OUT/julia.ply" -o "$OUT/julia-render.png"
$Q picture slice "$OUT/optimized/map.json" --target "$OUT/initial/target.qgrid" -n 1 -o "$OUT/slice-n1.png"
echo
echo "quijibo: done. Look at:"
echo "  $OUT/initial/potential.png     the potential and the monopoles (top roots blue, bottom red)"
echo "  $OUT/convergence.png           the energy per step (psi+1)/2, like the paper's Fig. 11"
echo "  $OUT/slice-n1.png             the one-step set against the bunny on z = 0 (orange: set only, blue: bunny only)"
echo "  $OUT/julia-render.png          the Julia set of the optimized map, shaded"
echo "  $OUT/julia.ply, julia.vdb      the mesh (bunny's original coordinates) and the volume"
echo "  $OUT/optimized/summary.json    per-pass stop reasons, times and energies"
