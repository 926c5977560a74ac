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

// The partition of the distributed solve, made before the problem so that each rank builds
// its own share of it only (the spacetime generator under mpirun: design/generate.cpp):
// every rank owns a part of the vertices with their whole temporal lines; a rank's share of
// a space-time array is frames × owned.size(), frame-major, its vertices in `owned` order
// (ascending). Collective; the same on every rank but `rank` and `owned`.
struct VertexShares {
  int rank = 0, ranks = 1;
  std::vector<int> owner;  // per vertex: its rank
  std::vector<int> local;  // per vertex: its index among its rank's vertices
  std::vector<int> count;  // per rank: how many vertices it owns
  std::vector<int> owned;  // this rank's vertices, ascending
  long cut_edges = 0;      // edges of L's graph between two ranks
  std::string partitioner;
};
VertexShares petsc_vertex_shares(const ConnectionLaplacian& laplacian);

// petsc_spacetime_solve on the ranks' shares (see VertexShares): fixed and z are this rank's
// shares of the fixed marks and of the first guess, which holds the fixed values at the
// fixed entries (the temporal interpolation); z receives the rank's share of the result.
// The other ranks' values the operator needs (the halo) are exchanged inside. Collective.
SolveReport petsc_spacetime_solve_shares(const ConnectionLaplacian& laplacian, const VertexShares& shares,
                                         int frames, double temporal_weight, std::span<const char> fixed,
                                         std::span<cplx> z, const SpaceTimeOptions& options);

// The gather step: every rank's share (frames × its owned vertices) into `field` on rank 0
// (frames × all vertices; empty elsewhere), frame by frame (MPI_Gatherv: rank 0 holds one
// frame of the ranks' values beside the field). Collective.
void petsc_gather_to_root(const VertexShares& shares, std::span<const cplx> share, int frames,
                          std::span<cplx> field);

// The constraints' evaluation, distributed by frames: rank `root` evaluated a whole frame
// (fixed marks and values of every vertex, read on root only); each rank receives its share
// of it. Collective.
void petsc_scatter_frame(const VertexShares& shares, int root, std::span<const char> fixed,
                         std::span<const cplx> values, std::span<char> fixed_share, std::span<cplx> values_share);

// Keeps this rank's share of the generated field (the per-rank VTK pieces are written from
// it: distributed_share_values in solve/distributed.h). One kept at a time; every rank keeps
// its own.
void petsc_keep_share(VertexShares shares, std::vector<cplx> share, int frames);

// The rank that owns each vertex in the partition the solve uses (collective; for tests and
// benchmarks), and its cut: the edges of L's graph between two ranks.
struct PetscPartition {
  std::vector<int> owner;
  long cut_edges = 0, edges = 0;
  std::string partitioner;
};
PetscPartition petsc_partition(const ConnectionLaplacian& laplacian);

}  // namespace tvf
