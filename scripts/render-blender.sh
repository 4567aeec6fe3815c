#!/usr/bin/env bash
# Renders a mesh or a .vdb level set with Blender's Cycles, as the papers' figures look (soft area
# light, sky, shadow on white; scripts/blender-render.py has the options). Needs Blender (Debian's
# `blender`), not quijibo.
#   scripts/render-blender.sh IN.ply|IN.obj|IN.stl|IN.vdb -o OUT.png [--samples N] [--size WxH]
#                             [--color clay|paper|#RRGGBB] [--up y] [--view AZ EL] [--threads N]
set -euo pipefail
BLENDER=${BLENDER:-blender}
if ! command -v "$BLENDER" >/dev/null; then
  echo "render-blender.sh: Blender is not installed (apt-get install blender, or set BLENDER=/path/to/blender)" >&2
  exit 1
fi
if (($# == 0)) || [[ "$1" == "-h" || "$1" == "--help" ]]; then
  exec "$BLENDER" -b --factory-startup --python-exit-code 1 -P "$(dirname "$0")/blender-render.py" -- --help
fi
# Blender prints its own progress on stdout: keep it in a log, show it only when the render fails.
log=$(mktemp)
trap 'rm -f "$log"' EXIT
if "$BLENDER" -b --factory-startup --python-exit-code 1 -P "$(dirname "$0")/blender-render.py" -- "$@" >"$log" 2>&1; then
  grep '^blender-render:' "$log"
else
  grep '^blender-render:' "$log" >&2 || tail -n 30 "$log" >&2
  exit 1
fi
