#!/usr/bin/env bash
# Installs every Debian package tvf needs to build, test, benchmark and render.
# Usage: scripts/install-deps.sh   (as root, or with sudo available)
set -euo pipefail
packages=(
  build-essential cmake ninja-build pkg-config
  libeigen3-dev          # dense/sparse linear algebra
  libsuitesparse-dev     # CHOLMOD sparse Cholesky
  libtbb-dev             # parallel frames
  nlohmann-json3-dev     # scene JSON
  libcli11-dev           # command line
  libfmt-dev libspdlog-dev
  libcgal-dev            # OBJ/PLY/OFF reading (polygon soups) and mesh repair
  libgmp-dev libmpfr-dev # required by CGAL headers
  libgtest-dev libgmock-dev libbenchmark-dev
  python3 python3-numpy python3-vtk9 python3-jsonschema  # tests read our outputs with NumPy, VTK and jsonschema
)
sudo_cmd=()
if [ "$(id -u)" -ne 0 ]; then sudo_cmd=(sudo); fi
missing=()
for p in "${packages[@]}"; do
  dpkg-query -W -f='${Status}' "$p" 2>/dev/null | grep -q "install ok installed" || missing+=("$p")
done
if [ ${#missing[@]} -eq 0 ]; then
  echo "install-deps: all ${#packages[@]} packages present"
  exit 0
fi
echo "install-deps: installing ${missing[*]}"
export DEBIAN_FRONTEND=noninteractive
"${sudo_cmd[@]}" apt-get update -qq
"${sudo_cmd[@]}" apt-get install -y -qq --no-install-recommends "${missing[@]}"
