#!/usr/bin/env bash
# scripts/render-blender.sh where Blender is installed (it is optional, and not in CI): a mesh and a
# .vdb level set each render to a PNG of the asked size that shows the shape on a white ground (a
# tenth or more of the pixels darker than the background, the corners white), and bad input fails
# with one line. Exit 77 (ctest: skipped) without Blender.
#   blender_render_test.sh SOURCE_DIR QUIJIBO_BINARY WORK_DIR
set -euo pipefail
src=$1 quijibo=$2 work=$3
if ! command -v "${BLENDER:-blender}" >/dev/null; then
  echo "blender_render: SKIPPED: Blender is not installed (optional: apt-get install blender)"
  exit 77
fi
rm -rf "$work" && mkdir -p "$work"
render=$src/scripts/render-blender.sh
"$quijibo" --quiet sdf "$src/data/bunny.obj" -r 32 -o "$work/bunny.qgrid" --vdb "$work/bunny.vdb" >/dev/null
"$render" "$src/data/bunny.obj" -o "$work/mesh.png" --size 96x72 --samples 4
"$render" "$work/bunny.vdb" -o "$work/volume.png" --size 96x72 --samples 4
/usr/bin/python3 - "$work/mesh.png" "$work/volume.png" <<'PY'
import sys
import matplotlib.image as image
for path in sys.argv[1:]:
    a = image.imread(path)[..., :3]
    assert a.shape[:2] == (72, 96), f"{path}: {a.shape}"
    corners = [a[0, 0], a[0, -1], a[-1, -1]]
    assert all(c.min() > 0.9 for c in corners), f"{path}: the background is not white: {corners}"
    dark = (a.mean(axis=2) < 0.85).mean()
    assert dark > 0.1, f"{path}: only {dark:.1%} of the picture shows the shape"
    print(f"ok {path}: {dark:.0%} of the pixels show the shape")
PY
if "$render" "$work/missing.ply" -o "$work/x.png" 2>"$work/err.txt"; then
  echo "FAIL: a missing file rendered"; exit 1
fi
grep -q "missing.ply: no such file" "$work/err.txt" || { echo "FAIL: no message"; cat "$work/err.txt"; exit 1; }
echo "blender_render: passed"
