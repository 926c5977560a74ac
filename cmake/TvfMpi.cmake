# The distributed space-time solve (issue 19, DESIGN §12 "MPI"): PETSc (Debian's petsc-dev,
# real scalars) over MPI (libopenmpi-dev, openmpi-bin). Optional: without them the build is
# the single-process one, unchanged. On by default where both are found (pkg-config
# `PETSc`, CMake's FindMPI), off under the sanitizers and fuzzing (MPI's own allocations
# are not ours to check).
find_package(PkgConfig REQUIRED)
pkg_check_modules(PETSC QUIET IMPORTED_TARGET PETSc)
find_package(MPI QUIET COMPONENTS CXX)
if(PETSC_FOUND AND MPI_CXX_FOUND AND NOT TVF_SANITIZE AND NOT TVF_FUZZ)
  set(tvf_mpi_default ON)
else()
  set(tvf_mpi_default OFF)
endif()
option(TVF_MPI "Build the distributed space-time solve (PETSc + MPI; `mpirun -n K tvf generate`)" ${tvf_mpi_default})
if(TVF_MPI AND NOT (PETSC_FOUND AND MPI_CXX_FOUND))
  message(FATAL_ERROR "TVF_MPI needs PETSc and MPI: install the Debian packages "
                      "'petsc-dev libopenmpi-dev openmpi-bin' (scripts/install-deps.sh) or configure with -DTVF_MPI=OFF")
endif()
if(TVF_MPI)
  message(STATUS "tvf: distributed solve on PETSc ${PETSC_VERSION} and MPI (${MPIEXEC_EXECUTABLE})")
endif()
