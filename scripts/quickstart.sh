#!/usr/bin/env bash
# README command 1: install what is missing, build, and run the main job on the shipped default.
# Until the full pipeline exists, the main job is the precision benchmark on its quick setting.
set -euo pipefail
cd "$(dirname "$0")/.."
./scripts/install-deps.sh
./scripts/build.sh
mkdir -p results
./build/experiments/quijibo bench precision --quick \
  --json results/bench-precision.json --markdown results/bench-precision.md
echo
echo "quijibo: the table above is in results/bench-precision.md (JSON: results/bench-precision.json)."
echo "quijibo: the full benchmark is 'build/experiments/quijibo bench precision'; see docs/benchmarks.md."
