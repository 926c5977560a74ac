// The per-frame constrained solve alone (DirichletSolver, paper §5.3): one numeric
// factorization and solve per frame on the grids and the 20,252-vertex sphere of the other
// benchmarks, by each factorization (docs/benchmarks.md, "Sparse factorizations").
//   BM_DirichletFrames/MESH/FACTORIZATION/SCHEDULE
//   MESH: 0 the 65×65 grid, 1 the 141×141 grid, 2 make_geodesic_sphere(45) (20,252
//   vertices), 3 the icosphere of 10,242 vertices
//   FACTORIZATION: 0 Eigen's SimplicialLDLᴴ, 1 CHOLMOD supernodal LLᴴ
//   SCHEDULE: 0 frames in sequence, 1 frames in parallel (TBB, a solver per thread, as
//   generate_constrained does). DirichletSolver holds OpenBLAS to one thread while CHOLMOD
//   factors; the schedules with OpenBLAS's own threads in docs/benchmarks.md were measured
//   before it did.
// 20 frames a run; constraints are discs around 6 points that move from frame to frame.
#include "tvf/mesh/grid.h"
#include "tvf/mesh/primitives.h"
#include "tvf/solve/connection_laplacian.h"

#include <Eigen/CholmodSupport>
#include <Eigen/SparseCholesky>
#include <benchmark/benchmark.h>
#include <cblas.h>
#include <tbb/enumerable_thread_specific.h>
#include <tbb/parallel_for.h>

#include <atomic>
#include <cmath>
#include <ctime>
#include <memory>

namespace tvf {
namespace {

double cpu_ms_now() {
  timespec t{};
  clock_gettime(CLOCK_PROCESS_CPUTIME_ID, &t);
  return static_cast<double>(t.tv_sec) * 1e3 + static_cast<double>(t.tv_nsec) * 1e-6;
}

Mesh bench_mesh(int which) {
  if (which == 0) return make_grid(GridSpec{65, 65, {-1, -1}, {1, 1}}, "65 grid");
  if (which == 1) return make_grid(GridSpec{141, 141, {-1, -1}, {1, 1}}, "141 grid");
  if (which == 3) return make_icosphere(5);
  return make_geodesic_sphere(45);
}

void BM_DirichletFrames(benchmark::State& state) {
  const Mesh mesh = bench_mesh(static_cast<int>(state.range(0)));
  const TangentBundle bundle(mesh);
  const ConnectionLaplacian l = connection_laplacian(bundle);
  const auto factorization =
      state.range(1) == 0 ? DirichletFactorization::simplicial : DirichletFactorization::cholmod;
  const int schedule = static_cast<int>(state.range(2));
  const auto n = static_cast<size_t>(mesh.num_vertices());
  constexpr int kFrames = 20;
  // Frame j: vertices within 0.12 of six points turning about the z axis, values i·(x − c).
  std::vector<std::vector<char>> fixed(kFrames, std::vector<char>(n, 0));
  std::vector<std::vector<cplx>> values(kFrames, std::vector<cplx>(n, cplx(0, 0)));
  for (int j = 0; j < kFrames; ++j)
    for (int e = 0; e < 6; ++e) {
      const double a = 2 * kPi * e / 6 + 0.05 * j;
      const Vec3 c = state.range(0) < 2 ? Vec3(0.6 * std::cos(a), 0.6 * std::sin(a), 0)
                                        : Vec3(std::cos(a), std::sin(a), 0.3).normalized();
      for (size_t v = 0; v < n; ++v)
        if ((mesh.position(static_cast<int>(v)) - c).norm() < 0.12) {
          fixed[static_cast<size_t>(j)][v] = 1;
          values[static_cast<size_t>(j)][v] = cplx(0.5 + e, 1.0 - e);
        }
    }
  std::vector<std::vector<cplx>> out(kFrames, std::vector<cplx>(n));
  const DirichletSolver prototype(l, factorization);
  tbb::enumerable_thread_specific<DirichletSolver> solvers(prototype);
  double worst = 0;
  std::atomic<bool> ok{true};
  double cpu = 0;
  for (auto _ : state) {
    const double c0 = cpu_ms_now();
    if (schedule == 0) {
      DirichletSolver& s = solvers.local();
      for (int j = 0; j < kFrames; ++j) {
        const SolveReport r = s.solve(fixed[static_cast<size_t>(j)], values[static_cast<size_t>(j)],
                                      out[static_cast<size_t>(j)]);
        if (!r.success) ok = false;
        worst = std::max(worst, r.residual);
      }
    } else {
      tbb::parallel_for(0, kFrames, [&](int j) {
        const SolveReport r = solvers.local().solve(fixed[static_cast<size_t>(j)], values[static_cast<size_t>(j)],
                                                    out[static_cast<size_t>(j)]);
        if (!r.success) ok = false;
      });
    }
    cpu += cpu_ms_now() - c0;
  }
  if (!ok) state.SkipWithError("a solve failed");
  state.counters["cpu_ms"] = cpu / static_cast<double>(state.iterations());
  state.counters["vertices"] = static_cast<double>(n);
  state.counters["frames"] = kFrames;
  state.counters["residual"] = worst;
  DirichletSolver one(prototype);
  state.SetLabel(one.solve(fixed[0], values[0], out[0]).method);
}
BENCHMARK(BM_DirichletFrames)
    ->ArgNames({"mesh", "cholmod", "schedule"})
    ->ArgsProduct({{0, 1, 2, 3}, {0, 1}, {0, 1}})
    ->Unit(benchmark::kMillisecond);

}  // namespace
}  // namespace tvf

namespace tvf {
namespace {

// GCC 12 warns of a null pointer in Eigen's viewAsCholmod of a compressed matrix, which
// cannot occur (as in src/solve/connection_laplacian.cpp).
#pragma GCC diagnostic push
#pragma GCC diagnostic ignored "-Wnull-dereference"

// One factorization (symbolic + numeric) and one solve, one thread, of the matrices of the
// log map's set-up (docs/architecture.md, "Local coordinates on surfaces") and of the
// Hodge projection's kind, by each factorization, OpenBLAS held to one thread:
//   BM_SparseFactor/MESH/MATRIX/CHOLMOD
//   MESH: 0 the icosphere of 10,242 vertices, 1 make_geodesic_sphere(45) (20,252)
//   MATRIX: 0 the scalar heat system M + h²L (real), 1 the vector heat system M + h²L∇
//   (complex), 2 L M⁻¹ L + M (real, the 2-ring pattern of the Hodge projection's D W⁻¹ Dᵀ)
//   CHOLMOD: 0 Eigen's SimplicialLDLT, 1 CHOLMOD supernodal LLᵀ
// Counters (CPU time): analyze_factor_ms (analysis + factorization), solve_ms (one
// right-hand side).
template <class Solver, class Matrix>
void factor_and_solve(benchmark::State& state, const Matrix& a, Solver& solver) {
  using Vector = Eigen::Matrix<typename Matrix::Scalar, Eigen::Dynamic, 1>;
  const Vector b = Vector::Ones(a.rows());
  double factor = 0, solve = 0, residual = 0;
  for (auto _ : state) {
    const double c0 = cpu_ms_now();
    solver.compute(a);
    const double c1 = cpu_ms_now();
    const Vector x = solver.solve(b);
    const double c2 = cpu_ms_now();
    factor += c1 - c0;
    solve += c2 - c1;
    residual = (a * x - b).norm() / b.norm();
    if (solver.info() != Eigen::Success) state.SkipWithError("factorization failed");
  }
  state.counters["analyze_factor_ms"] = factor / static_cast<double>(state.iterations());
  state.counters["solve_ms"] = solve / static_cast<double>(state.iterations());
  state.counters["residual"] = residual;
  state.counters["vertices"] = static_cast<double>(a.rows());
}

void BM_SparseFactor(benchmark::State& state) {
  const Mesh mesh = state.range(0) == 0 ? make_icosphere(5) : make_geodesic_sphere(45);
  const TangentBundle bundle(mesh);
  const ConnectionLaplacian l = connection_laplacian(bundle);
  const int nv = mesh.num_vertices();
  Eigen::VectorXd mass = Eigen::VectorXd::Zero(nv);
  for (int f = 0; f < mesh.num_faces(); ++f)
    for (int v : mesh.face(f)) mass[v] += mesh.face_area(f) / 3.0;
  const double h2 = mesh.mean_edge_length() * mesh.mean_edge_length();
  // The scalar cotan Laplacian: the connection Laplacian's weights (as magnitudes) without the transports.
  std::vector<Eigen::Triplet<double>> t;
  for (int c = 0; c < l.matrix.outerSize(); ++c)
    for (Eigen::SparseMatrix<cplx>::InnerIterator it(l.matrix, c); it; ++it)
      if (it.row() != c) {
        t.emplace_back(static_cast<int>(it.row()), c, -std::abs(it.value()));
      }
  for (int v = 0; v < nv; ++v) t.emplace_back(v, v, l.weight_sum[v]);
  Eigen::SparseMatrix<double> ls(nv, nv);
  ls.setFromTriplets(t.begin(), t.end());
  const bool cholmod = state.range(2) != 0;
  const int blas_threads = openblas_get_num_threads();
  openblas_set_num_threads(1);
  struct Restore {
    int threads;
    ~Restore() { openblas_set_num_threads(threads); }
  } restore{blas_threads};
  Eigen::SparseMatrix<double> m(nv, nv);
  for (int v = 0; v < nv; ++v) m.insert(v, v) = mass[v];
  if (state.range(1) == 1) {
    Eigen::SparseMatrix<cplx> a = l.matrix * cplx(h2, 0);
    for (int v = 0; v < nv; ++v) a.coeffRef(v, v) += mass[v];
    if (cholmod) {
      Eigen::CholmodSupernodalLLT<Eigen::SparseMatrix<cplx>> s;
      factor_and_solve(state, a, s);
    } else {
      Eigen::SimplicialLDLT<Eigen::SparseMatrix<cplx>> s;
      factor_and_solve(state, a, s);
    }
    return;
  }
  Eigen::SparseMatrix<double> a;
  if (state.range(1) == 0) {
    a = m + h2 * ls;
  } else {
    const Eigen::VectorXd inv = mass.cwiseInverse();
    a = Eigen::SparseMatrix<double>(ls * inv.asDiagonal() * ls) + m;
  }
  if (cholmod) {
    Eigen::CholmodSupernodalLLT<Eigen::SparseMatrix<double>> s;
    factor_and_solve(state, a, s);
  } else {
    Eigen::SimplicialLDLT<Eigen::SparseMatrix<double>> s;
    factor_and_solve(state, a, s);
  }
}
BENCHMARK(BM_SparseFactor)
    ->ArgNames({"mesh", "matrix", "cholmod"})
    ->ArgsProduct({{0, 1}, {0, 1, 2}, {0, 1}})
    ->Unit(benchmark::kMillisecond);

}  // namespace
}  // namespace tvf

#pragma GCC diagnostic pop
