#!/usr/bin/env bash
# Installs the Debian 12 packages quijibo needs to build, test and plot. Idempotent; run as root.
set -euo pipefail
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
)
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
