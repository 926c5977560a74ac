#include "tvf/solve/connection_laplacian.h"

#include "support/test_meshes.h"
#include "tvf/mesh/grid.h"

#include <gtest/gtest.h>

#include <tbb/parallel_for.h>

#include <random>

namespace tvf {
namespace {

constexpr LaplacianWeights kAll[] = {LaplacianWeights::cotan, LaplacianWeights::uniform,
                                     LaplacianWeights::mean_value};

TEST(ConnectionLaplacian, ConstantFieldOnThePlaneIsInTheKernel) {
  const Mesh& grid = test::grid_mesh();
  const TangentBundle bundle(grid);
  for (auto w : kAll) {
    const ConnectionLaplacian l = connection_laplacian(bundle, w);
    const Eigen::VectorXcd c = Eigen::VectorXcd::Constant(grid.num_vertices(), cplx(0.3, -1.7));
    EXPECT_LT((l.matrix * c).cwiseAbs().maxCoeff(), 1e-12) << static_cast<int>(w);
  }
}

TEST(ConnectionLaplacian, HermitianForSymmetricWeightsOnly) {
  for (const auto& [name, mesh] : test::all_meshes()) {
    const TangentBundle bundle(*mesh);
    for (auto w : kAll) {
      const ConnectionLaplacian l = connection_laplacian(bundle, w);
      const Eigen::SparseMatrix<cplx> adj = l.matrix.adjoint();
      const double asym = (adj - l.matrix).norm() / l.matrix.norm();
      if (w == LaplacianWeights::mean_value) {
        EXPECT_FALSE(l.hermitian);
      } else {
        EXPECT_TRUE(l.hermitian);
        EXPECT_EQ(asym, 0.0) << name;
      }
    }
  }
}

TEST(ConnectionLaplacian, PositiveSemidefiniteAndDiagonalIsTheWeightSum) {
  for (const auto& [name, mesh] : test::all_meshes()) {
    const TangentBundle bundle(*mesh);
    const ConnectionLaplacian l = connection_laplacian(bundle, LaplacianWeights::cotan);
    std::mt19937 rng(3);
    std::normal_distribution<double> g;
    for (int k = 0; k < 5; ++k) {
      Eigen::VectorXcd z(mesh->num_vertices());
      for (auto& x : z) x = cplx(g(rng), g(rng));
      const cplx q = z.dot(l.matrix * z);  // zᴴ L z
      EXPECT_NEAR(q.imag(), 0.0, 1e-9 * std::abs(q)) << name;
      EXPECT_GE(q.real(), -1e-12) << name;
    }
    for (int v = 0; v < mesh->num_vertices(); ++v)
      EXPECT_NEAR(l.matrix.coeff(v, v).real(), l.weight_sum[v], 1e-12) << name;
  }
}

// Linear precision: with the boundary fixed to a linear field, every weight reproduces it
// in the interior of a planar mesh (the discrete maximum principle's exact case).
TEST(DirichletSolver, ReproducesLinearFieldsFromTheBoundary) {
  const Mesh grid = make_grid(GridSpec{23, 17, {-1, -0.5}, {2, 1.5}});
  const TangentBundle bundle(grid);
  for (auto w : kAll) {
    const ConnectionLaplacian l = connection_laplacian(bundle, w);
    DirichletSolver solver(l);
    std::vector<char> fixed(static_cast<size_t>(grid.num_vertices()));
    std::vector<cplx> values(fixed.size()), exact(fixed.size()), out(fixed.size());
    for (int v = 0; v < grid.num_vertices(); ++v) {
      const Vec3& x = grid.position(v);
      exact[static_cast<size_t>(v)] = cplx(0.5, 1) + cplx(2, -1) * x.x() + cplx(-0.3, 0.7) * x.y();
      fixed[static_cast<size_t>(v)] = grid.is_boundary_vertex(v);
      values[static_cast<size_t>(v)] = fixed[static_cast<size_t>(v)] ? exact[static_cast<size_t>(v)] : cplx(99, 99);
    }
    const SolveReport r = solver.solve(fixed, values, out);
    ASSERT_TRUE(r.success) << r.method;
    EXPECT_LT(r.residual, 1e-12);
    for (size_t v = 0; v < out.size(); ++v) EXPECT_LT(std::abs(out[v] - exact[v]), 1e-10) << v;
  }
}

TEST(DirichletSolver, KeepsConstraintsExactlyAndSolvesTheFreeRows) {
  for (const auto& [name, mesh] : test::all_meshes()) {
    const TangentBundle bundle(*mesh);
    const ConnectionLaplacian l = connection_laplacian(bundle);
    DirichletSolver solver(l);
    std::mt19937 rng(11);
    std::uniform_real_distribution<double> u(-1, 1);
    const auto n = static_cast<size_t>(mesh->num_vertices());
    std::vector<char> fixed(n);
    std::vector<cplx> values(n), out(n);
    for (size_t v = 0; v < n; ++v) {
      fixed[v] = u(rng) > 0.8;
      values[v] = cplx(u(rng), u(rng));
    }
    const SolveReport r = solver.solve(fixed, values, out);
    ASSERT_TRUE(r.success) << name;
    const Eigen::VectorXcd z = Eigen::Map<const Eigen::VectorXcd>(out.data(), static_cast<Eigen::Index>(n));
    const Eigen::VectorXcd lz = l.matrix * z;
    for (size_t v = 0; v < n; ++v) {
      if (fixed[v]) EXPECT_EQ(out[v], values[v]) << name;
      else EXPECT_LT(std::abs(lz[static_cast<Eigen::Index>(v)]), 1e-10) << name << " " << v;
    }
    // A second solve with other constraints reuses the symbolic analysis.
    for (size_t v = 0; v < n; ++v) fixed[v] = !fixed[v] && u(rng) > 0.5;
    EXPECT_TRUE(solver.solve(fixed, values, out).success);
  }
}

TEST(DirichletSolver, NoConstraintGivesTheZeroField) {
  const TangentBundle bundle(test::grid_mesh());
  const ConnectionLaplacian l = connection_laplacian(bundle);
  DirichletSolver solver(l);
  const auto n = static_cast<size_t>(test::grid_mesh().num_vertices());
  std::vector<char> fixed(n, 0);
  std::vector<cplx> values(n, cplx(1, 1)), out(n, cplx(5, 5));
  EXPECT_TRUE(solver.solve(fixed, values, out).success);
  for (const cplx& z : out) EXPECT_EQ(z, cplx(0, 0));
}

// Two planar grids side by side, only the first constrained: the second (flat connection,
// singular Laplacian) is held at zero and the first solved as on its own.
TEST(DirichletSolver, ComponentWithoutConstraintsGetsZero) {
  const Mesh& grid = test::grid_mesh();
  std::vector<Vec3> p = grid.positions();
  std::vector<Face> f = grid.faces();
  const int n0 = grid.num_vertices();
  for (const Vec3& x : grid.positions()) p.push_back(x + Vec3(10, 0, 0));
  for (const Face& t : grid.faces()) f.push_back({t[0] + n0, t[1] + n0, t[2] + n0});
  const Mesh two(std::move(p), std::move(f), "two grids");
  const TangentBundle bundle(two);
  const ConnectionLaplacian l = connection_laplacian(bundle);
  for (auto factorization : {DirichletFactorization::simplicial, DirichletFactorization::cholmod}) {
    DirichletSolver solver(l, factorization);
    const auto n = static_cast<size_t>(two.num_vertices());
    std::vector<char> fixed(n, 0);
    std::vector<cplx> values(n, cplx(0, 0)), out(n, cplx(5, 5));
    for (int v = 0; v < n0; ++v)
      if (grid.is_boundary_vertex(v)) {
        fixed[static_cast<size_t>(v)] = 1;
        values[static_cast<size_t>(v)] = cplx(0.5, -2.0);
      }
    const SolveReport r = solver.solve(fixed, values, out);
    ASSERT_TRUE(r.success) << r.failure;
    for (size_t v = 0; v < n; ++v) EXPECT_LT(std::abs(out[v] - (v < static_cast<size_t>(n0) ? cplx(0.5, -2.0) : cplx(0, 0))), 1e-12) << v;
  }
}

// A factorization that fails says which matrix, by which method, and why.
TEST(DirichletSolver, AFailedFactorizationNamesTheMatrixAndWhy) {
  const Mesh& grid = test::grid_mesh();
  const TangentBundle bundle(grid);
  ConnectionLaplacian l = connection_laplacian(bundle);
  for (int v = 0; v < grid.num_vertices(); ++v) l.matrix.coeffRef(v, v) -= 10.0;  // indefinite
  DirichletSolver solver(l, DirichletFactorization::cholmod);
  const auto n = static_cast<size_t>(grid.num_vertices());
  std::vector<char> fixed(n, 0);
  std::vector<cplx> values(n, cplx(1, 0)), out(n);
  fixed[0] = 1;
  const SolveReport r = solver.solve(fixed, values, out);
  EXPECT_FALSE(r.success);
  EXPECT_NE(r.failure.find("connection Laplacian (cotan weights"), std::string::npos) << r.failure;
  EXPECT_NE(r.failure.find("CHOLMOD"), std::string::npos) << r.failure;
  EXPECT_NE(r.failure.find("not positive definite"), std::string::npos) << r.failure;
}

// On meshes that are already Delaunay the cotan connection Laplacian is the input
// triangles' own, bit for bit: ½(cot α + cot β) from the 3D corners and
// TangentBundle::transport.
TEST(ConnectionLaplacian, CotanIsTheInputsOwnOnDelaunayMeshes) {
  for (const auto& [name, mesh] : test::all_meshes()) {
    const TangentBundle bundle(*mesh);
    const ConnectionLaplacian l = connection_laplacian(bundle);
    EXPECT_EQ(l.intrinsic_flips, 0) << name;
    EXPECT_EQ(l.mollification, 0.0) << name;
    auto cot = [&](int h) {
      const int o = Mesh::prev(h);
      const Vec3& a = mesh->position(mesh->tail(o));
      const Vec3 u = mesh->position(mesh->head(o)) - a;
      const Vec3 w = mesh->position(mesh->tail(Mesh::prev(o))) - a;
      return u.dot(w) / u.cross(w).norm();
    };
    for (int h = 0; h < mesh->num_halfedges(); ++h) {
      const int i = mesh->tail(h), j = mesh->head(h), t = mesh->twin(h);
      double w = 0.5 * cot(h);
      if (t >= 0) w += 0.5 * cot(t);
      // Boundary edges of the hemisphere may have an obtuse opposite angle: clamped.
      w = std::max(w, 0.0);
      ASSERT_EQ(l.matrix.coeff(j, i), -w * bundle.transport(h)) << name << " " << h;
    }
  }
}

// CHOLMOD's supernodal LLᴴ (the default for Hermitian weights) against Eigen's simplicial
// LDLᴴ: the same solution to rounding on every test mesh, frame after frame with one
// symbolic analysis, in the solver and in its copies (one per thread in the generators).
TEST(DirichletSolver, CholmodAgreesWithTheSimplicialFactorization) {
  for (const auto& [name, mesh] : test::all_meshes()) {
    const TangentBundle bundle(*mesh);
    for (auto w : {LaplacianWeights::cotan, LaplacianWeights::uniform}) {
      const ConnectionLaplacian l = connection_laplacian(bundle, w);
      DirichletSolver simplicial(l, DirichletFactorization::simplicial);
      DirichletSolver cholmod(l, DirichletFactorization::cholmod);
      DirichletSolver copy(cholmod);
      EXPECT_EQ(copy.factorization(), DirichletFactorization::cholmod) << name;
      std::mt19937 rng(7);
      std::uniform_real_distribution<double> u(-1, 1);
      const auto n = static_cast<size_t>(mesh->num_vertices());
      for (int frame = 0; frame < 3; ++frame) {
        std::vector<char> fixed(n);
        std::vector<cplx> values(n), a(n), b(n), c(n);
        for (size_t v = 0; v < n; ++v) {
          fixed[v] = u(rng) > 0.7 - 0.2 * frame;
          values[v] = cplx(u(rng), u(rng));
        }
        const SolveReport ra = simplicial.solve(fixed, values, a);
        const SolveReport rb = cholmod.solve(fixed, values, b);
        const SolveReport rc = copy.solve(fixed, values, c);
        ASSERT_TRUE(ra.success && rb.success && rc.success) << name;
        EXPECT_NE(ra.method, rb.method);
        EXPECT_LT(rb.residual, 1e-12) << name;
        // The residual the solver reports is the one measured here.
        Eigen::VectorXcd z = Eigen::Map<const Eigen::VectorXcd>(b.data(), static_cast<Eigen::Index>(n));
        const Eigen::VectorXcd lz = l.matrix * z;
        double free2 = 0, rhs2 = 0;
        for (size_t v = 0; v < n; ++v) {
          if (fixed[v]) {
            EXPECT_EQ(b[v], values[v]) << name;
            rhs2 += std::norm(values[v]);
          } else {
            free2 += std::norm(lz[static_cast<Eigen::Index>(v)]);
          }
        }
        EXPECT_LT(std::sqrt(free2), 1e-11 * std::sqrt(rhs2) * l.weight_sum.maxCoeff()) << name;
        double scale = 0, diff = 0;
        for (size_t v = 0; v < n; ++v) {
          scale = std::max(scale, std::abs(a[v]));
          diff = std::max(diff, std::abs(a[v] - b[v]));
          EXPECT_EQ(b[v], c[v]) << name << ": a copy factors exactly as the original";
        }
        EXPECT_LT(diff, 1e-11 * scale) << name << " frame " << frame;
      }
    }
  }
}

// automatic: CHOLMOD for Hermitian weights on large meshes (where it was measured faster),
// the simplicial LDLᴴ on small ones, sparse LU for mean-value weights (CHOLMOD refused).
TEST(DirichletSolver, AutomaticTakesCholmodForLargeHermitianProblems) {
  const TangentBundle small(test::grid_mesh());
  EXPECT_EQ(DirichletSolver(connection_laplacian(small)).factorization(), DirichletFactorization::simplicial);
  const Mesh large_grid = make_grid(GridSpec{100, 100, {-1, -1}, {1, 1}});
  const TangentBundle large(large_grid);
  const ConnectionLaplacian cotan = connection_laplacian(large);
  DirichletSolver solver(cotan);
  EXPECT_EQ(solver.factorization(), DirichletFactorization::cholmod);
  const ConnectionLaplacian mean_value = connection_laplacian(large, LaplacianWeights::mean_value);
  EXPECT_EQ(DirichletSolver(mean_value).factorization(), DirichletFactorization::simplicial);
  EXPECT_THROW(DirichletSolver(mean_value, DirichletFactorization::cholmod), std::exception);
  // A large solve, frames in parallel as the generators run them: each thread's copy
  // reproduces the boundary's linear field.
  const auto n = static_cast<size_t>(large_grid.num_vertices());
  std::vector<char> fixed(n);
  std::vector<cplx> values(n), exact(n);
  for (int v = 0; v < large_grid.num_vertices(); ++v) {
    const Vec3& x = large_grid.position(v);
    exact[static_cast<size_t>(v)] = cplx(0.5, 1) + cplx(2, -1) * x.x() + cplx(-0.3, 0.7) * x.y();
    fixed[static_cast<size_t>(v)] = large_grid.is_boundary_vertex(v);
    values[static_cast<size_t>(v)] = fixed[static_cast<size_t>(v)] ? exact[static_cast<size_t>(v)] : cplx(0, 0);
  }
  std::vector<std::vector<cplx>> out(4, std::vector<cplx>(n));
  std::vector<SolveReport> reports(4);
  tbb::parallel_for(0, 4, [&](int k) {
    DirichletSolver copy(solver);
    reports[static_cast<size_t>(k)] = copy.solve(fixed, values, out[static_cast<size_t>(k)]);
  });
  for (int k = 0; k < 4; ++k) {
    ASSERT_TRUE(reports[static_cast<size_t>(k)].success);
    EXPECT_LT(reports[static_cast<size_t>(k)].residual, 1e-12);
    for (size_t v = 0; v < n; ++v) EXPECT_LT(std::abs(out[static_cast<size_t>(k)][v] - exact[v]), 1e-9) << v;
  }
}

}  // namespace
}  // namespace tvf
