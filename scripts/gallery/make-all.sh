#!/usr/bin/env bash
# Regenerates every gallery picture of docs/gallery.md into docs/images/gallery/ (work files in
# results/gallery/). Needs the build (./scripts/build.sh: build/experiments/quijibo, quijibo-fields
# and the Python module) and /usr/bin/python3 with numpy and matplotlib.
#   scripts/gallery/make-all.sh            # everything (time: see docs/gallery.md)
#   scripts/gallery/make-all.sh 2015-3 2023-8   # some figures only
# GALLERY_SCALE=test makes tiny versions (tests/python/test_gallery.py); GALLERY_IMAGES / GALLERY_WORK move the outputs.
set -euo pipefail
cd "$(dirname "$0")/../.."
export PYTHONPATH="${QUIJIBO_BUILD_DIR:-build}/python${PYTHONPATH:+:$PYTHONPATH}"
py() { /usr/bin/python3 "scripts/gallery/$1" "${@:2}"; }
declare -A FIG=(
  [2015-3]="qj2015_roots.py 3" [2015-4]="qj2015_roots.py 4" [2015-5]="qj2015_roots.py 5"
  [2015-6]="qj2015_bunny.py" [2015-7]="qj2015_weights.py" [2015-8]="qj2015_potential.py"
  [2023-2]="sm2023_tooth.py 2" [2023-3]="sm2023_tooth.py 3" [2023-8]="sm2023_average.py"
  [2023-9]="sm2023_bunny.py 9" [2023-10]="sm2023_bunny.py 10" [2023-11]="sm2023_bunny.py 11"
  [2023-12]="sm2023_bunny.py 12" [2024-2]="portals2024.py 2" [2024-3]="portals2024.py 3" [2024-7]="portals2024.py 7"
  [2024-8]="portals2024.py 8"
)
ORDER=(2015-3 2015-4 2015-5 2015-6 2015-7 2015-8 2023-2 2023-3 2023-8 2023-9 2023-10 2023-11 2023-12
       2024-2 2024-3 2024-7 2024-8)
[ $# -gt 0 ] && ORDER=("$@")
start=$SECONDS
for f in "${ORDER[@]}"; do
  [ -n "${FIG[$f]:-}" ] || { echo "make-all: unknown figure $f (known: ${!FIG[*]})" >&2; exit 1; }
  echo "== $f"
  t=$SECONDS
  # shellcheck disable=SC2086
  py ${FIG[$f]}
  echo "   $f: $((SECONDS - t)) s"
done
echo "make-all: $((SECONDS - start)) s"
