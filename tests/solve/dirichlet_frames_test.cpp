#include "tvf/solve/dirichlet_frames.h"

#include "support/test_meshes.h"

#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <mutex>
#include <random>

namespace tvf {
namespace {

// A moving disc of fixed vertices with a ramp of penalties around it, and a static one,
// frame after frame: the constrained generator's kind of problems.
struct Frames {
  std::vector<std::vector<char>> fixed;
  std::vector<std::vector<cplx>> values;
  std::vector<std::vector<double>> penalty;

  std::vector<DirichletProblem> problems() const {
    std::vector<DirichletProblem> p;
    for (size_t k = 0; k < fixed.size(); ++k) p.push_back({fixed[k], values[k], penalty[k]});
    return p;
  }
};

Frames moving_discs(const Mesh& mesh, const ConnectionLaplacian& l, int frames, double radius, bool with_static = true) {
  Frames f;
  const auto n = static_cast<size_t>(mesh.num_vertices());
  const double h = mesh.mean_edge_length();
  // The path: a quarter turn around the mesh's centroid, from one extreme vertex.
  Vec3 centre = Vec3::Zero();
  for (const Vec3& x : mesh.positions()) centre += x;
  centre /= static_cast<double>(n);
  const Vec3 start = mesh.position(0);
  const Vec3 fixed_at = mesh.position(mesh.num_vertices() - 1);
  std::mt19937 rng(7);
  std::uniform_real_distribution<double> u(-1, 1);
  for (int k = 0; k < frames; ++k) {
    const double s = 0.6 * k / std::max(1, frames - 1);  // along the segment start → centre
    const Vec3 p = start + s * (centre - start);
    std::vector<char> fixed(n, 0);
    std::vector<cplx> values(n);
    std::vector<double> penalty(n, 0.0);
    for (size_t v = 0; v < n; ++v) {
      values[v] = cplx(u(rng), u(rng));
      const double rho = (mesh.position(static_cast<int>(v)) - p).norm();
      if (rho <= radius) {
        fixed[v] = 1;
      } else if (rho < radius + 2 * h) {
        const double x = (radius + 2 * h - rho) / (2 * h);
        const double psi = x * x * (3 - 2 * x);
        penalty[v] = l.weight_sum[static_cast<Eigen::Index>(v)] * psi / (1 - psi);
      }
      if (with_static && (mesh.position(static_cast<int>(v)) - fixed_at).norm() <= radius) fixed[v] = 1;
    }
    f.fixed.push_back(std::move(fixed));
    f.values.push_back(std::move(values));
    f.penalty.push_back(std::move(penalty));
  }
  return f;
}

// Every frame of a shared block is the frame solved alone by DirichletSolver, to rounding,
// and its fixed vertices hold their values exactly; on every mesh of the catalogue (grids:
// a real factorization; curved meshes: a complex one), with the block factored by Eigen's
// simplicial LDLᴴ and by CHOLMOD's supernodal one.
TEST(DirichletFrames, ABlockOfMovingConstraintsGivesEachFramesOwnSolution) {
  for (const auto& [name, mesh] : test::all_meshes()) {
    const TangentBundle bundle(*mesh);
    const ConnectionLaplacian l = connection_laplacian(bundle);
    const Frames f = moving_discs(*mesh, l, 7, 3 * mesh->mean_edge_length());
    const auto n = static_cast<size_t>(mesh->num_vertices());
    DirichletSolver alone(l, DirichletFactorization::simplicial);
    for (const int cholmod_from : {0, 1 << 30}) {
      const std::string what = name + (cholmod_from == 0 ? " (CHOLMOD)" : " (simplicial)");
      std::vector<std::vector<cplx>> out(f.fixed.size(), std::vector<cplx>(n));
      std::vector<std::span<cplx>> spans(out.begin(), out.end());
      DirichletFramesOptions o;
      o.max_trailing_fraction = 1.0;  // never split
      o.cholmod_from = cholmod_from;
      const DirichletFrames frames(l, o);
      DirichletFrames::Statistics stats;
      const std::vector<DirichletProblem> problems = f.problems();
      const std::vector<SolveReport> reports = frames.solve(problems, spans, &stats);
      EXPECT_EQ(stats.blocks, 1) << what;  // one factorization for the seven frames
      EXPECT_GT(stats.largest_trailing, 0) << what;
      EXPECT_EQ(frames.real(), bundle.is_flat()) << what;
      for (size_t k = 0; k < f.fixed.size(); ++k) {
        ASSERT_TRUE(reports[k].success) << what << " " << reports[k].failure;
        EXPECT_LT(reports[k].residual, 1e-12) << what << " frame " << k;
        std::vector<cplx> expected(n);
        ASSERT_TRUE(alone.solve(f.fixed[k], f.values[k], expected, f.penalty[k]).success);
        double worst = 0, largest = 0;
        for (size_t v = 0; v < n; ++v) {
          worst = std::max(worst, std::abs(out[k][v] - expected[v]));
          largest = std::max(largest, std::abs(expected[v]));
          if (f.fixed[k][v]) {
            EXPECT_EQ(out[k][v], f.values[k][v]) << what << " frame " << k << " vertex " << v;
          }
        }
        EXPECT_LT(worst, 1e-11 * largest) << what << " frame " << k;
      }
    }
  }
}

// The frames of a block solved at once on TBB's threads: the same results bit for bit as
// one after the other (each thread its own Schur complement; the block's factor only
// read), the viewer's frame still first, and after_each called once for every frame.
TEST(DirichletFrames, FramesSolvedAtOnceEqualThemSolvedInTurn) {
  for (const bool cholmod : {false, true}) {
    const Mesh& mesh = test::icosphere_mesh();
    const TangentBundle bundle(mesh);
    const ConnectionLaplacian l = connection_laplacian(bundle);
    const Frames f = moving_discs(mesh, l, 12, 3 * mesh.mean_edge_length());
    const auto n = static_cast<size_t>(mesh.num_vertices());
    DirichletFramesOptions o;
    o.max_trailing_fraction = 1.0;
    o.cholmod_from = cholmod ? 0 : 1 << 30;
    const DirichletFrames frames(l, o);
    const std::vector<DirichletProblem> problems = f.problems();
    auto run = [&](bool parallel, std::vector<std::vector<cplx>>& out, std::vector<size_t>& order) {
      out.assign(f.fixed.size(), std::vector<cplx>(n));
      std::vector<std::span<cplx>> spans(out.begin(), out.end());
      std::mutex m;
      const auto after = [&](size_t k) {
        std::lock_guard lock(m);
        order.push_back(k);
      };
      return frames.solve(problems, spans, nullptr, after, 5, parallel);
    };
    std::vector<std::vector<cplx>> in_turn, at_once;
    std::vector<size_t> order_in_turn, order_at_once;
    const auto r1 = run(false, in_turn, order_in_turn);
    const auto r2 = run(true, at_once, order_at_once);
    ASSERT_EQ(order_at_once.size(), f.fixed.size());
    EXPECT_EQ(order_in_turn.front(), 5u);
    EXPECT_EQ(order_at_once.front(), 5u);  // the viewer's frame before the others start
    std::sort(order_at_once.begin(), order_at_once.end());
    for (size_t k = 0; k < order_at_once.size(); ++k) EXPECT_EQ(order_at_once[k], k);
    for (size_t k = 0; k < f.fixed.size(); ++k) {
      ASSERT_TRUE(r1[k].success && r2[k].success) << k;
      EXPECT_EQ(r1[k].residual, r2[k].residual) << k;
      for (size_t v = 0; v < n; ++v) ASSERT_EQ(in_turn[k][v], at_once[k][v]) << "frame " << k << " vertex " << v;
    }
  }
}

// A block whose changing set is too large is split (down to single frames, which need no
// trailing set), and the frames still come out as each one's own solution.
TEST(DirichletFrames, SplitsABlockWhoseChangingSetIsTooLarge) {
  const Mesh& mesh = test::icosphere_mesh();
  const TangentBundle bundle(mesh);
  const ConnectionLaplacian l = connection_laplacian(bundle);
  const Frames f = moving_discs(mesh, l, 4, 0.5);
  const auto n = static_cast<size_t>(mesh.num_vertices());
  std::vector<std::vector<cplx>> out(f.fixed.size(), std::vector<cplx>(n));
  std::vector<std::span<cplx>> spans(out.begin(), out.end());
  DirichletFramesOptions o;
  o.max_trailing_fraction = 0.0;
  DirichletFrames::Statistics stats;
  const std::vector<DirichletProblem> problems = f.problems();
  const std::vector<SolveReport> reports = DirichletFrames(l, o).solve(problems, spans, &stats);
  EXPECT_EQ(stats.blocks, 4);
  EXPECT_EQ(stats.largest_trailing, 0);
  DirichletSolver alone(l);
  for (size_t k = 0; k < f.fixed.size(); ++k) {
    ASSERT_TRUE(reports[k].success) << reports[k].failure;
    std::vector<cplx> expected(n);
    ASSERT_TRUE(alone.solve(f.fixed[k], f.values[k], expected, f.penalty[k]).success);
    for (size_t v = 0; v < n; ++v) EXPECT_LT(std::abs(out[k][v] - expected[v]), 1e-11) << k << " " << v;
  }
}

// Two grids side by side (flat connection: L singular on each), only the first ever
// constrained, and one frame without any constraint: the unconstrained component, and
// that frame, get zero, as with DirichletSolver.
TEST(DirichletFrames, ComponentsWithoutConstraintsGetZero) {
  const Mesh& grid = test::grid_mesh();
  std::vector<Vec3> p = grid.positions();
  std::vector<Face> faces = grid.faces();
  const int n0 = grid.num_vertices();
  for (const Vec3& x : grid.positions()) p.push_back(x + Vec3(10, 0, 0));
  for (const Face& t : grid.faces()) faces.push_back({t[0] + n0, t[1] + n0, t[2] + n0});
  const Mesh two(std::move(p), std::move(faces), "two grids");
  const TangentBundle bundle(two);
  const ConnectionLaplacian l = connection_laplacian(bundle);
  const auto n = static_cast<size_t>(two.num_vertices());
  Frames f;
  for (int k = 0; k < 3; ++k) {
    std::vector<char> fixed(n, 0);
    std::vector<cplx> values(n, cplx(0, 0));
    for (int v = 0; v < n0; ++v)
      if (k < 2 && grid.is_boundary_vertex(v) && (k == 0 || grid.position(v).x() < 0)) {
        fixed[static_cast<size_t>(v)] = 1;
        values[static_cast<size_t>(v)] = cplx(0.5, -2.0);
      }
    f.fixed.push_back(fixed);
    f.values.push_back(values);
    f.penalty.emplace_back();
  }
  std::vector<std::vector<cplx>> out(3, std::vector<cplx>(n, cplx(5, 5)));
  std::vector<std::span<cplx>> spans(out.begin(), out.end());
  const std::vector<DirichletProblem> problems = f.problems();
  const std::vector<SolveReport> reports = DirichletFrames(l).solve(problems, spans);
  for (int k = 0; k < 3; ++k) {
    ASSERT_TRUE(reports[static_cast<size_t>(k)].success) << reports[static_cast<size_t>(k)].failure;
    for (size_t v = 0; v < n; ++v) {
      const cplx expected = k < 2 && v < static_cast<size_t>(n0) ? cplx(0.5, -2.0) : cplx(0, 0);
      EXPECT_LT(std::abs(out[static_cast<size_t>(k)][v] - expected), 1e-12) << k << " " << v;
    }
  }
}

}  // namespace
}  // namespace tvf
