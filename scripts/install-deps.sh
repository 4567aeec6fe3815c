#!/usr/bin/env bash
# Installs the Debian 12 packages quijibo needs to build, test and plot, and report.html's viewer
# (three.js, web/package.json) from npm. Idempotent; run as root.
set -euo pipefail
cd "$(dirname "$0")/.."
PACKAGES=(
  build-essential cmake ninja-build pkg-config
  libeigen3-dev liblbfgspp-dev libceres-dev
  libboost-dev libboost-iostreams-dev
  libopenvdb-dev libtbb-dev
  nlohmann-json3-dev libcli11-dev libpng-dev
  libgtest-dev
  gnuplot-nox
  libassimp-dev libembree-dev
  ffmpeg
  mpi-default-dev mpi-default-bin
  pybind11-dev python3-dev python3-numpy python3-pytest python3-matplotlib
  libmeshoptimizer-dev libcmark-gfm-dev libcmark-gfm-extensions-dev
  chromium
)
# node and npm (report.html's viewer): Debian's unless a node is already installed.
command -v npm >/dev/null || PACKAGES+=(nodejs npm)
missing=()
for p in "${PACKAGES[@]}"; do
  dpkg-query -W -f='${Status}' "$p" 2>/dev/null | grep -q "install ok installed" || missing+=("$p")
done
if ((${#missing[@]})); then
  echo "quijibo: installing ${missing[*]}" >&2
  export DEBIAN_FRONTEND=noninteractive
  apt-get update -qq
  apt-get install -y -qq --no-install-recommends "${missing[@]}" >/dev/null
fi
# three.js (bundled into report.html at build time) and playwright-core (the browser test), as pinned
# by web/package-lock.json; again only when the lock changed.
if [[ ! -f web/node_modules/.package-lock.json || web/package-lock.json -nt web/node_modules/.package-lock.json ]]; then
  echo "quijibo: installing web/ (npm ci)" >&2
  (cd web && npm ci --no-audit --no-fund --loglevel=error)
fi
