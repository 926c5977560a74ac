#pragma once
// tvf under mpirun (DESIGN §12 "MPI"; docs/architecture.md, "What a command loads"): the
// distributed solve lives in tvf-mpi beside tvf (PETSc and MPI are linked there alone), and
// tvf launched by an MPI launcher runs it in its own place (execv: same pid, same command
// line, same environment), before anything else. Nothing where this is tvf-mpi itself, where
// the process was not launched by mpirun, or where the build has no distributed solve
// (TVF_MPI off: every rank then runs as one process, as before). When tvf-mpi cannot be
// started, says so in one sentence and exits with status 1.
namespace tvf::cli {

void run_mpi_program_if_launched(char** argv);

}  // namespace tvf::cli
