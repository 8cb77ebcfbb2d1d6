#!/usr/bin/env bash
# Install the Debian packages engage builds and runs with (Debian 12; run as root). report.html
# inlines three.js and dygraphs (libjs-three, libjs-dygraphs); the tests open it in chromium and
# run a batch on a one-node Slurm (slurm-wlm, munge) and compare the reader with LinuxCNC's rs274
# (linuxcnc-uspace); the thin-cut tests subtract exact swept hulls
# with CGAL (libcgal-dev, headers only).
set -euo pipefail
packages=(
  cmake make g++ ccache
  libeigen3-dev libtbb-dev libopenvdb-dev libopenvdb-tools zlib1g-dev libboost-iostreams-dev
  libopenmesh-dev libcli11-dev nlohmann-json3-dev libpolyclipping-dev catch2 gnuplot-nox libcgal-dev
  pybind11-dev python3-dev python3-numpy python3-pytest python3-matplotlib
  libjs-three libjs-dygraphs chromium python3-pil slurm-wlm munge linuxcnc-uspace
)
missing=()
for p in "${packages[@]}"; do
  dpkg-query -W -f='${Status}' "$p" 2>/dev/null | grep -q "install ok installed" || missing+=("$p")
done
if [ ${#missing[@]} -gt 0 ]; then
  echo "install-deps: installing ${missing[*]}"
  apt-get update
  DEBIAN_FRONTEND=noninteractive apt-get install -y --no-install-recommends "${missing[@]}"
fi
