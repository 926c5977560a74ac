#pragma once
// The distributed space-time solve (solve/distributed.h; docs/architecture.md, "Running on
// a cluster"): private to libtvf, called by SpaceTimeSolver::solve under mpirun.
#include "tvf/solve/spacetime.h"

#include <string>
#include <vector>

namespace tvf {

// Solves the space-time system of SpaceTimeSolver::solve (same arguments, same meaning of
// fixed, values and z, all replicated on every rank) on all ranks of the running session:
// each rank owns a part of the vertices (PETSc's MatPartitioning on L's graph) with their
// whole temporal lines; PETSc's CG on the matrix-free operator (real form, re and im
// interleaved), preconditioned as the one process's CG (options.coarse_modes > 0: the low
// temporal modes' spatial systems by CG + GAMG, the local solve on the cut lines when
// options.local_rings ≥ 0, the temporal line solves; flexible CG; coarse_modes = 0: the
// line solves alone, plain CG), to options.tolerance in the one process's residual
// ‖b − A z‖ / ‖b‖ over the free entries. z receives the whole
// result on every rank. values may be z itself (its fixed entries holding the fixed
// values): the generator passes it so, to hold one replicated field less per rank.
// Collective: every rank must call it with the same arguments.
SolveReport petsc_spacetime_solve(const ConnectionLaplacian& laplacian, int frames, double temporal_weight,
                                  std::span<const char> fixed, std::span<const cplx> values, std::span<cplx> z,
                                  const SpaceTimeOptions& options);

// The rank that owns each vertex in the partition the solve uses (collective; for tests and
// benchmarks), and its cut: the edges of L's graph between two ranks.
struct PetscPartition {
  std::vector<int> owner;
  long cut_edges = 0, edges = 0;
  std::string partitioner;
};
PetscPartition petsc_partition(const ConnectionLaplacian& laplacian);

}  // namespace tvf
