#include "solve/petsc_spacetime.h"

// Compiled twice (src/CMakeLists.txt): into libtvf without TVF_HAVE_PETSC (the
// single-process stubs), and as tvf_petsc with TVF_HAVE_PETSC=1 (the distributed back end of
// tvf-mpi and the MPI tests). Both define the same symbols.
#ifndef TVF_HAVE_PETSC
#define TVF_HAVE_PETSC 0
#endif

#include "solve/spacetime_coarse.h"
#include "tvf/core/error.h"
#include "tvf/solve/distributed.h"

#include <fmt/format.h>

#include <algorithm>
#include <cstdlib>
#include <string>
#include <vector>

#if TVF_HAVE_PETSC
#include <mpi.h>
#include <petscksp.h>
#include <petscmat.h>

#include <algorithm>
#include <cmath>
#include <limits>
#include <string>
#include <vector>
#endif

namespace tvf {

namespace {

int g_ranks = 1;
int g_rank = 0;
bool g_active = false;

}  // namespace

bool distributed_built() { return TVF_HAVE_PETSC != 0; }
// An MPI launcher's environment: OpenMPI's mpirun, MPICH's/Hydra's mpiexec (PMI), PMIx
// (Slurm's srun, OpenMPI 5).
bool distributed_launched() {
  for (const char* v : {"OMPI_COMM_WORLD_SIZE", "PMI_SIZE", "PMIX_RANK", "PMI_RANK"})
    if (std::getenv(v) != nullptr) return true;
  return false;
}
int distributed_ranks() { return g_ranks; }
int distributed_rank() { return g_rank; }
bool distributed_active() { return g_active; }
bool distributed_owns_frame(int frame) { return frame % g_ranks == g_rank; }

namespace {
// The partition of the last distributed space-time solve (distributed_vertex_owners).
std::vector<int> g_last_owner;
// This rank's share of the generated field (petsc_keep_share): frames × its owned vertices.
VertexShares g_shares;
std::vector<cplx> g_share;
size_t g_share_frames = 0;
bool g_has_share = false;
}  // namespace

bool distributed_has_share() { return g_has_share; }

void petsc_keep_share(VertexShares shares, std::vector<cplx> share, int frames) {
  g_shares = std::move(shares);
  g_share = std::move(share);
  g_share_frames = static_cast<size_t>(frames);
  g_has_share = true;
}

std::vector<int> distributed_vertex_owners(int vertices) {
  if (g_ranks > 1 && g_last_owner.size() == static_cast<size_t>(vertices)) return g_last_owner;
  std::vector<int> owner(static_cast<size_t>(std::max(vertices, 0)), 0);
  for (int v = 0; v < vertices; ++v)
    owner[static_cast<size_t>(v)] =
        static_cast<int>(static_cast<long long>(g_ranks) * v / std::max(vertices, 1));
  return owner;
}

#if !TVF_HAVE_PETSC

DistributedSession::DistributedSession() = default;
DistributedSession::~DistributedSession() = default;

SolveReport petsc_spacetime_solve(const ConnectionLaplacian&, int, double, std::span<const char>,
                                  std::span<const cplx>, std::span<cplx>, const SpaceTimeOptions&) {
  TVF_CHECK(false, "this build has no distributed solve (configure with -DTVF_MPI=ON; needs petsc-dev and "
                   "libopenmpi-dev)");
  return {};
}

VertexShares petsc_vertex_shares(const ConnectionLaplacian&) {
  TVF_CHECK(false, "this build has no distributed solve");
  return {};
}

SolveReport petsc_spacetime_solve_shares(const ConnectionLaplacian&, const VertexShares&, int, double,
                                         std::span<const char>, std::span<cplx>, const SpaceTimeOptions&) {
  TVF_CHECK(false, "this build has no distributed solve");
  return {};
}

void petsc_gather_to_root(const VertexShares&, std::span<const cplx>, int, std::span<cplx>) {
  TVF_CHECK(false, "this build has no distributed solve");
}

void petsc_scatter_frame(const VertexShares&, int, std::span<const char>, std::span<const cplx>, std::span<char>,
                         std::span<cplx>) {
  TVF_CHECK(false, "this build has no distributed solve");
}

void distributed_refresh_share(const Field&) {}
std::vector<cplx> distributed_share_values(std::span<const int>) {
  TVF_CHECK(false, "this build has no distributed solve");
  return {};
}

void distributed_share_frames(std::span<cplx>, size_t, int, int) {}
bool distributed_all(bool ok) { return ok; }
double distributed_max(double x) { return x; }
std::string distributed_broadcast(const std::string& s) { return s; }

PetscPartition petsc_partition(const ConnectionLaplacian& laplacian) {
  PetscPartition p;
  p.owner.assign(static_cast<size_t>(laplacian.matrix.rows()), 0);
  return p;
}

#else

namespace {

void check(PetscErrorCode code, const char* what) {
  if (code != 0) throw Error(fmt::format("PETSc failed in {} (error {})", what, static_cast<int>(code)));
}

}  // namespace

DistributedSession::DistributedSession() {
  if (!distributed_launched()) return;
  // PETSc's options come from PETSC_OPTIONS only: the command line is the CLI's. Its signal
  // handlers stay off (the CLI removes its staging folders on SIGINT/SIGTERM itself).
  check(PetscOptionsSetValue(nullptr, "-no_signal_handler", nullptr), "PetscOptionsSetValue");
  int argc = 1;
  char name[] = "tvf";
  char* args[] = {name, nullptr};
  char** argv = args;
  check(PetscInitialize(&argc, &argv, nullptr, nullptr), "PetscInitialize");
  MPI_Comm_size(PETSC_COMM_WORLD, &g_ranks);
  MPI_Comm_rank(PETSC_COMM_WORLD, &g_rank);
  active_ = g_active = true;
}

void distributed_share_frames(std::span<cplx> data, size_t vertices_per_frame, int frames, int frames_per_block) {
  if (!g_active || g_ranks == 1) return;
  TVF_CHECK(data.size() == vertices_per_frame * static_cast<size_t>(frames), "{} values for {} frames of {}",
            data.size(), frames, vertices_per_frame);
  for (int j = 0; j < frames; ++j)
    MPI_Bcast(data.data() + static_cast<size_t>(j) * vertices_per_frame, static_cast<int>(2 * vertices_per_frame),
              MPI_DOUBLE, (j / std::max(1, frames_per_block)) % g_ranks, PETSC_COMM_WORLD);
}

bool distributed_all(bool ok) {
  if (!g_active) return ok;
  int v = ok ? 1 : 0;
  MPI_Allreduce(MPI_IN_PLACE, &v, 1, MPI_INT, MPI_MIN, PETSC_COMM_WORLD);
  return v != 0;
}

double distributed_max(double x) {
  if (!g_active) return x;
  MPI_Allreduce(MPI_IN_PLACE, &x, 1, MPI_DOUBLE, MPI_MAX, PETSC_COMM_WORLD);
  return x;
}

std::string distributed_broadcast(const std::string& s) {
  if (!g_active || g_ranks == 1) return s;
  unsigned long long size = s.size();
  MPI_Bcast(&size, 1, MPI_UNSIGNED_LONG_LONG, 0, PETSC_COMM_WORLD);
  std::string out = g_rank == 0 ? s : std::string(static_cast<size_t>(size), '\0');
  if (size > 0) MPI_Bcast(out.data(), static_cast<int>(size), MPI_CHAR, 0, PETSC_COMM_WORLD);
  return out;
}

DistributedSession::~DistributedSession() {
  if (!active_) return;
  g_ranks = 1;
  g_rank = 0;
  g_active = false;
  PetscFinalize();
}

namespace {

using RowMatrix = Eigen::SparseMatrix<cplx, Eigen::RowMajor>;

// The coarse correction's spatial solves: to the one process's relative residual (solve/
// spacetime.cpp: kCoarseTolerance), or this many iterations.
constexpr double kCoarseTolerance = 1e-2;
constexpr int kCoarseIterations = 200;
// The local solve on the cut lines: to the one process's kLocalTolerance, or this many
// iterations.
constexpr double kLocalTolerance = 1e-1;
constexpr int kLocalIterations = 50;

// Which rank owns each vertex (VertexShares, from PETSc's partitioner on L's graph:
// PT-Scotch in Debian's PETSc; PETSC_OPTIONS=-mat_partitioning_type ... picks another), and
// what the solve derives from it for `nf` frames.
struct Distribution : VertexShares {
  int size = 1;                 // = ranks
  std::vector<PetscInt> first;  // per rank: its first row of the global vector
  std::vector<int> ghosts;      // other ranks' vertices next to this rank's, ascending
};

VertexShares partition_vertices(const RowMatrix& rows, MPI_Comm comm) {
  VertexShares d;
  MPI_Comm_rank(comm, &d.rank);
  MPI_Comm_size(comm, &d.ranks);
  const auto n = static_cast<PetscInt>(rows.rows());
  // The adjacency graph, rows split evenly in the input's order for the partitioner.
  const PetscInt lo = n * d.rank / d.ranks, hi = n * (d.rank + 1) / d.ranks;
  PetscInt* ia = nullptr;
  PetscInt* ja = nullptr;
  PetscInt nnz = 0;
  for (PetscInt i = lo; i < hi; ++i)
    for (RowMatrix::InnerIterator it(rows, i); it; ++it) nnz += it.col() != i;
  check(PetscMalloc1(hi - lo + 1, &ia), "PetscMalloc1");
  check(PetscMalloc1(std::max<PetscInt>(nnz, 1), &ja), "PetscMalloc1");
  ia[0] = 0;
  PetscInt k = 0;
  for (PetscInt i = lo; i < hi; ++i) {
    for (RowMatrix::InnerIterator it(rows, i); it; ++it)
      if (it.col() != i) ja[k++] = static_cast<PetscInt>(it.col());
    ia[i - lo + 1] = k;
  }
  Mat adj = nullptr;
  check(MatCreateMPIAdj(comm, hi - lo, n, ia, ja, nullptr, &adj), "MatCreateMPIAdj");  // owns ia, ja
  MatPartitioning part = nullptr;
  check(MatPartitioningCreate(comm, &part), "MatPartitioningCreate");
  check(MatPartitioningSetAdjacency(part, adj), "MatPartitioningSetAdjacency");
  check(MatPartitioningSetType(part, d.ranks > 1 ? MATPARTITIONINGPTSCOTCH : MATPARTITIONINGCURRENT),
        "MatPartitioningSetType");
  check(MatPartitioningSetFromOptions(part), "MatPartitioningSetFromOptions");
  MatPartitioningType type = nullptr;
  check(MatPartitioningGetType(part, &type), "MatPartitioningGetType");
  d.partitioner = type;
  IS parts = nullptr, all = nullptr;
  check(MatPartitioningApply(part, &parts), "MatPartitioningApply");
  check(ISAllGather(parts, &all), "ISAllGather");
  const PetscInt* owner = nullptr;
  check(ISGetIndices(all, &owner), "ISGetIndices");
  d.owner.assign(owner, owner + n);
  check(ISRestoreIndices(all, &owner), "ISRestoreIndices");
  ISDestroy(&all);
  ISDestroy(&parts);
  MatPartitioningDestroy(&part);
  MatDestroy(&adj);

  d.count.assign(static_cast<size_t>(d.ranks), 0);
  d.local.resize(static_cast<size_t>(n));
  for (PetscInt v = 0; v < n; ++v) {
    const auto r = static_cast<size_t>(d.owner[static_cast<size_t>(v)]);
    d.local[static_cast<size_t>(v)] = d.count[r]++;
    if (static_cast<int>(r) == d.rank) d.owned.push_back(static_cast<int>(v));
  }
  for (PetscInt v = 0; v < n; ++v)
    for (RowMatrix::InnerIterator it(rows, v); it; ++it)
      if (it.col() > v && d.owner[static_cast<size_t>(it.col())] != d.owner[static_cast<size_t>(v)]) ++d.cut_edges;
  return d;
}

Distribution distribution_of(const VertexShares& shares, const RowMatrix& rows, size_t nf) {
  Distribution d;
  static_cast<VertexShares&>(d) = shares;
  d.size = d.ranks;
  const auto n = static_cast<PetscInt>(rows.rows());
  TVF_CHECK(d.owner.size() == static_cast<size_t>(n), "a partition of {} vertices for {}", d.owner.size(), n);
  d.first.assign(static_cast<size_t>(d.size), 0);
  for (size_t r = 1; r < d.first.size(); ++r)
    d.first[r] = d.first[r - 1] + static_cast<PetscInt>(2 * nf) * d.count[r - 1];
  std::vector<char> ghost(static_cast<size_t>(n), 0);
  for (const int v : d.owned)
    for (RowMatrix::InnerIterator it(rows, v); it; ++it)
      if (d.owner[static_cast<size_t>(it.col())] != d.rank) ghost[static_cast<size_t>(it.col())] = 1;
  for (PetscInt v = 0; v < n; ++v)
    if (ghost[static_cast<size_t>(v)]) d.ghosts.push_back(static_cast<int>(v));
  return d;
}

Distribution distribute(const RowMatrix& rows, size_t nf, MPI_Comm comm) {
  return distribution_of(partition_vertices(rows, comm), rows, nf);
}

// This rank's part of the space-time operator A_FF (and of its preconditioner): local
// vectors are frame-major over the owned vertices, complex entries as (re, im) pairs, the
// one-process layout restricted to this rank. Column c ≥ 0 is an owned vertex, c < 0 the
// ghost −c − 1.
struct LocalSystem {
  size_t nl = 0, ng = 0, nf = 0;
  double b = 0;
  std::vector<int> row_start, column;
  std::vector<cplx> value;
  std::vector<double> diagonal, weight_sum;
  std::vector<char> fixed;    // nf × nl
  std::vector<double> pivot;  // the temporal lines' elimination (nf × nl): 1 / its pivots
  // The elimination's off-diagonal factors, recomputed from fixed and weight_sum where
  // used rather than stored (two fewer arrays of nf × nl doubles per rank):
  // lower(k) = −b·w_i where the previous frame's entry is free, else 0; upper(k) =
  // −b·w_i · pivot(k) where the next frame's entry is free, else 0.
  double lower(size_t j, size_t i) const {
    return j > 0 && !fixed[(j - 1) * nl + i] ? -b * weight_sum[i] : 0.0;
  }
  double upper(size_t j, size_t i) const {
    return j + 1 < nf && !fixed[(j + 1) * nl + i] ? -b * weight_sum[i] * pivot[j * nl + i] : 0.0;
  }
  Vec ghost = nullptr;                      // nf × ng ghost values (sequential)
  VecScatter scatter = nullptr;             // global → ghost
  std::vector<char> ghost_fixed;            // nf × ng

  // The coarse correction (SpaceTimeOptions::coarse_modes > 0; solve/spacetime_coarse.h):
  // the low temporal modes' spatial systems E_m y_m = g_m, assembled in the real 2 × 2 block
  // form as one block-diagonal system over this rank's vertices (mode-major: the rank's
  // rows of mode 0, then of mode 1, ...) and solved by one KSP (CG with GAMG by default,
  // options prefix tvf_coarse_): one set of reductions and halo exchanges for all modes.
  struct Mode {
    size_t first = 0;
    Eigen::VectorXd q;  // over the segment's frames
  };
  std::vector<Mode> modes;
  std::vector<std::vector<std::pair<size_t, size_t>>> frame_modes;  // per frame: (mode, index in its segment)
  Mat coarse = nullptr;
  KSP coarse_ksp = nullptr;
  Vec coarse_g = nullptr, coarse_y = nullptr;  // modes × 2·nl reals: the restriction, the solution
  Vec coarse_ghost = nullptr;                  // modes × 2·ng reals: y at the ghost vertices
  VecScatter coarse_scatter = nullptr;         // coarse_y → coarse_ghost
  std::vector<cplx> prolonged;                                      // 3 frames of nl + ng
  long coarse_iterations = 0;

  // The local solve after the coarse correction (SpaceTimeOptions::local_rings ≥ 0): the
  // vertices whose temporal line a moving constraint cuts (Ω, grown by local_rings rings),
  // solved together over all frames, zero around them, by a KSP (CG with the line solves)
  // on a vector of Ω's lines (vertex-major: the rank's Ω vertices' lines one after the other).
  struct Cut {
    size_t count = 0;                       // the rank's Ω vertices
    size_t ghosts = 0;                      // other ranks' Ω vertices next to the rank's vertices
    std::vector<int> vertex;                // per Ω vertex of the rank: its owned index
    std::vector<int> start, column;         // its Ω neighbours: ≥ 0 the rank's, < 0 the ghost −c − 1
    std::vector<cplx> value;
    std::vector<int> touched;               // owned vertices outside Ω next to Ω: owned index
    std::vector<int> touched_start, touched_column;  // their Ω neighbours (as column above)
    std::vector<cplx> touched_value;
    Mat a = nullptr;
    KSP ksp = nullptr;
    Vec r = nullptr, x = nullptr;           // 2·nf·count reals
    Vec ghost = nullptr;                    // 2·nf·ghosts reals
    VecScatter scatter = nullptr;
    long iterations = 0;
  } cut;

  ~LocalSystem() {
    KSPDestroy(&coarse_ksp);
    MatDestroy(&coarse);
    VecDestroy(&coarse_g);
    VecDestroy(&coarse_y);
    VecDestroy(&coarse_ghost);
    VecScatterDestroy(&coarse_scatter);
    KSPDestroy(&cut.ksp);
    MatDestroy(&cut.a);
    VecDestroy(&cut.r);
    VecDestroy(&cut.x);
    VecDestroy(&cut.ghost);
    VecScatterDestroy(&cut.scatter);
    VecScatterDestroy(&scatter);
    VecDestroy(&ghost);
  }
};

PetscErrorCode apply_operator(Mat a, Vec x, Vec y) {
  LocalSystem* s = nullptr;
  PetscCall(MatShellGetContext(a, &s));
  PetscCall(VecScatterBegin(s->scatter, x, s->ghost, INSERT_VALUES, SCATTER_FORWARD));
  PetscCall(VecScatterEnd(s->scatter, x, s->ghost, INSERT_VALUES, SCATTER_FORWARD));
  const PetscScalar *xa = nullptr, *ga = nullptr;
  PetscScalar* ya = nullptr;
  PetscCall(VecGetArrayRead(x, &xa));
  PetscCall(VecGetArrayRead(s->ghost, &ga));
  PetscCall(VecGetArray(y, &ya));
  const auto* xs = reinterpret_cast<const cplx*>(xa);
  const auto* gs = reinterpret_cast<const cplx*>(ga);
  auto* ys = reinterpret_cast<cplx*>(ya);
  const size_t nl = s->nl, ng = s->ng, nf = s->nf;
  for (size_t j = 0; j < nf; ++j) {
    const cplx* xj = xs + j * nl;
    const cplx* gj = gs + j * ng;
    for (size_t i = 0; i < nl; ++i) {
      const size_t k = j * nl + i;
      if (s->fixed[k]) {
        ys[k] = 0;
        continue;
      }
      cplx acc = s->diagonal[i] * xs[k];
      for (int e = s->row_start[i]; e < s->row_start[i + 1]; ++e) {
        const int c = s->column[static_cast<size_t>(e)];
        acc += s->value[static_cast<size_t>(e)] * (c >= 0 ? xj[c] : gj[-c - 1]);
      }
      cplx t(0, 0);
      if (j > 0) t += xs[k] - xs[k - nl];
      if (j + 1 < nf) t += xs[k] - xs[k + nl];
      ys[k] = acc + s->b * s->weight_sum[i] * t;
    }
  }
  PetscCall(VecRestoreArray(y, &ya));
  PetscCall(VecRestoreArrayRead(s->ghost, &ga));
  PetscCall(VecRestoreArrayRead(x, &xa));
  return 0;
}

// Every owned vertex's temporal line solved exactly (Thomas), fixed entries splitting it:
// the one process's preconditioner, with no communication. os may be rs (in place).
void line_solve(const LocalSystem& s, const cplx* rs, cplx* os) {
  const size_t nl = s.nl, nf = s.nf;
  for (size_t i = 0; i < nl; ++i) os[i] = rs[i] * s.pivot[i];
  for (size_t j = 1; j < nf; ++j)
    for (size_t i = 0; i < nl; ++i) {
      const size_t k = j * nl + i;
      os[k] = (rs[k] - s.lower(j, i) * os[k - nl]) * s.pivot[k];
    }
  for (size_t j = nf - 1; j-- > 0;)
    for (size_t i = 0; i < nl; ++i) {
      const size_t k = j * nl + i;
      os[k] -= s.upper(j, i) * os[k + nl];
    }
}

PetscErrorCode apply_line_solves(PC pc, Vec r, Vec out) {
  LocalSystem* s = nullptr;
  PetscCall(PCShellGetContext(pc, &s));
  const PetscScalar* ra = nullptr;
  PetscScalar* oa = nullptr;
  PetscCall(VecGetArrayRead(r, &ra));
  PetscCall(VecGetArray(out, &oa));
  line_solve(*s, reinterpret_cast<const cplx*>(ra), reinterpret_cast<cplx*>(oa));
  PetscCall(VecRestoreArray(out, &oa));
  PetscCall(VecRestoreArrayRead(r, &ra));
  return 0;
}

// y = A x on Ω's lines (Dirichlet zero around Ω): one vertex's line, xs the rank's Ω lines,
// gs the ghosts' (nf each).
void cut_row(const LocalSystem& s, const cplx* xs, const cplx* gs, size_t li, cplx* y) {
  const LocalSystem::Cut& c = s.cut;
  const size_t nf = s.nf, nl = s.nl;
  const auto i = static_cast<size_t>(c.vertex[li]);
  const double w = s.b * s.weight_sum[i];
  const cplx* xi = xs + li * nf;
  for (size_t j = 0; j < nf; ++j) {
    cplx t = s.diagonal[i] * xi[j];
    if (j > 0) t += w * (xi[j] - xi[j - 1]);
    if (j + 1 < nf) t += w * (xi[j] - xi[j + 1]);
    y[j] = t;
  }
  for (int e = c.start[li]; e < c.start[li + 1]; ++e) {
    const int col = c.column[static_cast<size_t>(e)];
    const cplx v = c.value[static_cast<size_t>(e)];
    const cplx* xc = col >= 0 ? xs + static_cast<size_t>(col) * nf : gs + static_cast<size_t>(-col - 1) * nf;
    for (size_t j = 0; j < nf; ++j) y[j] += v * xc[j];
  }
  for (size_t j = 0; j < nf; ++j)
    if (s.fixed[j * nl + i]) y[j] = 0;
}

PetscErrorCode apply_cut_operator(Mat a, Vec x, Vec y) {
  LocalSystem* s = nullptr;
  PetscCall(MatShellGetContext(a, &s));
  LocalSystem::Cut& c = s->cut;
  PetscCall(VecScatterBegin(c.scatter, x, c.ghost, INSERT_VALUES, SCATTER_FORWARD));
  PetscCall(VecScatterEnd(c.scatter, x, c.ghost, INSERT_VALUES, SCATTER_FORWARD));
  const PetscScalar *xa = nullptr, *ga = nullptr;
  PetscScalar* ya = nullptr;
  PetscCall(VecGetArrayRead(x, &xa));
  PetscCall(VecGetArrayRead(c.ghost, &ga));
  PetscCall(VecGetArray(y, &ya));
  for (size_t li = 0; li < c.count; ++li)
    cut_row(*s, reinterpret_cast<const cplx*>(xa), reinterpret_cast<const cplx*>(ga), li,
            reinterpret_cast<cplx*>(ya) + li * s->nf);
  PetscCall(VecRestoreArray(y, &ya));
  PetscCall(VecRestoreArrayRead(c.ghost, &ga));
  PetscCall(VecRestoreArrayRead(x, &xa));
  return 0;
}

// The line solves on Ω's lines (the global ones' rows).
PetscErrorCode apply_cut_lines(PC pc, Vec r, Vec out) {
  LocalSystem* s = nullptr;
  PetscCall(PCShellGetContext(pc, &s));
  const PetscScalar* ra = nullptr;
  PetscScalar* oa = nullptr;
  PetscCall(VecGetArrayRead(r, &ra));
  PetscCall(VecGetArray(out, &oa));
  const size_t nf = s->nf, nl = s->nl;
  for (size_t li = 0; li < s->cut.count; ++li) {
    const auto i = static_cast<size_t>(s->cut.vertex[li]);
    const auto* rs = reinterpret_cast<const cplx*>(ra) + li * nf;
    auto* os = reinterpret_cast<cplx*>(oa) + li * nf;
    os[0] = rs[0] * s->pivot[i];
    for (size_t j = 1; j < nf; ++j) os[j] = (rs[j] - s->lower(j, i) * os[j - 1]) * s->pivot[j * nl + i];
    for (size_t j = nf - 1; j-- > 0;) os[j] -= s->upper(j, i) * os[j + 1];
  }
  PetscCall(VecRestoreArray(out, &oa));
  PetscCall(VecRestoreArrayRead(r, &ra));
  return 0;
}

// The two-level preconditioner, the one process's (solve/spacetime.cpp, solve_cg):
// out = C r + M⁻¹ (r − A C r), C the coarse correction (restriction to the low temporal
// modes, their spatial solves, prolongation), M⁻¹ the line solves, with the local solve δ
// on the cut lines between them (below). C r is never stored
// whole: its frames are prolonged from the modes' solutions where used (three at a time
// for the product), so the preconditioner needs no space-time vector beside out.
PetscErrorCode apply_two_level(PC pc, Vec r, Vec out) {
  LocalSystem* s = nullptr;
  PetscCall(PCShellGetContext(pc, &s));
  const size_t nl = s->nl, ng = s->ng, nf = s->nf;
  const PetscScalar* ra = nullptr;
  PetscCall(VecGetArrayRead(r, &ra));
  const auto* rs = reinterpret_cast<const cplx*>(ra);
  // Restriction: g_m = Σ_j q_m(j) r_j over the mode's segment (r is zero at fixed entries).
  {
    PetscScalar* ga = nullptr;
    PetscCall(VecGetArray(s->coarse_g, &ga));
    for (size_t mi = 0; mi < s->modes.size(); ++mi) {
      const LocalSystem::Mode& m = s->modes[mi];
      auto* g = reinterpret_cast<cplx*>(ga) + mi * nl;
      std::fill(g, g + nl, cplx(0, 0));
      for (Eigen::Index jj = 0; jj < m.q.size(); ++jj) {
        const double q = m.q[jj];
        const cplx* rj = rs + (m.first + static_cast<size_t>(jj)) * nl;
        for (size_t i = 0; i < nl; ++i) g[i] += q * rj[i];
      }
    }
    PetscCall(VecRestoreArray(s->coarse_g, &ga));
  }
  // The modes' spatial solves, together (to the one process's coarse tolerance), then the
  // ghosts' values.
  PetscCall(KSPSolve(s->coarse_ksp, s->coarse_g, s->coarse_y));
  PetscInt coarse_it = 0;
  PetscCall(KSPGetIterationNumber(s->coarse_ksp, &coarse_it));
  s->coarse_iterations += coarse_it;
  PetscCall(VecScatterBegin(s->coarse_scatter, s->coarse_y, s->coarse_ghost, INSERT_VALUES, SCATTER_FORWARD));
  PetscCall(VecScatterEnd(s->coarse_scatter, s->coarse_y, s->coarse_ghost, INSERT_VALUES, SCATTER_FORWARD));
  const PetscScalar *cya = nullptr, *cga = nullptr;
  PetscCall(VecGetArrayRead(s->coarse_y, &cya));
  PetscCall(VecGetArrayRead(s->coarse_ghost, &cga));
  std::vector<const cplx*> ys(s->modes.size()), gys(s->modes.size());
  for (size_t m = 0; m < s->modes.size(); ++m) {
    ys[m] = reinterpret_cast<const cplx*>(cya) + m * nl;
    gys[m] = reinterpret_cast<const cplx*>(cga) + m * ng;
  }
  // Frame j of t = C r over the owned vertices, then the ghosts: Σ_m q_m(j) y_m, zero at
  // fixed entries.
  const size_t width = nl + ng;
  auto prolong = [&](size_t j, cplx* t) {
    std::fill(t, t + width, cplx(0, 0));
    for (const auto& [m, jj] : s->frame_modes[j]) {
      const double q = s->modes[m].q[static_cast<Eigen::Index>(jj)];
      for (size_t i = 0; i < nl; ++i) t[i] += q * ys[m][i];
      for (size_t g = 0; g < ng; ++g) t[nl + g] += q * gys[m][g];
    }
    for (size_t i = 0; i < nl; ++i)
      if (s->fixed[j * nl + i]) t[i] = 0;
    for (size_t g = 0; g < ng; ++g)
      if (s->ghost_fixed[j * ng + g]) t[nl + g] = 0;
  };
  PetscScalar* oa = nullptr;
  PetscCall(VecGetArray(out, &oa));
  auto* os = reinterpret_cast<cplx*>(oa);
  // out = r − A t, the operator's row formula on three prolonged frames.
  s->prolonged.resize(3 * width);
  cplx* prev = s->prolonged.data();
  cplx* cur = prev + width;
  cplx* next = cur + width;
  prolong(0, cur);
  if (nf > 1) prolong(1, next);
  for (size_t j = 0; j < nf; ++j) {
    for (size_t i = 0; i < nl; ++i) {
      const size_t k = j * nl + i;
      if (s->fixed[k]) {
        os[k] = 0;
        continue;
      }
      cplx acc = s->diagonal[i] * cur[i];
      for (int e = s->row_start[i]; e < s->row_start[i + 1]; ++e) {
        const int c = s->column[static_cast<size_t>(e)];
        acc += s->value[static_cast<size_t>(e)] * cur[c >= 0 ? static_cast<size_t>(c) : nl + static_cast<size_t>(-c - 1)];
      }
      cplx t(0, 0);
      if (j > 0) t += cur[i] - prev[i];
      if (j + 1 < nf) t += cur[i] - next[i];
      os[k] = rs[k] - (acc + s->b * s->weight_sum[i] * t);
    }
    std::swap(prev, cur);
    std::swap(cur, next);
    if (j + 2 < nf) prolong(j + 2, next);
  }
  // The local solve: δ ≈ A_ΩΩ⁻¹ (r − A t)_Ω, then out = r − A (t + δ).
  LocalSystem::Cut& c = s->cut;
  if (c.ksp != nullptr) {
    PetscScalar* ca = nullptr;
    PetscCall(VecGetArray(c.r, &ca));
    auto* cr = reinterpret_cast<cplx*>(ca);
    for (size_t li = 0; li < c.count; ++li)
      for (size_t j = 0; j < nf; ++j) cr[li * nf + j] = os[j * nl + static_cast<size_t>(c.vertex[li])];
    PetscCall(VecRestoreArray(c.r, &ca));
    PetscCall(KSPSolve(c.ksp, c.r, c.x));
    PetscInt it = 0;
    PetscCall(KSPGetIterationNumber(c.ksp, &it));
    c.iterations += it;
    PetscCall(VecScatterBegin(c.scatter, c.x, c.ghost, INSERT_VALUES, SCATTER_FORWARD));
    PetscCall(VecScatterEnd(c.scatter, c.x, c.ghost, INSERT_VALUES, SCATTER_FORWARD));
    const PetscScalar *xa = nullptr, *ga = nullptr;
    PetscCall(VecGetArrayRead(c.x, &xa));
    PetscCall(VecGetArrayRead(c.ghost, &ga));
    const auto* xs = reinterpret_cast<const cplx*>(xa);
    const auto* gs = reinterpret_cast<const cplx*>(ga);
    std::vector<cplx> row(nf);
    for (size_t li = 0; li < c.count; ++li) {
      cut_row(*s, xs, gs, li, row.data());
      const auto i = static_cast<size_t>(c.vertex[li]);
      for (size_t j = 0; j < nf; ++j) os[j * nl + i] -= row[j];  // zero at fixed entries
    }
    for (size_t ti = 0; ti < c.touched.size(); ++ti) {
      std::fill(row.begin(), row.end(), cplx(0, 0));
      for (int e = c.touched_start[ti]; e < c.touched_start[ti + 1]; ++e) {
        const int col = c.touched_column[static_cast<size_t>(e)];
        const cplx v = c.touched_value[static_cast<size_t>(e)];
        const cplx* xc = col >= 0 ? xs + static_cast<size_t>(col) * nf : gs + static_cast<size_t>(-col - 1) * nf;
        for (size_t j = 0; j < nf; ++j) row[j] += v * xc[j];
      }
      const auto i = static_cast<size_t>(c.touched[ti]);
      for (size_t j = 0; j < nf; ++j)
        if (!s->fixed[j * nl + i]) os[j * nl + i] -= row[j];
    }
    PetscCall(VecRestoreArrayRead(c.ghost, &ga));
    PetscCall(VecRestoreArrayRead(c.x, &xa));
  }
  // out = t + δ + M⁻¹ (r − A (t + δ)).
  line_solve(*s, os, os);
  for (size_t j = 0; j < nf; ++j) {
    prolong(j, cur);
    for (size_t i = 0; i < nl; ++i) os[j * nl + i] += cur[i];
  }
  if (c.ksp != nullptr) {
    const PetscScalar* xa = nullptr;
    PetscCall(VecGetArrayRead(c.x, &xa));
    const auto* xs = reinterpret_cast<const cplx*>(xa);
    for (size_t li = 0; li < c.count; ++li)
      for (size_t j = 0; j < nf; ++j) os[j * nl + static_cast<size_t>(c.vertex[li])] += xs[li * nf + j];
    PetscCall(VecRestoreArrayRead(c.x, &xa));
  }
  PetscCall(VecRestoreArray(out, &oa));
  PetscCall(VecRestoreArrayRead(s->coarse_ghost, &cga));
  PetscCall(VecRestoreArrayRead(s->coarse_y, &cya));
  PetscCall(VecRestoreArrayRead(r, &ra));
  return 0;
}

// The local solve's set-up (the one process's choice of Ω: vertices whose line has a fixed
// entry outside the key frames and a free entry, grown by `rings` rings of neighbours).
void set_up_cut(LocalSystem& s, const Distribution& d, const RowMatrix& rows, const Segments& segs, int rings,
                MPI_Comm comm) {
  const auto n = static_cast<size_t>(rows.rows());
  const size_t nf = s.nf, nl = s.nl;
  // The cut lines: each rank marks its own vertices' (from its share of the fixed marks),
  // then the marks (one byte per vertex) are combined on every rank.
  std::vector<char> cut(nl, 0), free_entry(nl, 0), in(n, 0);
  for (size_t j = 0; j < nf; ++j) {
    const char* fj = s.fixed.data() + j * nl;
    for (size_t i = 0; i < nl; ++i) {
      if (!fj[i])
        free_entry[i] = 1;
      else if (!segs.key[j])
        cut[i] = 1;
    }
  }
  for (size_t i = 0; i < nl; ++i) in[static_cast<size_t>(d.owned[i])] = cut[i] && free_entry[i];
  MPI_Allreduce(MPI_IN_PLACE, in.data(), static_cast<int>(n), MPI_UNSIGNED_CHAR, MPI_MAX, comm);
  for (int ring = 0; ring < rings; ++ring) {
    std::vector<char> grown = in;
    for (size_t v = 0; v < n; ++v)
      if (in[v])
        for (RowMatrix::InnerIterator it(rows, static_cast<Eigen::Index>(v)); it; ++it)
          grown[static_cast<size_t>(it.col())] = 1;
    in = std::move(grown);
  }
  if (std::find(in.begin(), in.end(), 1) == in.end()) return;
  LocalSystem::Cut& c = s.cut;
  // Ω's vertices per rank in the ranks' vertex order, their index there; the ghosts: other
  // ranks' Ω vertices next to one of this rank's vertices.
  std::vector<int> omega_index(n, -1);
  std::vector<PetscInt> omega_count(static_cast<size_t>(d.size), 0);
  // In each rank's vertex order (a rank's local indices increase with the vertex number).
  for (size_t v = 0; v < n; ++v)
    if (in[v]) omega_index[v] = static_cast<int>(omega_count[static_cast<size_t>(d.owner[v])]++);
  std::vector<PetscInt> omega_first(static_cast<size_t>(d.size), 0);
  for (size_t r = 1; r < omega_first.size(); ++r) omega_first[r] = omega_first[r - 1] + omega_count[r - 1];
  std::vector<int> ghost_of(n, -1);
  std::vector<int> ghost_vertex;
  for (const int v : d.owned)
    for (RowMatrix::InnerIterator it(rows, v); it; ++it) {
      const auto col = static_cast<size_t>(it.col());
      if (in[col] && d.owner[col] != d.rank && ghost_of[col] < 0) {
        ghost_of[col] = 0;
        ghost_vertex.push_back(static_cast<int>(col));
      }
    }
  std::sort(ghost_vertex.begin(), ghost_vertex.end());
  for (size_t g = 0; g < ghost_vertex.size(); ++g) ghost_of[static_cast<size_t>(ghost_vertex[g])] = static_cast<int>(g);
  auto column_of = [&](size_t col) {
    return d.owner[col] == d.rank ? omega_index[col] : -ghost_of[col] - 1;
  };
  c.start.push_back(0);
  c.touched_start.push_back(0);
  for (size_t i = 0; i < s.nl; ++i) {
    const auto v = static_cast<size_t>(d.owned[i]);
    bool near = false;
    for (RowMatrix::InnerIterator it(rows, static_cast<Eigen::Index>(v)); it; ++it) {
      const auto col = static_cast<size_t>(it.col());
      if (col == v || !in[col]) continue;
      near = true;
      if (in[v]) {
        c.column.push_back(column_of(col));
        c.value.push_back(it.value());
      } else {
        c.touched_column.push_back(column_of(col));
        c.touched_value.push_back(it.value());
      }
    }
    if (in[v]) {
      c.vertex.push_back(static_cast<int>(i));
      c.start.push_back(static_cast<int>(c.column.size()));
    } else if (near) {
      c.touched.push_back(static_cast<int>(i));
      c.touched_start.push_back(static_cast<int>(c.touched_column.size()));
    }
  }
  c.count = c.vertex.size();
  c.ghosts = ghost_vertex.size();
  check(VecCreateMPI(comm, static_cast<PetscInt>(2 * nf * c.count), PETSC_DETERMINE, &c.x), "VecCreateMPI");
  check(VecDuplicate(c.x, &c.r), "VecDuplicate");
  check(VecCreateSeq(PETSC_COMM_SELF, static_cast<PetscInt>(2 * nf * c.ghosts), &c.ghost), "VecCreateSeq");
  {
    std::vector<PetscInt> from(2 * nf * c.ghosts);
    for (size_t g = 0; g < c.ghosts; ++g) {
      const auto v = static_cast<size_t>(ghost_vertex[g]);
      const PetscInt at = static_cast<PetscInt>(2 * nf) *
                          (omega_first[static_cast<size_t>(d.owner[v])] + omega_index[v]);
      for (size_t q = 0; q < 2 * nf; ++q) from[2 * nf * g + q] = at + static_cast<PetscInt>(q);
    }
    IS is = nullptr;
    check(ISCreateGeneral(PETSC_COMM_SELF, static_cast<PetscInt>(from.size()), from.data(), PETSC_COPY_VALUES, &is),
          "ISCreateGeneral");
    check(VecScatterCreate(c.x, is, c.ghost, nullptr, &c.scatter), "VecScatterCreate");
    ISDestroy(&is);
  }
  const auto size = static_cast<PetscInt>(2 * nf * c.count);
  check(MatCreateShell(comm, size, size, PETSC_DETERMINE, PETSC_DETERMINE, &s, &c.a), "MatCreateShell");
  check(MatShellSetOperation(c.a, MATOP_MULT, reinterpret_cast<void (*)(void)>(apply_cut_operator)),
        "MatShellSetOperation");
  check(MatSetOption(c.a, MAT_SPD, PETSC_TRUE), "MatSetOption");
  check(KSPCreate(comm, &c.ksp), "KSPCreate");
  check(KSPSetOperators(c.ksp, c.a, c.a), "KSPSetOperators");
  check(KSPSetType(c.ksp, KSPCG), "KSPSetType");
  PC pc = nullptr;
  check(KSPGetPC(c.ksp, &pc), "KSPGetPC");
  check(PCSetType(pc, PCSHELL), "PCSetType");
  check(PCShellSetContext(pc, &s), "PCShellSetContext");
  check(PCShellSetApply(pc, apply_cut_lines), "PCShellSetApply");
  check(KSPSetNormType(c.ksp, KSP_NORM_UNPRECONDITIONED), "KSPSetNormType");
  check(KSPSetTolerances(c.ksp, kLocalTolerance, 0.0, 1e300, kLocalIterations), "KSPSetTolerances");
  check(KSPSetOptionsPrefix(c.ksp, "tvf_local_"), "KSPSetOptionsPrefix");
  check(KSPSetFromOptions(c.ksp), "KSPSetFromOptions");
}

// The coarse correction's set-up: the low temporal modes of every segment between key
// frames, their systems E_m = S^½ L S^½ + T assembled as one block-diagonal matrix over the
// rank's vertices (PETSc rows mode-major in the rank's vertex order, complex entries as real
// 2 × 2 blocks [[a, −b], [b, a]], so the real form is symmetric positive definite), its KSP,
// and the scatter of the solution to the ghost vertices. One system rather than one per
// mode: the same iterations and one set of synchronisations (docs/benchmarks.md).
void set_up_coarse(LocalSystem& s, const Distribution& d, const RowMatrix& rows, const ConnectionLaplacian& laplacian,
                   const Segments& segs, int coarse_modes, MPI_Comm comm) {
  const auto n = static_cast<size_t>(rows.rows());
  const size_t nl = s.nl, ng = s.ng, nf = s.nf;
  s.frame_modes.assign(nf, {});
  for (const auto& [first, count] : segs.segments) {
    Eigen::MatrixXd q;
    Eigen::VectorXd lambda;
    temporal_eigenbasis(static_cast<int>(count), first == 0, first + count == nf, coarse_modes, q, lambda);
    for (Eigen::Index k = 0; k < q.cols(); ++k) {
      LocalSystem::Mode m;
      m.first = first;
      m.q = q.col(k);
      for (size_t jj = 0; jj < count; ++jj) s.frame_modes[first + jj].emplace_back(s.modes.size(), jj);
      s.modes.push_back(std::move(m));
    }
  }
  const size_t nm = s.modes.size();
  if (nm == 0) return;
  // Block (complex) row of mode m at vertex v: the modes' rows of the ranks before v's, then
  // v's rank's rows of the modes before m, then v's index there.
  std::vector<PetscInt> first_row(static_cast<size_t>(d.size), 0);
  for (size_t r = 1; r < first_row.size(); ++r)
    first_row[r] = first_row[r - 1] + static_cast<PetscInt>(nm) * d.count[r - 1];
  auto block = [&](size_t m, size_t v) {
    const auto r = static_cast<size_t>(d.owner[v]);
    return first_row[r] + static_cast<PetscInt>(m) * d.count[r] + d.local[v];
  };

  // The scatter of the modes' solution to the ghosts.
  check(VecCreateSeq(PETSC_COMM_SELF, static_cast<PetscInt>(2 * ng * nm), &s.coarse_ghost), "VecCreateSeq");
  check(VecCreateMPI(comm, static_cast<PetscInt>(2 * nl * nm), PETSC_DETERMINE, &s.coarse_y), "VecCreateMPI");
  check(VecDuplicate(s.coarse_y, &s.coarse_g), "VecDuplicate");
  {
    std::vector<PetscInt> from(2 * ng * nm);
    for (size_t m = 0; m < nm; ++m)
      for (size_t g = 0; g < ng; ++g) {
        const PetscInt at = 2 * block(m, static_cast<size_t>(d.ghosts[g]));
        from[2 * (m * ng + g)] = at;
        from[2 * (m * ng + g) + 1] = at + 1;
      }
    IS is = nullptr;
    check(ISCreateGeneral(PETSC_COMM_SELF, static_cast<PetscInt>(from.size()), from.data(), PETSC_COPY_VALUES, &is),
          "ISCreateGeneral");
    check(VecScatterCreate(s.coarse_y, is, s.coarse_ghost, nullptr, &s.coarse_scatter), "VecScatterCreate");
    ISDestroy(&is);
  }

  // The block rows' counts in the diagonal and off-diagonal parts (the graph of L, per mode).
  std::vector<PetscInt> dnz(nl * nm, 1), onz(nl * nm, 0);
  for (size_t m = 0; m < nm; ++m)
    for (size_t i = 0; i < nl; ++i)
      for (int e = s.row_start[i]; e < s.row_start[i + 1]; ++e)
        ++(s.column[static_cast<size_t>(e)] >= 0 ? dnz[m * nl + i] : onz[m * nl + i]);
  check(MatCreate(comm, &s.coarse), "MatCreate");
  check(MatSetSizes(s.coarse, static_cast<PetscInt>(2 * nl * nm), static_cast<PetscInt>(2 * nl * nm), PETSC_DETERMINE,
                    PETSC_DETERMINE),
        "MatSetSizes");
  check(MatSetType(s.coarse, MATAIJ), "MatSetType");
  check(MatXAIJSetPreallocation(s.coarse, 2, dnz.data(), onz.data(), nullptr, nullptr), "MatXAIJSetPreallocation");
  std::vector<double> scale(n, 0.0), shift(nl, 0.0);
  for (size_t mi = 0; mi < nm; ++mi) {
    const LocalSystem::Mode& m = s.modes[mi];
    // √s_i at the owned and ghost vertices, T_ii at the owned ones.
    for (size_t i = 0; i < nl; ++i) {
      const auto v = static_cast<size_t>(d.owned[i]);
      const CoarseWeight w = coarse_weight(m.q, m.first, s.fixed, nl, nf, i, s.b * s.weight_sum[i]);
      scale[v] = w.scale;
      shift[i] = w.shift;
    }
    for (size_t g = 0; g < ng; ++g) {
      const int v = d.ghosts[g];
      scale[static_cast<size_t>(v)] =
          coarse_weight(m.q, m.first, s.ghost_fixed, ng, nf, g, s.b * laplacian.weight_sum[v]).scale;
    }
    for (size_t i = 0; i < nl; ++i) {
      const auto v = static_cast<size_t>(d.owned[i]);
      const PetscInt row = block(mi, v);
      const double si = scale[v];
      // A vertex out of the coarse space (fixed at every frame of the segment): identity row,
      // its right-hand side is zero.
      const double dg = si == 0 ? 1.0 : si * si * s.diagonal[i] + shift[i];
      const PetscScalar diag[4] = {dg, 0, 0, dg};
      check(MatSetValuesBlocked(s.coarse, 1, &row, 1, &row, diag, INSERT_VALUES), "MatSetValuesBlocked");
      if (si == 0) continue;
      for (RowMatrix::InnerIterator it(rows, static_cast<Eigen::Index>(v)); it; ++it) {
        const auto c = static_cast<size_t>(it.col());
        if (c == v || scale[c] == 0) continue;
        const cplx a = si * scale[c] * it.value();
        const PetscScalar entry[4] = {a.real(), -a.imag(), a.imag(), a.real()};
        const PetscInt col = block(mi, c);
        check(MatSetValuesBlocked(s.coarse, 1, &row, 1, &col, entry, INSERT_VALUES), "MatSetValuesBlocked");
      }
    }
  }
  check(MatAssemblyBegin(s.coarse, MAT_FINAL_ASSEMBLY), "MatAssemblyBegin");
  check(MatAssemblyEnd(s.coarse, MAT_FINAL_ASSEMBLY), "MatAssemblyEnd");
  check(MatSetOption(s.coarse, MAT_SPD, PETSC_TRUE), "MatSetOption");
  check(KSPCreate(comm, &s.coarse_ksp), "KSPCreate");
  check(KSPSetOperators(s.coarse_ksp, s.coarse, s.coarse), "KSPSetOperators");
  check(KSPSetType(s.coarse_ksp, KSPCG), "KSPSetType");
  PC pc = nullptr;
  check(KSPGetPC(s.coarse_ksp, &pc), "KSPGetPC");
  check(PCSetType(pc, PCGAMG), "PCSetType");
  check(KSPSetNormType(s.coarse_ksp, KSP_NORM_UNPRECONDITIONED), "KSPSetNormType");
  check(KSPSetTolerances(s.coarse_ksp, kCoarseTolerance, 0.0, 1e300, kCoarseIterations), "KSPSetTolerances");
  check(KSPSetOptionsPrefix(s.coarse_ksp, "tvf_coarse_"), "KSPSetOptionsPrefix");
  check(KSPSetFromOptions(s.coarse_ksp), "KSPSetFromOptions");
  check(KSPSetUp(s.coarse_ksp), "KSPSetUp");
}

}  // namespace

PetscPartition petsc_partition(const ConnectionLaplacian& laplacian) {
  const RowMatrix rows = laplacian.matrix;
  Distribution d = distribute(rows, 1, PETSC_COMM_WORLD);
  PetscPartition p;
  p.owner = std::move(d.owner);
  p.cut_edges = d.cut_edges;
  p.edges = (rows.nonZeros() - rows.rows()) / 2;
  p.partitioner = d.partitioner;
  return p;
}

namespace {

// PETSc's index type (32 bits in Debian's build) must count the real unknowns.
void check_index_range(size_t n, size_t nf) {
  if (static_cast<double>(2 * n * nf) > static_cast<double>(std::numeric_limits<PetscInt>::max()))
    throw Error(fmt::format("the distributed solve's {} real unknowns (2 · {} vertices · {} frames) exceed what "
                            "this PETSc indexes ({}); it needs a PETSc built with 64-bit indices",
                            2 * n * nf, n, nf, std::numeric_limits<PetscInt>::max()));
}

SolveReport solve_shares(const RowMatrix& rows, const ConnectionLaplacian& laplacian, const VertexShares& shares,
                         int frames, double temporal_weight, std::span<const char> fixed, std::span<cplx> z,
                         const SpaceTimeOptions& options) {
  const MPI_Comm comm = PETSC_COMM_WORLD;
  const auto n = static_cast<size_t>(rows.rows());
  const auto nf = static_cast<size_t>(frames);
  const double b = temporal_weight;
  check_index_range(n, nf);
  const Distribution d = distribution_of(shares, rows, nf);
  TVF_CHECK(fixed.size() == d.owned.size() * nf && z.size() == d.owned.size() * nf,
            "distributed space-time shares {} {} for {} owned vertices × {} frames", fixed.size(), z.size(),
            d.owned.size(), nf);
  g_last_owner = d.owner;  // the per-rank VTK pieces follow it (distributed_vertex_owners)

  // This rank's rows: the spatial operator with columns renumbered, fixed set, lines.
  LocalSystem s;
  s.nl = d.owned.size();
  s.ng = d.ghosts.size();
  s.nf = nf;
  s.b = b;
  std::vector<int> ghost_index(n, -1);
  for (size_t g = 0; g < d.ghosts.size(); ++g) ghost_index[static_cast<size_t>(d.ghosts[g])] = static_cast<int>(g);
  s.row_start.push_back(0);
  for (const int v : d.owned) {
    double diagonal = 0;
    for (RowMatrix::InnerIterator it(rows, v); it; ++it) {
      const auto c = static_cast<size_t>(it.col());
      if (it.col() == v) {
        diagonal = it.value().real();
        continue;
      }
      s.column.push_back(d.owner[c] == d.rank ? d.local[c] : -ghost_index[c] - 1);
      s.value.push_back(it.value());
    }
    s.row_start.push_back(static_cast<int>(s.column.size()));
    s.diagonal.push_back(diagonal);
    s.weight_sum.push_back(laplacian.weight_sum[v]);
  }
  const size_t nlf = s.nl * nf;
  s.fixed.assign(fixed.begin(), fixed.end());
  s.pivot.assign(nlf, 0);
  for (size_t j = 0; j < nf; ++j)
    for (size_t i = 0; i < s.nl; ++i) {
      const size_t k = j * s.nl + i;
      if (s.fixed[k]) continue;  // pivot 0: the line solve leaves fixed entries 0
      const bool has_prev = j > 0, has_next = j + 1 < nf;
      const double c = b * s.weight_sum[i];
      const double diag = s.diagonal[i] + c * ((has_prev ? 1 : 0) + (has_next ? 1 : 0));
      const double denom = diag - (has_prev ? s.lower(j, i) * s.upper(j - 1, i) : 0.0);
      s.pivot[k] = 1.0 / denom;
    }
  // Vectors: this rank's block of 2·nf·nl reals; the ghosts' values in every frame.
  Vec x = nullptr, rhs = nullptr;
  check(VecCreateMPI(comm, static_cast<PetscInt>(2 * nlf), PETSC_DETERMINE, &x), "VecCreateMPI");
  check(VecSetBlockSize(x, 2), "VecSetBlockSize");
  check(VecDuplicate(x, &rhs), "VecDuplicate");
  check(VecCreateSeq(PETSC_COMM_SELF, static_cast<PetscInt>(2 * s.ng * nf), &s.ghost), "VecCreateSeq");
  {
    std::vector<PetscInt> from(2 * s.ng * nf);
    for (size_t j = 0; j < nf; ++j)
      for (size_t g = 0; g < s.ng; ++g) {
        const auto v = static_cast<size_t>(d.ghosts[g]);
        const auto r = static_cast<size_t>(d.owner[v]);
        const PetscInt at = d.first[r] + static_cast<PetscInt>(2 * (j * static_cast<size_t>(d.count[r]) +
                                                                    static_cast<size_t>(d.local[v])));
        from[2 * (j * s.ng + g)] = at;
        from[2 * (j * s.ng + g) + 1] = at + 1;
      }
    IS is = nullptr;
    check(ISCreateGeneral(PETSC_COMM_SELF, static_cast<PetscInt>(from.size()), from.data(), PETSC_COPY_VALUES, &is),
          "ISCreateGeneral");
    check(VecScatterCreate(x, is, s.ghost, nullptr, &s.scatter), "VecScatterCreate");
    ISDestroy(&is);
  }

  // The ghosts' fixed marks and values (the right-hand side needs the fixed ones): one
  // exchange each, through x.
  s.ghost_fixed.resize(s.ng * nf);
  {
    PetscScalar* xa = nullptr;
    check(VecGetArray(x, &xa), "VecGetArray");
    for (size_t k = 0; k < nlf; ++k) {
      xa[2 * k] = s.fixed[k] ? 1.0 : 0.0;
      xa[2 * k + 1] = 0;
    }
    check(VecRestoreArray(x, &xa), "VecRestoreArray");
    check(VecScatterBegin(s.scatter, x, s.ghost, INSERT_VALUES, SCATTER_FORWARD), "VecScatterBegin");
    check(VecScatterEnd(s.scatter, x, s.ghost, INSERT_VALUES, SCATTER_FORWARD), "VecScatterEnd");
    const PetscScalar* ga = nullptr;
    check(VecGetArrayRead(s.ghost, &ga), "VecGetArrayRead");
    for (size_t k = 0; k < s.ng * nf; ++k) s.ghost_fixed[k] = ga[2 * k] != 0 ? 1 : 0;
    check(VecRestoreArrayRead(s.ghost, &ga), "VecRestoreArrayRead");
    check(VecGetArray(x, &xa), "VecGetArray");
    std::copy(z.begin(), z.end(), reinterpret_cast<cplx*>(xa));
    check(VecRestoreArray(x, &xa), "VecRestoreArray");
    check(VecScatterBegin(s.scatter, x, s.ghost, INSERT_VALUES, SCATTER_FORWARD), "VecScatterBegin");
    check(VecScatterEnd(s.scatter, x, s.ghost, INSERT_VALUES, SCATTER_FORWARD), "VecScatterEnd");
  }

  // The right-hand side −A_FC v_C and the first guess (z's free entries), fixed entries 0.
  {
    PetscScalar *ra = nullptr, *xa = nullptr;
    const PetscScalar* ga = nullptr;
    check(VecGetArray(rhs, &ra), "VecGetArray");
    check(VecGetArray(x, &xa), "VecGetArray");
    check(VecGetArrayRead(s.ghost, &ga), "VecGetArrayRead");
    auto* rs = reinterpret_cast<cplx*>(ra);
    auto* xs = reinterpret_cast<cplx*>(xa);
    const auto* gs = reinterpret_cast<const cplx*>(ga);
    const size_t nl = s.nl, ng = s.ng;
    for (size_t j = 0; j < nf; ++j) {
      const char* fj = s.fixed.data() + j * nl;
      const cplx* zj = z.data() + j * nl;
      const char* gfj = s.ghost_fixed.data() + j * ng;
      const cplx* gj = gs + j * ng;
      for (size_t i = 0; i < nl; ++i) {
        const size_t k = j * nl + i;
        if (fj[i]) {
          rs[k] = xs[k] = 0;
          continue;
        }
        // L's row in its stored order (the diagonal left out), as the one process sums it.
        cplx acc(0, 0);
        for (int e = s.row_start[i]; e < s.row_start[i + 1]; ++e) {
          const int c = s.column[static_cast<size_t>(e)];
          if (c >= 0) {
            if (fj[c]) acc -= s.value[static_cast<size_t>(e)] * zj[c];
          } else if (gfj[-c - 1]) {
            acc -= s.value[static_cast<size_t>(e)] * gj[-c - 1];
          }
        }
        const double c = b * s.weight_sum[i];
        // The temporal neighbours indexed from the array's start (no pointer before it).
        if (j > 0 && s.fixed[k - nl]) acc += c * z[k - nl];
        if (j + 1 < nf && s.fixed[k + nl]) acc += c * z[k + nl];
        rs[k] = acc;
        xs[k] = z[k];
      }
    }
    check(VecRestoreArrayRead(s.ghost, &ga), "VecRestoreArrayRead");
    check(VecRestoreArray(x, &xa), "VecRestoreArray");
    check(VecRestoreArray(rhs, &ra), "VecRestoreArray");
  }
  PetscReal bnorm = 0;
  check(VecNorm(rhs, NORM_2, &bnorm), "VecNorm");

  SolveReport report;
  // The halo: ghost vertices summed over ranks; each iteration's one exchange moves
  // halo × frames complex values (docs/benchmarks.md, "Distributed").
  long halo = static_cast<long>(s.ng);
  MPI_Allreduce(MPI_IN_PLACE, &halo, 1, MPI_LONG, MPI_SUM, comm);
  const std::string where =
      fmt::format("{} {}, {} partition cutting {} of {} edges, halo {} vertices", d.size, d.size == 1 ? "rank" : "ranks",
                  d.partitioner, d.cut_edges, (rows.nonZeros() - static_cast<long>(n)) / 2, halo);
  PetscInt iterations = 0;
  if (bnorm == 0) {
    check(VecZeroEntries(x), "VecZeroEntries");
    report.method = "nothing to solve (no fixed entry asks for a non-zero field), " + where;
    report.success = true;
  } else {
    Mat a = nullptr;
    check(MatCreateShell(comm, static_cast<PetscInt>(2 * nlf), static_cast<PetscInt>(2 * nlf), PETSC_DETERMINE,
                         PETSC_DETERMINE, &s, &a),
          "MatCreateShell");
    check(MatShellSetOperation(a, MATOP_MULT, reinterpret_cast<void (*)(void)>(apply_operator)),
          "MatShellSetOperation");
    check(MatSetOption(a, MAT_SPD, PETSC_TRUE), "MatSetOption");
    // The key frames (whole frames fixed) and the segments between them: each rank's share
    // of a frame, then all ranks' (one number per frame).
    std::vector<int> key(nf, 1);
    for (size_t j = 0; j < nf; ++j)
      key[j] = std::all_of(s.fixed.begin() + static_cast<std::ptrdiff_t>(j * s.nl),
                           s.fixed.begin() + static_cast<std::ptrdiff_t>((j + 1) * s.nl),
                           [](char f) { return f != 0; })
                   ? 1
                   : 0;
    MPI_Allreduce(MPI_IN_PLACE, key.data(), static_cast<int>(nf), MPI_INT, MPI_MIN, comm);
    const Segments segs = segments_between(std::vector<char>(key.begin(), key.end()));
    // The two-level preconditioner (options.coarse_modes > 0, the one process's default) is
    // not symmetric (multiplicative) and not linear (inexact coarse solves): flexible CG,
    // orthogonalising against the last direction only (the one process's Polak–Ribière
    // CG). The line solves alone: plain CG.
    if (options.coarse_modes > 0) set_up_coarse(s, d, rows, laplacian, segs, options.coarse_modes, comm);
    const bool two_level = s.coarse_ksp != nullptr;
    if (two_level && options.local_rings >= 0) set_up_cut(s, d, rows, segs, options.local_rings, comm);
    KSP ksp = nullptr;
    check(KSPCreate(comm, &ksp), "KSPCreate");
    check(KSPSetOperators(ksp, a, a), "KSPSetOperators");
    check(KSPSetType(ksp, two_level ? KSPFCG : KSPCG), "KSPSetType");
    if (two_level) {
      check(KSPFCGSetMmax(ksp, 1), "KSPFCGSetMmax");
      check(KSPFCGSetNprealloc(ksp, 2), "KSPFCGSetNprealloc");
    }
    PC pc = nullptr;
    check(KSPGetPC(ksp, &pc), "KSPGetPC");
    check(PCSetType(pc, PCSHELL), "PCSetType");
    check(PCShellSetContext(pc, &s), "PCShellSetContext");
    check(PCShellSetApply(pc, two_level ? apply_two_level : apply_line_solves), "PCShellSetApply");
    check(PCShellSetName(pc, two_level ? "low temporal modes, then temporal line solves" : "temporal line solves"),
          "PCShellSetName");
    // The one process's test: ‖b − A x‖ ≤ tolerance · ‖b‖ (PETSc's default test measures
    // against ‖b‖ when the first guess is non-zero), the true residual's norm.
    check(KSPSetNormType(ksp, KSP_NORM_UNPRECONDITIONED), "KSPSetNormType");
    check(KSPSetTolerances(ksp, options.tolerance, 0.0, 1e300, options.max_iterations), "KSPSetTolerances");
    check(KSPSetInitialGuessNonzero(ksp, PETSC_TRUE), "KSPSetInitialGuessNonzero");
    check(KSPSetFromOptions(ksp), "KSPSetFromOptions");
    check(KSPSolve(ksp, rhs, x), "KSPSolve");
    KSPConvergedReason reason{};
    check(KSPGetConvergedReason(ksp, &reason), "KSPGetConvergedReason");
    check(KSPGetIterationNumber(ksp, &iterations), "KSPGetIterationNumber");
    PetscReal rnorm = 0;
    check(KSPGetResidualNorm(ksp, &rnorm), "KSPGetResidualNorm");
    KSPType ksp_type = nullptr;
    check(KSPGetType(ksp, &ksp_type), "KSPGetType");
    const std::string type = ksp_type;  // KSPDestroy frees ksp_type
    std::string coarse;
    if (two_level) {
      PC mode_pc = nullptr;
      PCType mode_type = nullptr;
      check(KSPGetPC(s.coarse_ksp, &mode_pc), "KSPGetPC");
      check(PCGetType(mode_pc, &mode_type), "PCGetType");
      coarse = fmt::format(" with {} low temporal modes as coarse correction ({} on their block-diagonal spatial "
                           "system; {} iterations of it in all)",
                           s.modes.size(), mode_type, s.coarse_iterations);
      if (s.cut.ksp != nullptr) {
        long cut_vertices = static_cast<long>(s.cut.count);
        MPI_Allreduce(MPI_IN_PLACE, &cut_vertices, 1, MPI_LONG, MPI_SUM, comm);
        coarse += fmt::format(" and a local solve on the {} vertices near the moving constraints ({} iterations in all)",
                              cut_vertices, s.cut.iterations);
      }
    }
    KSPDestroy(&ksp);
    MatDestroy(&a);
    report.method = fmt::format("PETSc CG ({}; temporal line solves){}, matrix-free, {} iterations, {}", type, coarse,
                                iterations, where);
    report.iterations = static_cast<int>(iterations);
    report.residual = rnorm / bnorm;
    report.success = reason > 0 && std::isfinite(report.residual) && report.residual <= options.tolerance;
  }

  // The rank's share of the result: the solution at its free entries, the fixed values
  // (already in z) at the others.
  {
    const PetscScalar* xa = nullptr;
    check(VecGetArrayRead(x, &xa), "VecGetArrayRead");
    const auto* xs = reinterpret_cast<const cplx*>(xa);
    for (size_t k = 0; k < nlf; ++k)
      if (!s.fixed[k]) z[k] = xs[k];
    check(VecRestoreArrayRead(x, &xa), "VecRestoreArrayRead");
  }
  VecScatterDestroy(&s.scatter);
  VecDestroy(&s.ghost);
  VecDestroy(&rhs);
  VecDestroy(&x);
  return report;
}

}  // namespace

VertexShares petsc_vertex_shares(const ConnectionLaplacian& laplacian) {
  const RowMatrix rows = laplacian.matrix;
  return partition_vertices(rows, PETSC_COMM_WORLD);
}

SolveReport petsc_spacetime_solve_shares(const ConnectionLaplacian& laplacian, const VertexShares& shares,
                                         int frames, double temporal_weight, std::span<const char> fixed,
                                         std::span<cplx> z, const SpaceTimeOptions& options) {
  const RowMatrix rows = laplacian.matrix;
  return solve_shares(rows, laplacian, shares, frames, temporal_weight, fixed, z, options);
}

SolveReport petsc_spacetime_solve(const ConnectionLaplacian& laplacian, int frames, double temporal_weight,
                                  std::span<const char> fixed, std::span<const cplx> values, std::span<cplx> z,
                                  const SpaceTimeOptions& options) {
  const MPI_Comm comm = PETSC_COMM_WORLD;
  const RowMatrix rows = laplacian.matrix;
  const auto n = static_cast<size_t>(rows.rows());
  const auto nf = static_cast<size_t>(frames);
  TVF_CHECK(fixed.size() == n * nf && values.size() == n * nf && z.size() == n * nf,
            "distributed space-time sizes {} {} {} for {} entries", fixed.size(), values.size(), z.size(), n * nf);
  check_index_range(n, nf);
  // Every rank's share of the replicated arrays (the fixed values in the first guess's
  // fixed entries), the solve on the shares, then the whole result on every rank.
  const VertexShares shares = partition_vertices(rows, comm);
  const size_t nl = shares.owned.size();
  std::vector<char> fs(nl * nf);
  std::vector<cplx> zs(nl * nf);
  for (size_t j = 0; j < nf; ++j)
    for (size_t i = 0; i < nl; ++i) {
      const size_t at = j * n + static_cast<size_t>(shares.owned[i]);
      fs[j * nl + i] = fixed[at];
      zs[j * nl + i] = fixed[at] ? values[at] : z[at];
    }
  const SolveReport report = solve_shares(rows, laplacian, shares, frames, temporal_weight, fs, zs, options);
  // The gather: every rank's entries into z on every rank, frame by frame (a sum in which
  // each entry has one non-zero term, so exact).
  std::vector<cplx> frame(n);
  for (size_t j = 0; j < nf; ++j) {
    std::fill(frame.begin(), frame.end(), cplx(0, 0));
    for (size_t i = 0; i < nl; ++i) frame[static_cast<size_t>(shares.owned[i])] = zs[j * nl + i];
    MPI_Allreduce(MPI_IN_PLACE, frame.data(), static_cast<int>(2 * n), MPI_DOUBLE, MPI_SUM, comm);
    for (size_t v = 0; v < n; ++v) z[j * n + v] = fixed[j * n + v] ? values[j * n + v] : frame[v];
  }
  return report;
}

namespace {

// Where each rank's share of one frame starts in a frame laid out rank after rank (each
// rank's vertices in its order): the layout of MPI_Gatherv and MPI_Scatterv below.
std::vector<size_t> rank_starts(const VertexShares& shares) {
  std::vector<size_t> start(static_cast<size_t>(shares.ranks), 0);
  for (size_t r = 1; r < start.size(); ++r) start[r] = start[r - 1] + static_cast<size_t>(shares.count[r - 1]);
  return start;
}

// Counts and displacements of `per_entry` items per vertex, for MPI's v-collectives.
void counts_of(const VertexShares& shares, int per_entry, std::vector<int>& counts, std::vector<int>& displs) {
  counts.assign(static_cast<size_t>(shares.ranks), 0);
  displs.assign(static_cast<size_t>(shares.ranks), 0);
  for (size_t r = 0; r < counts.size(); ++r) {
    counts[r] = per_entry * shares.count[r];
    if (r > 0) displs[r] = displs[r - 1] + counts[r - 1];
  }
}

}  // namespace

void petsc_gather_to_root(const VertexShares& shares, std::span<const cplx> share, int frames,
                          std::span<cplx> field) {
  const MPI_Comm comm = PETSC_COMM_WORLD;
  const size_t n = shares.owner.size(), nf = static_cast<size_t>(frames), nl = shares.owned.size();
  const bool root = shares.rank == 0;
  TVF_CHECK(share.size() == nl * nf && field.size() == (root ? n * nf : 0), "gather of {} values into {}",
            share.size(), field.size());
  std::vector<int> counts, displs;
  counts_of(shares, 2, counts, displs);
  const std::vector<size_t> start = rank_starts(shares);
  std::vector<cplx> frame(root ? n : 0);
  for (size_t j = 0; j < nf; ++j) {
    MPI_Gatherv(share.data() + j * nl, static_cast<int>(2 * nl), MPI_DOUBLE, frame.data(), counts.data(),
                displs.data(), MPI_DOUBLE, 0, comm);
    if (!root) continue;
    cplx* out = field.data() + j * n;
    for (size_t v = 0; v < n; ++v)
      out[v] = frame[start[static_cast<size_t>(shares.owner[v])] + static_cast<size_t>(shares.local[v])];
  }
}

void petsc_scatter_frame(const VertexShares& shares, int root, std::span<const char> fixed,
                         std::span<const cplx> values, std::span<char> fixed_share, std::span<cplx> values_share) {
  const MPI_Comm comm = PETSC_COMM_WORLD;
  const size_t n = shares.owner.size(), nl = shares.owned.size();
  TVF_CHECK(fixed_share.size() == nl && values_share.size() == nl, "a frame's share of {} for {} vertices",
            values_share.size(), nl);
  const bool sender = shares.rank == root;
  TVF_CHECK(!sender || (fixed.size() == n && values.size() == n), "a frame of {} values for {} vertices",
            values.size(), n);
  std::vector<cplx> packed(sender ? n : 0);
  std::string packed_fixed(sender ? n : 0, '\0');
  if (sender) {
    const std::vector<size_t> start = rank_starts(shares);
    for (size_t v = 0; v < n; ++v) {
      const size_t at = start[static_cast<size_t>(shares.owner[v])] + static_cast<size_t>(shares.local[v]);
      packed[at] = values[v];
      packed_fixed[at] = fixed[v];
    }
  }
  std::vector<int> counts, displs;
  counts_of(shares, 2, counts, displs);
  MPI_Scatterv(packed.data(), counts.data(), displs.data(), MPI_DOUBLE, values_share.data(), static_cast<int>(2 * nl),
               MPI_DOUBLE, root, comm);
  counts_of(shares, 1, counts, displs);
  MPI_Scatterv(packed_fixed.data(), counts.data(), displs.data(), MPI_CHAR, fixed_share.data(), static_cast<int>(nl),
               MPI_CHAR, root, comm);
}

void distributed_refresh_share(const Field& field) {
  if (!g_has_share) return;
  const MPI_Comm comm = PETSC_COMM_WORLD;
  const VertexShares& d = g_shares;
  const size_t n = d.owner.size(), nl = d.owned.size();
  const bool root = d.rank == 0;
  TVF_CHECK(!root || (static_cast<size_t>(field.num_vertices()) == n &&
                      static_cast<size_t>(field.frames()) == g_share_frames),
            "a field of {} frames × {} vertices for a share of {} × {}", field.frames(), field.num_vertices(),
            g_share_frames, n);
  std::vector<int> counts, displs;
  counts_of(d, 2, counts, displs);
  const std::vector<size_t> start = rank_starts(d);
  std::vector<cplx> packed(root ? n : 0);
  for (size_t j = 0; j < g_share_frames; ++j) {
    if (root) {
      const auto frame = field.frame(static_cast<int>(j));
      for (size_t v = 0; v < n; ++v)
        packed[start[static_cast<size_t>(d.owner[v])] + static_cast<size_t>(d.local[v])] = frame[v];
    }
    MPI_Scatterv(packed.data(), counts.data(), displs.data(), MPI_DOUBLE, g_share.data() + j * nl,
                 static_cast<int>(2 * nl), MPI_DOUBLE, 0, comm);
  }
}

std::vector<cplx> distributed_share_values(std::span<const int> points) {
  TVF_CHECK(g_has_share, "no share of a distributed field is kept");
  const MPI_Comm comm = PETSC_COMM_WORLD;
  const VertexShares& d = g_shares;
  const size_t nl = d.owned.size(), np = points.size(), nf = g_share_frames;
  std::vector<cplx> out(np * nf);
  // One frame's scatter (every rank's share of the frame → these points), made once and
  // applied to every frame's arrays in turn.
  std::vector<PetscInt> first(static_cast<size_t>(d.ranks), 0);
  for (size_t r = 1; r < first.size(); ++r) first[r] = first[r - 1] + 2 * static_cast<PetscInt>(d.count[r - 1]);
  std::vector<PetscInt> from(2 * np);
  for (size_t p = 0; p < np; ++p) {
    const auto v = static_cast<size_t>(points[p]);
    from[2 * p] = first[static_cast<size_t>(d.owner[v])] + 2 * static_cast<PetscInt>(d.local[v]);
    from[2 * p + 1] = from[2 * p] + 1;
  }
  cplx none(0, 0);  // arrays for the vectors' creation when this rank has no entries
  Vec share = nullptr, mine = nullptr;
  check(VecCreateMPIWithArray(comm, 1, static_cast<PetscInt>(2 * nl), PETSC_DETERMINE,
                              reinterpret_cast<PetscScalar*>(nl > 0 ? g_share.data() : &none), &share),
        "VecCreateMPIWithArray");
  check(VecCreateSeqWithArray(PETSC_COMM_SELF, 1, static_cast<PetscInt>(2 * np),
                              reinterpret_cast<PetscScalar*>(np > 0 ? out.data() : &none), &mine),
        "VecCreateSeqWithArray");
  IS is = nullptr;
  check(ISCreateGeneral(PETSC_COMM_SELF, static_cast<PetscInt>(from.size()), from.data(), PETSC_COPY_VALUES, &is),
        "ISCreateGeneral");
  VecScatter scatter = nullptr;
  check(VecScatterCreate(share, is, mine, nullptr, &scatter), "VecScatterCreate");
  ISDestroy(&is);
  for (size_t j = 0; j < nf; ++j) {
    if (nl > 0) check(VecPlaceArray(share, reinterpret_cast<PetscScalar*>(g_share.data() + j * nl)), "VecPlaceArray");
    if (np > 0) check(VecPlaceArray(mine, reinterpret_cast<PetscScalar*>(out.data() + j * np)), "VecPlaceArray");
    check(VecScatterBegin(scatter, share, mine, INSERT_VALUES, SCATTER_FORWARD), "VecScatterBegin");
    check(VecScatterEnd(scatter, share, mine, INSERT_VALUES, SCATTER_FORWARD), "VecScatterEnd");
    if (nl > 0) check(VecResetArray(share), "VecResetArray");
    if (np > 0) check(VecResetArray(mine), "VecResetArray");
  }
  VecScatterDestroy(&scatter);
  VecDestroy(&mine);
  VecDestroy(&share);
  return out;
}

#endif

}  // namespace tvf
