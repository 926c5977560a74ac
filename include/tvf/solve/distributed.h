#pragma once
// Running under MPI (issue 19, DESIGN §12 "MPI"): `mpirun -n K tvf generate SCENE -o DIR`.
//
// Every rank runs the whole program on the whole scene (domain, Laplacian: per vertex);
// the spacetime generator's problem and solve are shared (design/generate.cpp,
// solve/petsc_spacetime.cpp: vertices partitioned across ranks with whole temporal lines
// each; the constraints evaluated by frames, each frame sent out in the ranks' shares;
// PETSc's flexible CG on the matrix-free operator, preconditioned as one process's CG: low
// temporal modes whose spatial systems GAMG solves, a local solve on the lines a moving
// constraint cuts, then the temporal line solves). Its result is gathered on rank 0 alone,
// where what follows (edits, projection) runs as in one process; the other ranks keep
// their shares. Rank 0 writes the assembled outputs (npy, native, csv, json); with K > 1
// ranks each rank writes its own piece of every VTK frame (field_NNNN_pR.vtu) and rank 0 the
// .pvtu files that join them (docs/architecture.md, "Running on a cluster").
//
// MPI and PETSc are started only where the process was launched by an MPI launcher
// (mpirun/mpiexec of OpenMPI or MPICH, srun with PMI): a plain `tvf` run, the Python
// module and `tvf serve` never touch MPI.

#include "tvf/core/types.h"
#include "tvf/field/field.h"

#include <cstddef>
#include <span>
#include <string>
#include <vector>

namespace tvf {

// Whether this program has the distributed back end: true in tvf-mpi and the MPI tests
// (CMake option TVF_MPI; src/CMakeLists.txt, tvf_petsc), false in libtvf's own
// single-process stubs, which tvf and the Python module link.
bool distributed_built();
// Whether the process was launched by an MPI launcher (mpirun/mpiexec of OpenMPI or MPICH,
// srun with PMI): its environment variables. tvf then runs tvf-mpi in its place (apps/tvf).
bool distributed_launched();

// Starts MPI and PETSc for the lifetime of the object where the process was launched by an
// MPI launcher and the build has the back end; otherwise does nothing. One per process
// (the CLI's main). PETSc reads its options from the environment (PETSC_OPTIONS), not
// from the command line, which stays the CLI's.
class DistributedSession {
public:
  DistributedSession();
  ~DistributedSession();
  DistributedSession(const DistributedSession&) = delete;
  DistributedSession& operator=(const DistributedSession&) = delete;
  bool active() const { return active_; }

private:
  bool active_ = false;
};

// The number of ranks of the running session (1 without one) and this process's rank (0
// without one): rank 0 writes the assembled outputs and prints the report.
int distributed_ranks();
int distributed_rank();
// Whether a session is running (launched by mpirun, even with one rank): generators then
// solve with the PETSc back end (SpaceTimeOptions::distributed).
bool distributed_active();

// Generators whose frames are independent (the per-frame `constrained` generator) share
// them: frame j is computed by rank j mod K. Without a session every frame is this
// process's. (Frames in blocks of B, as the constrained generator solves them: block b,
// frames bB … bB + B − 1, by rank b mod K; pass b.)
bool distributed_owns_frame(int frame);
// After every rank computed its frames: each frame sent from its rank to all (data is
// frames × vertices_per_frame, frame-major); frames_per_block B as above. Collective;
// nothing without a session.
void distributed_share_frames(std::span<cplx> data, size_t vertices_per_frame, int frames, int frames_per_block = 1);
// Whether `ok` holds on every rank (collective; `ok` itself without a session).
bool distributed_all(bool ok);
// The largest of x over the ranks (collective; x itself without a session).
double distributed_max(double x);
// Rank 0's `s` on every rank (collective; `s` itself without a session).
std::string distributed_broadcast(const std::string& s);

// The spacetime generator under mpirun leaves the field whole on rank 0 alone (the gather
// step: the assembled outputs need it) and each rank its own share, the vertices it owns in
// the solve's partition (distributed_vertex_owners) at every frame. Whether such a share is
// kept on every rank (after that generator ran; false without a session):
bool distributed_has_share();
// After rank 0 changed the field (the scene's edits, the incompressible projection): its
// values sent back into every rank's share, frame by frame. Collective; `field` is read on
// rank 0 only.
void distributed_refresh_share(const Field& field);
// The field's values at `points` (any vertices, e.g. a VTK piece's own and halo vertices),
// frames × points.size(), frame-major, from the ranks' shares: each rank's own from its
// share, the others' received from their ranks (a PETSc VecScatter). Collective; every
// rank passes its own points (possibly none).
std::vector<cplx> distributed_share_values(std::span<const int> points);

// Which rank owns each of `vertices` vertices, for the per-rank VTK pieces: the partition
// of this process's last distributed space-time solve where it had that many vertices,
// otherwise (the per-frame generators, no solve) contiguous blocks of vertex indices,
// ranks × v / vertices. All zeros with one rank. The same on every rank.
std::vector<int> distributed_vertex_owners(int vertices);

}  // namespace tvf
