#include "mpi_exec.h"

#include "tvf/solve/distributed.h"

#include <unistd.h>

#include <cerrno>
#include <cstdio>
#include <cstdlib>
#include <cstring>
#include <filesystem>
#include <system_error>

namespace fs = std::filesystem;

namespace tvf::cli {

void run_mpi_program_if_launched([[maybe_unused]] char** argv) {
#ifdef TVF_MPI_PROGRAM
  if (distributed_built() || !distributed_launched()) return;
  std::error_code ec;
  const fs::path self = fs::read_symlink("/proc/self/exe", ec);
  const fs::path program = ec ? fs::path(TVF_MPI_PROGRAM) : self.parent_path() / TVF_MPI_PROGRAM;
  execv(program.c_str(), argv);  // returns only when it failed
  const int error = errno;
  std::fprintf(stderr,
               "tvf: error: launched by mpirun, but %s, the program that runs the distributed solve, cannot be "
               "started (%s): build or install it beside tvf (CMake option TVF_MPI)\n",
               program.c_str(), std::strerror(error));
  std::exit(1);
#endif
}

}  // namespace tvf::cli
