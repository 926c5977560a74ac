#!/usr/bin/env bash
# Installs every Debian package tvf needs to build, test, benchmark and render.
# Usage: scripts/install-deps.sh   (as root, or with sudo available)
set -euo pipefail
packages=(
  build-essential cmake ninja-build pkg-config
  ccache                 # cheap rebuilds of unchanged files
  libeigen3-dev          # dense/sparse linear algebra
  libsuitesparse-dev     # CHOLMOD sparse Cholesky
  libtbb-dev             # parallel frames
  libopenblas-dev        # BLAS of CHOLMOD's supernodal factorization (run-time AVX dispatch)
  nlohmann-json3-dev     # scene JSON
  libcli11-dev           # command line
  libfmt-dev libspdlog-dev
  libcgal-dev            # OBJ/PLY/OFF reading (polygon soups) and mesh repair
  libcairo2-dev          # plots and texture frames (SVG, PNG)
  libegl-dev libgles-dev libegl-mesa0 libgl1-mesa-dri  # offscreen OpenGL ES (EGL surfaceless, llvmpipe): surface pictures
  libnanoflann-dev libjpeg62-turbo-dev  # texture synthesis: kd-tree search, JPEG exemplars
  ffmpeg                 # MP4 video (tvf render texture -o OUT.mp4) and ffprobe for the tests
  libgmp-dev libmpfr-dev # required by CGAL headers
  libgtest-dev libgmock-dev libbenchmark-dev
  python3 python3-numpy python3-vtk9 python3-jsonschema  # tests read our outputs with NumPy, VTK and jsonschema
  libcgal-demo           # CGAL's sample meshes: the real surfaces of examples/04 (no meshes in git)
  libcpp-httplib-dev     # tvf serve: the designer's HTTP server
  python3-dev pybind11-dev python3-pytest  # the Python module `tvf` (python/) and its tests
  libopenvdb-dev         # tvf export --vdb: OpenVDB velocity grids for Houdini and Blender
  python3-openvdb        # the tests read the VDB files back with OpenVDB's own reader
  chromium               # the designer's end-to-end test (web/e2e, playwright-core drives it)
  petsc-dev libopenmpi-dev openmpi-bin  # the distributed space-time solve (CMake TVF_MPI, `mpirun -n K tvf generate`): PETSc's KSP over MPI
  clang libclang-rt-14-dev valgrind  # the fuzz targets (libFuzzer, preset "fuzz", scripts/fuzz.sh) and memory checks
)
# The designer's front end (web/) is built with npm; a Node.js that brings its own npm
# (e.g. NodeSource's) is kept as it is.
command -v npm >/dev/null 2>&1 || packages+=(nodejs npm)
sudo_cmd=()
if [ "$(id -u)" -ne 0 ]; then sudo_cmd=(sudo); fi
missing=()
for p in "${packages[@]}"; do
  dpkg-query -W -f='${Status}' "$p" 2>/dev/null | grep -q "install ok installed" || missing+=("$p")
done
if [ ${#missing[@]} -eq 0 ]; then
  echo "install-deps: all ${#packages[@]} packages present"
else
  echo "install-deps: installing ${missing[*]}"
  export DEBIAN_FRONTEND=noninteractive
  "${sudo_cmd[@]}" apt-get update -qq
  "${sudo_cmd[@]}" apt-get install -y -qq --no-install-recommends "${missing[@]}"
fi

# The example meshes come out of libcgal-demo's data archive (the Stanford bunny as
# CGAL ships it); they are extracted next to the example scenes and ignored by git.
root=$(cd "$(dirname "$0")/.." && pwd)
archive=/usr/share/doc/libcgal-dev/data.tar.gz
target="$root/examples/04_surface_mesh/bunny.off"
if [ ! -s "$target" ]; then
  if [ ! -f "$archive" ]; then
    echo "install-deps: $archive is missing (package libcgal-demo)" >&2
    exit 1
  fi
  tmp=$(mktemp -d)
  tar -xzf "$archive" -C "$tmp" data/meshes/bunny00.off
  mv "$tmp/data/meshes/bunny00.off" "$target"
  rm -rf "$tmp"
  echo "install-deps: extracted the example mesh $target"
fi
