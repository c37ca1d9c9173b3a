#!/usr/bin/env bash
# Installs what dpts needs on Debian 12 (idempotent, non-interactive), builds Release into
# build/, and prepares the sample DEM. Run from anywhere; uses sudo when not root.
set -euo pipefail
root=$(cd "$(dirname "${BASH_SOURCE[0]}")/.." && pwd)
cd "$root"
packages=(build-essential cmake ninja-build libcgal-dev libboost-dev libgmp-dev libmpfr-dev
          libeigen3-dev libtbb-dev libgdal-dev gdal-bin catch2 libbenchmark-dev time python3 bc
          gnuplot-nox openmpi-bin libopenmpi-dev  # gnuplot: bench/scaling_sizes.sh; MPI: dpts-mpi
          python3-dev python3-pybind11 python3-numpy python3-pytest)  # the Python module
sudo=""
[[ $(id -u) -eq 0 ]] || sudo="sudo"
missing=()
for p in "${packages[@]}"; do
  dpkg-query -W -f='${Status}' "$p" 2>/dev/null | grep -q "install ok installed" || missing+=("$p")
done
if ((${#missing[@]})); then
  echo "setup: installing ${missing[*]}"
  $sudo apt-get update -qq
  DEBIAN_FRONTEND=noninteractive $sudo apt-get install -y -qq --no-install-recommends "${missing[@]}" >/dev/null
fi
cmake -S . -B build -G Ninja -DCMAKE_BUILD_TYPE=Release >/dev/null
# CGAL translation units need ~1 GB of compiler memory each: two jobs fit a 2-core machine.
cmake --build build -j 2
data/prepare_sample.sh
