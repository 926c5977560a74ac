#include "solve/petsc_spacetime.h"

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

// An MPI launcher's environment: OpenMPI's mpirun, MPICH's/Hydra's mpiexec (PMI), PMIx
// (Slurm's srun, OpenMPI 5).
[[maybe_unused]] bool launched_by_mpi() {
  for (const char* v : {"OMPI_COMM_WORLD_SIZE", "PMI_SIZE", "PMIX_RANK", "PMI_RANK"})
    if (std::getenv(v) != nullptr) return true;
  return false;
}

int g_ranks = 1;
int g_rank = 0;
bool g_active = false;

}  // namespace

bool distributed_built() { return TVF_HAVE_PETSC != 0; }
int distributed_ranks() { return g_ranks; }
int distributed_rank() { return g_rank; }
bool distributed_active() { return g_active; }
bool distributed_owns_frame(int frame) { return frame % g_ranks == g_rank; }

namespace {
// The partition of the last distributed space-time solve (distributed_vertex_owners).
std::vector<int> g_last_owner;
}  // namespace

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
  if (!launched_by_mpi()) return;
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

// Which rank owns each vertex, from PETSc's partitioner on L's graph (PT-Scotch in
// Debian's PETSc; PETSC_OPTIONS=-mat_partitioning_type ... picks another).
struct Distribution {
  int rank = 0, size = 1;
  std::vector<int> owner;       // per vertex
  std::vector<int> local;       // per vertex: its index among its owner's vertices
  std::vector<int> count;       // per rank: its vertices
  std::vector<PetscInt> first;  // per rank: its first row of the global vector
  std::vector<int> owned;       // this rank's vertices, in local order
  std::vector<int> ghosts;      // other ranks' vertices next to this rank's, ascending
  long cut_edges = 0;           // edges of L's graph between two ranks
  std::string partitioner;
};

Distribution distribute(const RowMatrix& rows, size_t nf, MPI_Comm comm) {
  Distribution d;
  MPI_Comm_rank(comm, &d.rank);
  MPI_Comm_size(comm, &d.size);
  const auto n = static_cast<PetscInt>(rows.rows());
  // The adjacency graph, rows split evenly in the input's order for the partitioner.
  const PetscInt lo = n * d.rank / d.size, hi = n * (d.rank + 1) / d.size;
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
  check(MatPartitioningSetType(part, d.size > 1 ? MATPARTITIONINGPTSCOTCH : MATPARTITIONINGCURRENT),
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

  d.count.assign(static_cast<size_t>(d.size), 0);
  d.local.resize(static_cast<size_t>(n));
  for (PetscInt v = 0; v < n; ++v) {
    const auto r = static_cast<size_t>(d.owner[static_cast<size_t>(v)]);
    d.local[static_cast<size_t>(v)] = d.count[r]++;
    if (static_cast<int>(r) == d.rank) d.owned.push_back(static_cast<int>(v));
  }
  d.first.assign(static_cast<size_t>(d.size), 0);
  for (size_t r = 1; r < d.first.size(); ++r)
    d.first[r] = d.first[r - 1] + static_cast<PetscInt>(2 * nf) * d.count[r - 1];
  std::vector<char> ghost(static_cast<size_t>(n), 0);
  for (PetscInt v = 0; v < n; ++v)
    for (RowMatrix::InnerIterator it(rows, v); it; ++it) {
      const auto c = static_cast<size_t>(it.col());
      if (d.owner[c] == d.owner[static_cast<size_t>(v)]) continue;
      if (it.col() > v) ++d.cut_edges;
      if (d.owner[static_cast<size_t>(v)] == d.rank) ghost[c] = 1;
    }
  for (PetscInt v = 0; v < n; ++v)
    if (ghost[static_cast<size_t>(v)]) d.ghosts.push_back(static_cast<int>(v));
  return d;
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
// the one process's preconditioner, with no communication.
PetscErrorCode apply_preconditioner(PC pc, Vec r, Vec out) {
  LocalSystem* s = nullptr;
  PetscCall(PCShellGetContext(pc, &s));
  const PetscScalar* ra = nullptr;
  PetscScalar* oa = nullptr;
  PetscCall(VecGetArrayRead(r, &ra));
  PetscCall(VecGetArray(out, &oa));
  const auto* rs = reinterpret_cast<const cplx*>(ra);
  auto* os = reinterpret_cast<cplx*>(oa);
  const size_t nl = s->nl, nf = s->nf;
  for (size_t i = 0; i < nl; ++i) os[i] = rs[i] * s->pivot[i];
  for (size_t j = 1; j < nf; ++j)
    for (size_t i = 0; i < nl; ++i) {
      const size_t k = j * nl + i;
      os[k] = (rs[k] - s->lower(j, i) * os[k - nl]) * s->pivot[k];
    }
  for (size_t j = nf - 1; j-- > 0;)
    for (size_t i = 0; i < nl; ++i) {
      const size_t k = j * nl + i;
      os[k] -= s->upper(j, i) * os[k + nl];
    }
  PetscCall(VecRestoreArray(out, &oa));
  PetscCall(VecRestoreArrayRead(r, &ra));
  return 0;
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

SolveReport petsc_spacetime_solve(const ConnectionLaplacian& laplacian, int frames, double temporal_weight,
                                  std::span<const char> fixed, std::span<const cplx> values, std::span<cplx> z,
                                  const SpaceTimeOptions& options) {
  const MPI_Comm comm = PETSC_COMM_WORLD;
  const RowMatrix rows = laplacian.matrix;
  const auto n = static_cast<size_t>(rows.rows());
  const auto nf = static_cast<size_t>(frames);
  const double b = temporal_weight;
  TVF_CHECK(fixed.size() == n * nf && values.size() == n * nf && z.size() == n * nf,
            "distributed space-time sizes {} {} {} for {} entries", fixed.size(), values.size(), z.size(), n * nf);
  // PETSc's index type (32 bits in Debian's build) must count the real unknowns.
  if (static_cast<double>(2 * n * nf) > static_cast<double>(std::numeric_limits<PetscInt>::max()))
    throw Error(fmt::format("the distributed solve's {} real unknowns (2 · {} vertices · {} frames) exceed what "
                            "this PETSc indexes ({}); it needs a PETSc built with 64-bit indices",
                            2 * n * nf, n, nf, std::numeric_limits<PetscInt>::max()));
  const Distribution d = distribute(rows, nf, comm);
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
  s.fixed.resize(nlf);
  for (size_t j = 0; j < nf; ++j)
    for (size_t i = 0; i < s.nl; ++i) s.fixed[j * s.nl + i] = fixed[j * n + static_cast<size_t>(d.owned[i])];
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

  // The right-hand side −A_FC v_C and the first guess (z's free entries), fixed entries 0.
  {
    PetscScalar *ra = nullptr, *xa = nullptr;
    check(VecGetArray(rhs, &ra), "VecGetArray");
    check(VecGetArray(x, &xa), "VecGetArray");
    auto* rs = reinterpret_cast<cplx*>(ra);
    auto* xs = reinterpret_cast<cplx*>(xa);
    for (size_t j = 0; j < nf; ++j) {
      const cplx* vj = values.data() + j * n;
      const char* fj = fixed.data() + j * n;
      for (size_t i = 0; i < s.nl; ++i) {
        const size_t k = j * s.nl + i;
        const auto v = static_cast<size_t>(d.owned[i]);
        if (fj[v]) {
          rs[k] = xs[k] = 0;
          continue;
        }
        cplx acc(0, 0);
        for (RowMatrix::InnerIterator it(rows, static_cast<Eigen::Index>(v)); it; ++it) {
          const auto c = static_cast<size_t>(it.col());
          if (c != v && fj[c]) acc -= it.value() * vj[c];
        }
        const double c = b * s.weight_sum[i];
        // The temporal neighbours indexed from the array's start: fj[v − n] with v < n adds a
        // wrapped unsigned offset to the pointer (undefined behaviour; UBSan's pointer-overflow
        // check, found by fuzz_session).
        if (j > 0 && fixed[(j - 1) * n + v]) acc += c * values[(j - 1) * n + v];
        if (j + 1 < nf && fixed[(j + 1) * n + v]) acc += c * values[(j + 1) * n + v];
        rs[k] = acc;
        xs[k] = z[j * n + v];
      }
    }
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
    KSP ksp = nullptr;
    check(KSPCreate(comm, &ksp), "KSPCreate");
    check(KSPSetOperators(ksp, a, a), "KSPSetOperators");
    check(KSPSetType(ksp, KSPCG), "KSPSetType");
    PC pc = nullptr;
    check(KSPGetPC(ksp, &pc), "KSPGetPC");
    check(PCSetType(pc, PCSHELL), "PCSetType");
    check(PCShellSetContext(pc, &s), "PCShellSetContext");
    check(PCShellSetApply(pc, apply_preconditioner), "PCShellSetApply");
    check(PCShellSetName(pc, "temporal line solves"), "PCShellSetName");
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
    KSPDestroy(&ksp);
    MatDestroy(&a);
    report.method = fmt::format("PETSc CG (temporal line solves), matrix-free, {} iterations, {}", iterations, where);
    report.iterations = static_cast<int>(iterations);
    report.residual = rnorm / bnorm;
    report.success = reason > 0 && std::isfinite(report.residual) && report.residual <= options.tolerance;
  }

  // The gather: every rank's entries into z on every rank, frame by frame (a sum in which
  // each entry has one non-zero term, so exact).
  {
    const PetscScalar* xa = nullptr;
    check(VecGetArrayRead(x, &xa), "VecGetArrayRead");
    const auto* xs = reinterpret_cast<const cplx*>(xa);
    std::vector<cplx> frame(n);
    for (size_t j = 0; j < nf; ++j) {
      std::fill(frame.begin(), frame.end(), cplx(0, 0));
      for (size_t i = 0; i < s.nl; ++i) frame[static_cast<size_t>(d.owned[i])] = xs[j * s.nl + i];
      MPI_Allreduce(MPI_IN_PLACE, frame.data(), static_cast<int>(2 * n), MPI_DOUBLE, MPI_SUM, comm);
      for (size_t v = 0; v < n; ++v) z[j * n + v] = fixed[j * n + v] ? values[j * n + v] : frame[v];
    }
    check(VecRestoreArrayRead(x, &xa), "VecRestoreArrayRead");
  }
  VecScatterDestroy(&s.scatter);
  VecDestroy(&s.ghost);
  VecDestroy(&rhs);
  VecDestroy(&x);
  return report;
}

#endif

}  // namespace tvf
