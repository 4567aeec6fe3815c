#!/usr/bin/env bash
# README command 1: install what is missing, build, and run the quick demo experiment on the
# shipped bunny from mesh to fractal (experiments/bunny-demo.json; docs/experiments.md). Results in
# results/bunny-demo/. A rerun reuses the stages whose inputs did not change.
set -euo pipefail
cd "$(dirname "$0")/.."
./scripts/install-deps.sh
./scripts/build.sh
OUT=results/bunny-demo
./build/experiments/quijibo run experiments/bunny-demo.json --out "$OUT"
echo
echo "quijibo: done. Look at:"
echo "  $OUT/report.md                  one page: roots, energies, per-pass table, times, the images"
echo "  $OUT/report.html                the same page with a 3D viewer of the meshes (open it in a browser)"
echo "  $OUT/initial/potential.png      the potential and the monopoles (top roots blue, bottom red)"
echo "  $OUT/plot/convergence.png       the energy per step (psi+1)/2, like the paper's Fig. 11"
echo "  $OUT/pictures/slice-n1.png      the one-step set against the bunny on z = 0 (orange: set only, blue: bunny only)"
echo "  $OUT/pictures/render.png        the Julia set of the optimized map, shaded"
echo "  $OUT/mesh/julia.ply, julia.vdb  the mesh (bunny's original coordinates) and the volume"
echo "  $OUT/optimized/summary.json     per-pass stop reasons, times and energies"
