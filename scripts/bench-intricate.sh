#!/usr/bin/env bash
# The intricate bunny meshed streamed at a large resolution, as benchmarks.md §28 measures it: makes
# bunny-intricate's optimized map (experiments/bunny-intricate.json with a 64³ mesh, no VDB, no
# pictures), then runs `quijibo mesh … --stream` under /usr/bin/time -v while sampling its resident
# set, CPU seconds and scratch files every 30 s.
#
#   scripts/bench-intricate.sh OUT_DIR [RESOLUTION [MESH_OPTION ...]]   (default 2048; build/experiments/quijibo)
#
# Options after the resolution go to `quijibo mesh` after bunny-intricate's settings, e.g.
# `--bisection-steps 0 --bisection-interpolate` (plain marching cubes: the same triangles, fewer
# evaluations; benchmarks.md §25, §28).
#
# OUT_DIR gets map.json (reused when present), bunny<RES>.ply, summary.json, time.txt (time -v) and
# samples.log (time, VmRSS and VmHWM in kB, CPU s, scratch bytes). At 2048³ the run takes hours on 2
# cores (§28): start it on an idle machine and run nothing else CPU-bound beside it.
set -euo pipefail
here="$(cd "$(dirname "$0")/.." && pwd)"
out=${1:?usage: scripts/bench-intricate.sh OUT_DIR [RESOLUTION [MESH_OPTION ...]]}
res=${2:-2048}
shift $(( $# < 2 ? $# : 2 ))
quijibo=${QUIJIBO:-$here/build/experiments/quijibo}
[ -x "$quijibo" ] || { echo "bench-intricate: $quijibo not found: build first (scripts/build.sh) or set QUIJIBO" >&2; exit 1; }
mkdir -p "$out"
out="$(cd "$out" && pwd)"

if [ ! -f "$out/map.json" ]; then
  /usr/bin/python3 - "$here" "$out/experiment.json" <<'EOF'
import json, os, sys
here, dest = sys.argv[1], sys.argv[2]
base = os.path.join(here, "experiments")
e = json.load(open(os.path.join(base, "bunny-intricate.json")))
e["target"]["mesh"] = os.path.normpath(os.path.join(base, e["target"]["mesh"]))
e["optimizer"]["schedule"] = os.path.normpath(os.path.join(base, e["optimizer"]["schedule"]))
e["mesh"]["resolution"] = 64
e["mesh"]["vdb"] = False
e["pictures"] = {"enabled": False}
json.dump(e, open(dest, "w"), indent=1)
EOF
  "$quijibo" run "$out/experiment.json" -o "$out/run" --quiet
  cp "$out/run/optimized/map.json" "$out/map.json"
fi

# The mesh stage's settings of bunny-intricate.json.
settings=(-n 4 --detail 4 --iteration-frame reference --translate 0,0,1 --translate-potential -2)
/usr/bin/time -v -o "$out/time.txt" "$quijibo" -q mesh "$out/map.json" -o "$out/bunny$res.ply" "${settings[@]}" \
  --resolution "$res" --stream --summary "$out/summary.json" "$@" &
timer=$!
: > "$out/samples.log"
while kill -0 "$timer" 2>/dev/null; do
  pid=$(pgrep -P "$timer" -x quijibo || true)
  if [ -n "$pid" ] && [ -r "/proc/$pid/status" ]; then
    rss=$(awk '/VmRSS|VmHWM/ {printf "%s %s ", $1, $2}' "/proc/$pid/status" 2>/dev/null || true)
    cpu=$(awk '{print ($14 + $15) / 100}' "/proc/$pid/stat" 2>/dev/null || true)
    scratch=$(for fd in /proc/$pid/fd/*; do
                case "$(readlink "$fd" 2>/dev/null)" in *"(deleted)") stat -L -c %s "$fd" 2>/dev/null ;; esac
              done | tr '\n' ' ')
    echo "$(date -u +%H:%M:%S) ${rss}cpu_s=$cpu scratch_bytes=$scratch" >> "$out/samples.log"
  fi
  sleep 30
done
wait "$timer"
grep -E "Elapsed|Maximum resident|User time|System time" "$out/time.txt"
/usr/bin/python3 -c "import json,sys; s=json.load(open(sys.argv[1])); print('triangles', s['triangles'], 'vertices', s['vertices'])" \
  "$out/summary.json"
