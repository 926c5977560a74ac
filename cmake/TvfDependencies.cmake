# Every dependency comes from a Debian package (scripts/install-deps.sh installs them).
# A missing one stops configuration with the name of the package to install.
macro(tvf_require pkg debian)
  find_package(${pkg} ${ARGN} QUIET)
  if(NOT ${pkg}_FOUND)
    message(FATAL_ERROR "tvf needs ${pkg}: install the Debian package '${debian}' (or run scripts/install-deps.sh)")
  endif()
endmacro()

tvf_require(Eigen3 libeigen3-dev 3.4 NO_MODULE)
tvf_require(TBB libtbb-dev)
tvf_require(nlohmann_json nlohmann-json3-dev)
tvf_require(CLI11 libcli11-dev)
tvf_require(fmt libfmt-dev)
tvf_require(CGAL libcgal-dev)
set(CGAL_DO_NOT_WARN_ABOUT_CMAKE_BUILD_TYPE TRUE)

find_package(Threads REQUIRED)
find_package(PkgConfig REQUIRED)
pkg_check_modules(CAIRO QUIET IMPORTED_TARGET cairo)
if(NOT CAIRO_FOUND)
  message(FATAL_ERROR "tvf needs Cairo: install the Debian package 'libcairo2-dev' (or run scripts/install-deps.sh)")
endif()
# Texture synthesis: nearest-neighbourhood search (nanoflann) and JPEG exemplars (libjpeg).
tvf_require(nanoflann libnanoflann-dev)
pkg_check_modules(JPEG QUIET IMPORTED_TARGET libjpeg)
if(NOT JPEG_FOUND)
  message(FATAL_ERROR "tvf needs libjpeg: install the Debian package 'libjpeg62-turbo-dev' (or run scripts/install-deps.sh)")
endif()
# Dense products of the temporal-mode solver: OpenBLAS picks its AVX2/AVX-512 kernels at
# run time, so one portable build runs at the machine's speed.
pkg_check_modules(OPENBLAS QUIET IMPORTED_TARGET openblas)
if(NOT OPENBLAS_FOUND)
  message(FATAL_ERROR "tvf needs OpenBLAS: install the Debian package 'libopenblas-dev' (or run scripts/install-deps.sh)")
endif()
# Sparse Cholesky: CHOLMOD (SuiteSparse), supernodal LLᴴ with BLAS kernels, for the
# per-frame constrained solves (solve/connection_laplacian.h). Debian 12's SuiteSparse 5.12
# installs neither a CMake config nor a pkg-config file, so the header and the libraries
# are looked up directly (libcholmod links AMD, COLAMD, METIS and the BLAS itself).
find_path(TVF_CHOLMOD_INCLUDE_DIR cholmod.h PATH_SUFFIXES suitesparse)
find_library(TVF_CHOLMOD_LIBRARY cholmod)
find_library(TVF_SUITESPARSECONFIG_LIBRARY suitesparseconfig)
if(NOT TVF_CHOLMOD_INCLUDE_DIR OR NOT TVF_CHOLMOD_LIBRARY OR NOT TVF_SUITESPARSECONFIG_LIBRARY)
  message(FATAL_ERROR "tvf needs CHOLMOD: install the Debian package 'libsuitesparse-dev' (or run scripts/install-deps.sh)")
endif()
# The libraries as a target; the headers (TVF_CHOLMOD_INCLUDE_DIR) are added to the few
# sources that include them (src/CMakeLists.txt, bench/CMakeLists.txt).
add_library(tvf_cholmod INTERFACE IMPORTED)
target_link_libraries(tvf_cholmod INTERFACE ${TVF_CHOLMOD_LIBRARY} ${TVF_SUITESPARSECONFIG_LIBRARY})
# Offscreen OpenGL for surface pictures (render/mesh_renderer.h): OpenGL ES 3 through
# EGL's surfaceless platform on Mesa (llvmpipe on machines without a GPU).
pkg_check_modules(EGL QUIET IMPORTED_TARGET egl glesv2)
if(NOT EGL_FOUND)
  message(FATAL_ERROR "tvf needs EGL and OpenGL ES: install the Debian packages 'libegl-dev libgles-dev libegl-mesa0 libgl1-mesa-dri' (or run scripts/install-deps.sh)")
endif()

# The designer's HTTP server (tvf serve).
pkg_check_modules(HTTPLIB QUIET IMPORTED_TARGET GLOBAL cpp-httplib)
if(NOT HTTPLIB_FOUND)
  message(FATAL_ERROR "tvf serve needs cpp-httplib: install the Debian package 'libcpp-httplib-dev' (or run scripts/install-deps.sh)")
endif()

if(TVF_BUILD_TESTS)
  tvf_require(GTest libgtest-dev)
  # Tests that read our outputs with NumPy and VTK's own readers use Debian's python3
  # (python3-numpy, python3-vtk9), not whatever python3 comes first on PATH.
  find_program(TVF_PYTHON NAMES python3 PATHS /usr/bin NO_DEFAULT_PATH)
  if(NOT TVF_PYTHON)
    find_program(TVF_PYTHON NAMES python3)
  endif()
endif()
if(TVF_BUILD_BENCH)
  tvf_require(benchmark libbenchmark-dev)
endif()

# OpenVDB export of planar fields (field/animation_export.h, `tvf export --vdb`): Debian's
# libopenvdb-dev, installed by scripts/install-deps.sh. Optional: without it tvf builds and
# `tvf export --vdb` says which package to install. Its own FindOpenVDB.cmake would bring
# a FindTBB that fights TBB's config, so the header and libraries are looked up directly
# (libopenvdb needs Imath's half tables at link time).
find_path(TVF_OPENVDB_INCLUDE_DIR openvdb/openvdb.h)
find_library(TVF_OPENVDB_LIBRARY openvdb)
pkg_check_modules(IMATH QUIET IMPORTED_TARGET Imath)
if(TVF_OPENVDB_INCLUDE_DIR AND TVF_OPENVDB_LIBRARY AND IMATH_FOUND)
  set(TVF_HAVE_OPENVDB ON)
  add_library(tvf_openvdb INTERFACE IMPORTED)
  target_link_libraries(tvf_openvdb INTERFACE ${TVF_OPENVDB_LIBRARY} PkgConfig::IMATH TBB::tbb)
else()
  set(TVF_HAVE_OPENVDB OFF)
  message(WARNING "OpenVDB not found: `tvf export --vdb` is disabled (install the Debian package 'libopenvdb-dev', "
                  "or run scripts/install-deps.sh)")
endif()

# The Python module (python/, DESIGN §12): pybind11 and NumPy from Debian. Not built with
# the sanitizers (an ASan extension cannot be imported by a Python without ASan preloaded).
if(TVF_BUILD_PYTHON)
  # Debian's python3 (where python3-numpy is), not whatever python3 comes first on PATH.
  if(NOT Python3_EXECUTABLE AND EXISTS /usr/bin/python3)
    set(Python3_EXECUTABLE /usr/bin/python3)
  endif()
  find_package(Python3 COMPONENTS Interpreter Development.Module QUIET)
  if(NOT Python3_FOUND)
    message(FATAL_ERROR "tvf's Python module needs Python 3 headers: install the Debian package 'python3-dev' "
                        "(or run scripts/install-deps.sh; -DTVF_BUILD_PYTHON=OFF skips the module)")
  endif()
  tvf_require(pybind11 pybind11-dev CONFIG)
endif()
