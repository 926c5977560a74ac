#include "tvf/solve/spacetime.h"

#include "tvf/core/error.h"

#include "support/test_meshes.h"

#include <gtest/gtest.h>

#include <algorithm>
#include <random>
#include <string>

namespace tvf {
namespace {

// Fixed whole first and last frames with constant fields: every interior frame is
// constant in space (in L's kernel on the plane) and linear in time (the path graph's
// harmonic functions).
TEST(SpaceTime, ConstantKeyFramesInterpolateLinearlyInTime) {
  const Mesh& grid = test::grid_mesh();
  const TangentBundle bundle(grid);
  const ConnectionLaplacian l = connection_laplacian(bundle);
  const int nf = 11;
  const auto n = static_cast<size_t>(grid.num_vertices());
  SpaceTimeSolver solver(l, nf, 30.0);
  std::vector<char> fixed(n * nf, 0);
  std::vector<cplx> values(n * nf), z(n * nf, cplx(0, 0));
  const cplx c0(1, -2), c1(-0.5, 3);
  for (size_t i = 0; i < n; ++i) {
    fixed[i] = fixed[(nf - 1) * n + i] = 1;
    values[i] = c0;
    values[(nf - 1) * n + i] = c1;
  }
  const SolveReport r = solver.solve(fixed, values, z);
  ASSERT_TRUE(r.success) << r.residual;
  for (int j = 0; j < nf; ++j)
    for (size_t i = 0; i < n; ++i) {
      const cplx expected = c0 + (c1 - c0) * (j / double(nf - 1));
      EXPECT_LT(std::abs(z[static_cast<size_t>(j) * n + i] - expected), 1e-8) << j << " " << i;
    }
}

// Against the assembled normal equations A = I ⊗ L + b (T ⊗ D) on small meshes: the
// free rows of A z vanish to the tolerance, and the fixed entries are kept exactly.
TEST(SpaceTime, SolvesTheAssembledSystem) {
  for (const auto& [name, mesh] : test::all_meshes()) {
    const TangentBundle bundle(*mesh);
    const ConnectionLaplacian l = connection_laplacian(bundle);
    const int nf = 7;
    const double b = 30;
    const auto n = static_cast<size_t>(mesh->num_vertices());
    std::vector<Eigen::Triplet<cplx>> t;
    for (int j = 0; j < nf; ++j) {
      for (int col = 0; col < l.matrix.outerSize(); ++col)
        for (Eigen::SparseMatrix<cplx>::InnerIterator it(l.matrix, col); it; ++it)
          t.emplace_back(j * int(n) + int(it.row()), j * int(n) + col, it.value());
      for (size_t i = 0; i < n; ++i) {
        const double c = b * l.weight_sum[static_cast<Eigen::Index>(i)];
        const int k = j * int(n) + int(i);
        if (j > 0) t.emplace_back(k, k, c), t.emplace_back(k, k - int(n), -c);
        if (j + 1 < nf) t.emplace_back(k, k, c), t.emplace_back(k, k + int(n), -c);
      }
    }
    Eigen::SparseMatrix<cplx> a(int(n) * nf, int(n) * nf);
    a.setFromTriplets(t.begin(), t.end());

    std::mt19937 rng(5);
    std::uniform_real_distribution<double> u(-1, 1);
    std::vector<char> fixed(n * nf, 0);
    std::vector<cplx> values(n * nf), z(n * nf, cplx(0, 0));
    for (size_t k = 0; k < fixed.size(); ++k) {
      const bool key = k < n || k >= (nf - 1) * n;  // key frames at both ends
      fixed[k] = key || u(rng) > 0.97;                 // plus scattered element constraints
      values[k] = cplx(u(rng), u(rng));
    }
    SpaceTimeSolver solver(l, nf, b);
    SpaceTimeOptions opt;
    opt.tolerance = 1e-11;
    const SolveReport r = solver.solve(fixed, values, z, opt);
    ASSERT_TRUE(r.success) << name << " residual " << r.residual;
    EXPECT_GT(r.iterations, 0);
    const Eigen::VectorXcd zz = Eigen::Map<const Eigen::VectorXcd>(z.data(), static_cast<Eigen::Index>(z.size()));
    const Eigen::VectorXcd az = a * zz;
    double free_norm = 0, scale = 0;
    for (size_t k = 0; k < fixed.size(); ++k) {
      if (fixed[k]) {
        EXPECT_EQ(z[k], values[k]);
        scale += std::norm(az[static_cast<Eigen::Index>(k)]);
      } else {
        free_norm += std::norm(az[static_cast<Eigen::Index>(k)]);
      }
    }
    EXPECT_LT(std::sqrt(free_norm), 1e-8 * std::sqrt(scale)) << name;

    // Warm start from the solution: nothing left to do.
    const SolveReport again = solver.solve(fixed, values, z, opt);
    EXPECT_LE(again.iterations, 1) << name;
  }
}

// Key frames in the middle (so segments with a Neumann end at the first and last frame)
// and static element regions (the same vertices at every frame): the temporal-mode method
// applies, and its result is the CG's and the paper's BiCGStab's to the tolerance, on
// planar and curved meshes.
TEST(SpaceTime, TemporalModesAgreeWithCGAndBiCGStab) {
  for (const auto& [name, mesh] : test::all_meshes()) {
    // Key frames 3 and 8 (segments Neumann–Dirichlet, Dirichlet–Dirichlet,
    // Dirichlet–Neumann), or none (one Neumann–Neumann segment); elements at every frame.
    for (const bool key_frames : {true, false}) {
      const TangentBundle bundle(*mesh);
      const ConnectionLaplacian l = connection_laplacian(bundle);
      const int nf = 12;
      const auto n = static_cast<size_t>(mesh->num_vertices());
      std::mt19937 rng(11);
      std::uniform_real_distribution<double> u(-1, 1);
      std::vector<char> fixed(n * nf, 0), element(n, 0);
      std::vector<cplx> values(n * nf);
      for (size_t i = 0; i < n; ++i) element[i] = u(rng) > 0.9;
      for (int j = 0; j < nf; ++j)
        for (size_t i = 0; i < n; ++i) {
          const size_t k = static_cast<size_t>(j) * n + i;
          fixed[k] = (key_frames && (j == 3 || j == 8)) || element[i];
          values[k] = cplx(u(rng), u(rng));
        }
      SpaceTimeSolver solver(l, nf, 30.0);
      ASSERT_TRUE(solver.modes_apply(fixed)) << name;
      SpaceTimeOptions opt;
      opt.tolerance = 1e-11;
      std::vector<std::vector<cplx>> results;
      for (auto method : {SpaceTimeMethod::modes, SpaceTimeMethod::cg, SpaceTimeMethod::bicgstab_jacobi}) {
        opt.method = method;
        std::vector<cplx> z(n * nf, cplx(0, 0));
        const SolveReport r = solver.solve(fixed, values, z, opt);
        ASSERT_TRUE(r.success) << name << " " << r.method << " residual " << r.residual;
        EXPECT_LE(r.residual, 1e-11) << name << " " << r.method;
        results.push_back(z);
      }
      double scale = 0, d_cg = 0, d_bicg = 0;
      for (size_t k = 0; k < n * nf; ++k) {
        scale = std::max(scale, std::abs(results[0][k]));
        d_cg = std::max(d_cg, std::abs(results[0][k] - results[1][k]));
        d_bicg = std::max(d_bicg, std::abs(results[0][k] - results[2][k]));
      }
      EXPECT_LT(d_cg, 1e-8 * scale) << name << (key_frames ? " with" : " without") << " key frames";
      EXPECT_LT(d_bicg, 1e-8 * scale) << name << (key_frames ? " with" : " without") << " key frames";
    }
  }
}

// A fixed set that moves in time (a moving element) couples the modes: automatic takes
// CG, and asking for the modes is refused.
TEST(SpaceTime, MovingConstraintsTakeCG) {
  const Mesh& grid = test::grid_mesh();
  const TangentBundle bundle(grid);
  const ConnectionLaplacian l = connection_laplacian(bundle);
  const int nf = 6;
  const auto n = static_cast<size_t>(grid.num_vertices());
  std::vector<char> fixed(n * nf, 0);
  std::vector<cplx> values(n * nf, cplx(0, 0)), z(n * nf, cplx(0, 0));
  for (size_t i = 0; i < n; ++i) fixed[i] = 1, values[i] = cplx(1, 0);
  for (int j = 1; j < nf; ++j) {
    const size_t k = static_cast<size_t>(j) * n + static_cast<size_t>(j);  // vertex j at frame j
    fixed[k] = 1;
    values[k] = cplx(0, 1);
  }
  SpaceTimeSolver solver(l, nf, 30.0);
  EXPECT_FALSE(solver.modes_apply(fixed));
  const SolveReport r = solver.solve(fixed, values, z);
  EXPECT_TRUE(r.success);
  EXPECT_NE(r.method.find("CG"), std::string::npos) << r.method;
  SpaceTimeOptions modes;
  modes.method = SpaceTimeMethod::modes;
  EXPECT_THROW(solver.solve(fixed, values, z, modes), InternalError);  // a caller's mistake
}

TEST(SpaceTime, InterpolationInTimeIsTheFirstGuess) {
  const Mesh& grid = test::grid_mesh();
  const TangentBundle bundle(grid);
  const ConnectionLaplacian l = connection_laplacian(bundle);
  const auto n = static_cast<size_t>(grid.num_vertices());
  SpaceTimeSolver solver(l, 5, 30.0);
  std::vector<char> fixed(n * 5, 0);
  std::vector<cplx> values(n * 5, cplx(0, 0)), z(n * 5);
  fixed[1 * n + 3] = 1, values[1 * n + 3] = cplx(2, 0);
  fixed[3 * n + 3] = 1, values[3 * n + 3] = cplx(0, 4);
  solver.interpolate_in_time(fixed, values, z);
  EXPECT_EQ(z[0 * n + 3], cplx(2, 0));
  EXPECT_EQ(z[2 * n + 3], cplx(1, 2));
  EXPECT_EQ(z[4 * n + 3], cplx(0, 4));
  EXPECT_EQ(z[2 * n + 4], cplx(0, 0));  // a line with no fixed entry
}

}  // namespace
}  // namespace tvf
