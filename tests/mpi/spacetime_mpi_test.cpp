// The distributed space-time solve (solve/petsc_spacetime.cpp) against the one-process
// solver, run by ctest under `mpirun -n 2` (tests/CMakeLists.txt): every rank builds the
// same problem, solves it once with the PETSc back end (all ranks together) and once in
// its own process, and compares.
#include "solve/petsc_spacetime.h"
#include "support/test_meshes.h"
#include "tvf/api/design.h"
#include "tvf/scene/scene_json.h"
#include "tvf/mesh/grid.h"
#include "tvf/mesh/tangent_bundle.h"
#include "tvf/solve/distributed.h"
#include "tvf/solve/spacetime.h"

#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <random>
#include <set>
#include <vector>

namespace tvf {
namespace {

// A design problem on a mesh: a key frame of seeded random vectors at frame 0, and a
// moving element, a disk of `radius` around a point that travels from `from` to `to` over
// the frames, holding the unit vector (1, 0) of its vertices' bases at every frame.
struct Problem {
  std::vector<char> fixed;
  std::vector<cplx> values;
};

Problem moving_element(const Mesh& mesh, int frames, Vec3 from, Vec3 to, double radius, bool keyframe) {
  const auto n = static_cast<size_t>(mesh.num_vertices());
  const auto nf = static_cast<size_t>(frames);
  Problem p{std::vector<char>(n * nf, 0), std::vector<cplx>(n * nf, cplx(0, 0))};
  std::mt19937 rng(7);
  std::uniform_real_distribution<double> u(-1, 1);
  if (keyframe)
    for (size_t i = 0; i < n; ++i) {
      p.fixed[i] = 1;
      p.values[i] = cplx(u(rng), u(rng));
    }
  for (size_t j = keyframe ? 1 : 0; j < nf; ++j) {
    const double s = static_cast<double>(j) / static_cast<double>(nf - 1);
    const Vec3 c = (1 - s) * from + s * to;
    for (size_t i = 0; i < n; ++i)
      if ((mesh.position(static_cast<int>(i)) - c).norm() < radius) {
        p.fixed[j * n + i] = 1;
        p.values[j * n + i] = cplx(1, 0);
      }
  }
  return p;
}

// The owners the back end's partition gives every vertex (collective).
std::vector<int> owners(const ConnectionLaplacian& laplacian) {
  return petsc_partition(laplacian).owner;
}

struct Comparison {
  SolveReport one, all;
  double largest = 0, difference = 0;  // max |z_one|, max |z_all − z_one|
  bool fixed_kept = true;              // fixed entries hold their values exactly
};

// Both solves with the line solves alone (coarse_modes = 0: the same algorithm, so the same
// iterations but for rounding) or, two_level, with the default two-level preconditioner
// (low temporal modes, the local solve on the cut lines, the line solves; the ranks solve
// the modes' spatial systems by GAMG, one process by Jacobi-PCG).
Comparison compare(const ConnectionLaplacian& laplacian, int frames, const Problem& p, bool two_level = false,
                   SpaceTimeMethod one_method = SpaceTimeMethod::cg) {
  const SpaceTimeSolver solver(laplacian, frames, 30.0);
  std::vector<cplx> one(p.values.size()), all(p.values.size());
  solver.interpolate_in_time(p.fixed, p.values, one);
  all = one;
  SpaceTimeOptions local;
  local.parallel = false;
  // One process's CG by default, the algorithm the ranks run (`automatic` would take the
  // modes with local solves where a key frame and a moving element meet).
  local.method = one_method;
  if (!two_level) local.coarse_modes = 0;
  SpaceTimeOptions shared = local;
  shared.distributed = true;
  Comparison c;
  c.one = solver.solve(p.fixed, p.values, one, local);
  c.all = solver.solve(p.fixed, p.values, all, shared);
  for (size_t k = 0; k < one.size(); ++k) {
    c.largest = std::max(c.largest, std::abs(one[k]));
    c.difference = std::max(c.difference, std::abs(all[k] - one[k]));
    if (p.fixed[k] && (all[k] != p.values[k] || one[k] != p.values[k])) c.fixed_kept = false;
  }
  return c;
}

// Checks common to every case: both solves met the tolerance, the distributed one on 2
// ranks, with the one process's iterations (same CG, same preconditioner: only the order
// of additions differs), and the fields agree to the tolerance.
void expect_same_field(const Comparison& c) {
  if (distributed_rank() == 0)
    std::printf("  one process: %d iterations, residual %.2e; 2 ranks: %d iterations, residual %.2e; "
                "max |difference| %.2e of max |z| %.3f\n",
                c.one.iterations, c.one.residual, c.all.iterations, c.all.residual, c.difference, c.largest);
  ASSERT_TRUE(c.one.success) << c.one.method;
  ASSERT_TRUE(c.all.success) << c.all.method << " residual " << c.all.residual;
  EXPECT_NE(c.all.method.find("PETSc CG"), std::string::npos) << c.all.method;
  EXPECT_NE(c.all.method.find("2 ranks"), std::string::npos) << c.all.method;
  EXPECT_LE(c.all.residual, 1e-10);
  EXPECT_GT(c.largest, 0.1);
  EXPECT_LE(c.difference, 1e-8 * c.largest) << "largest " << c.largest;
  EXPECT_TRUE(c.fixed_kept);
}

TEST(DistributedSpaceTime, RunsOnTwoRanks) {
  EXPECT_TRUE(distributed_built());
  EXPECT_EQ(distributed_ranks(), 2);
}

TEST(DistributedSpaceTime, GridWithAnElementCrossingThePartitionBoundary) {
  const Mesh mesh = make_grid(GridSpec{41, 41, {-1, -1}, {1, 1}});
  const TangentBundle bundle(mesh);
  const ConnectionLaplacian laplacian = connection_laplacian(bundle);
  const int frames = 24;
  const Problem p = moving_element(mesh, frames, Vec3(-0.8, -0.7, 0), Vec3(0.8, 0.7, 0), 0.15, true);
  // The element's vertices lie on both sides of the partition.
  const std::vector<int> owner = owners(laplacian);
  std::set<int> touched;
  const auto n = static_cast<size_t>(mesh.num_vertices());
  for (size_t k = n; k < p.fixed.size(); ++k)
    if (p.fixed[k]) touched.insert(owner[k % n]);
  EXPECT_EQ(touched.size(), 2u);
  const Comparison c = compare(laplacian, frames, p);
  expect_same_field(c);
  // The same algorithm: the iteration counts agree but for rounding.
  EXPECT_NEAR(c.all.iterations, c.one.iterations, 2) << c.one.method;
}

// The generator hands the solve its first guess as the fixed values too (z holds them at
// every fixed entry; the separate copy is freed under mpirun): the same field as with the
// values apart (to rounding: PT-Scotch's partition, and so the order of additions, may
// differ between two calls), the same iterations, and the fixed entries kept exactly.
TEST(DistributedSpaceTime, FixedValuesReadFromTheFirstGuess) {
  const Mesh mesh = make_grid(GridSpec{31, 31, {-1, -1}, {1, 1}});
  const TangentBundle bundle(mesh);
  const ConnectionLaplacian laplacian = connection_laplacian(bundle);
  const int frames = 16;
  const Problem p = moving_element(mesh, frames, Vec3(-0.8, 0.7, 0), Vec3(0.8, -0.7, 0), 0.2, true);
  const SpaceTimeSolver solver(laplacian, frames, 30.0);
  SpaceTimeOptions shared;
  shared.distributed = true;
  std::vector<cplx> apart(p.values.size());
  solver.interpolate_in_time(p.fixed, p.values, apart);
  std::vector<cplx> aliased = apart;
  const SolveReport r1 = solver.solve(p.fixed, p.values, apart, shared);
  const SolveReport r2 = solver.solve(p.fixed, aliased, aliased, shared);
  ASSERT_TRUE(r1.success) << r1.method;
  ASSERT_TRUE(r2.success) << r2.method;
  if (distributed_rank() == 0) std::printf("  %s\n  %s\n", r1.method.c_str(), r2.method.c_str());
  EXPECT_GT(r1.iterations, 5);
  EXPECT_NEAR(r1.iterations, r2.iterations, 1);
  size_t moved = 0;
  double most = 0, largest = 0;
  for (size_t k = 0; k < apart.size(); ++k) {
    most = std::max(most, std::abs(apart[k] - aliased[k]));
    largest = std::max(largest, std::abs(apart[k]));
    moved += p.fixed[k] && aliased[k] != p.values[k];
  }
  EXPECT_GT(largest, 0.5);
  EXPECT_LE(most, 1e-8 * largest);
  EXPECT_EQ(moved, 0u);
}

TEST(DistributedSpaceTime, SphereWithAVortexRoundTheEquator) {
  const Mesh& mesh = test::icosphere_mesh();
  const TangentBundle bundle(mesh);
  const ConnectionLaplacian laplacian = connection_laplacian(bundle);
  const int frames = 20;
  // No key frame: the element alone (its lines split by the fixed entries, the rest open).
  const Problem p = moving_element(mesh, frames, Vec3(1, 0, 0), Vec3(-1, 0.05, 0), 0.3, false);
  const std::vector<int> owner = owners(laplacian);
  std::set<int> touched;
  const auto n = static_cast<size_t>(mesh.num_vertices());
  for (size_t k = 0; k < p.fixed.size(); ++k)
    if (p.fixed[k]) touched.insert(owner[k % n]);
  EXPECT_EQ(touched.size(), 2u);
  const Comparison c = compare(laplacian, frames, p);
  expect_same_field(c);
  EXPECT_NEAR(c.all.iterations, c.one.iterations, 2) << c.one.method;
}

TEST(DistributedSpaceTime, KeyFramesOnlyMatchTheTemporalModes) {
  // Key frames at both ends: one process takes the temporal-mode method (direct in
  // time), the ranks CG; the same field to the tolerance.
  const Mesh mesh = make_grid(GridSpec{33, 25, {-1, -1}, {1, 0.5}});
  const TangentBundle bundle(mesh);
  const ConnectionLaplacian laplacian = connection_laplacian(bundle);
  const int frames = 16;
  const auto n = static_cast<size_t>(mesh.num_vertices());
  Problem p{std::vector<char>(n * frames, 0), std::vector<cplx>(n * frames, cplx(0, 0))};
  for (size_t i = 0; i < n; ++i) {
    const Vec3& x = mesh.position(static_cast<int>(i));
    p.fixed[i] = p.fixed[(frames - 1) * n + i] = 1;
    p.values[i] = cplx(1, x.y());
    p.values[(frames - 1) * n + i] = cplx(-x.y(), x.x());
  }
  const Comparison c = compare(laplacian, frames, p, false, SpaceTimeMethod::automatic);
  EXPECT_NE(c.one.method.find("temporal eigenmodes"), std::string::npos) << c.one.method;
  expect_same_field(c);
}

// The default two-level preconditioner on the ranks (the modes' spatial systems by PETSc's
// GAMG, the local solve across the partition) against one process's (Jacobi-PCG for the
// modes): the same field to the tolerance, at most a few iterations more than one process
// (the coarse solves are inexact differently: GAMG's often closer, and then fewer), far
// fewer than with the line solves alone.
TEST(DistributedSpaceTime, TwoLevelOnAGridWithAnElementCrossingThePartition) {
  const Mesh mesh = make_grid(GridSpec{41, 41, {-1, -1}, {1, 1}});
  const TangentBundle bundle(mesh);
  const ConnectionLaplacian laplacian = connection_laplacian(bundle);
  const int frames = 24;
  const Problem p = moving_element(mesh, frames, Vec3(-0.8, -0.7, 0), Vec3(0.8, 0.7, 0), 0.15, true);
  const Comparison lines = compare(laplacian, frames, p);
  const Comparison c = compare(laplacian, frames, p, true);
  expect_same_field(c);
  EXPECT_NE(c.all.method.find("coarse correction (gamg on their block-diagonal"), std::string::npos) << c.all.method;
  EXPECT_NE(c.all.method.find("local solve"), std::string::npos) << c.all.method;
  EXPECT_NE(c.one.method.find("local solve"), std::string::npos) << c.one.method;
  EXPECT_LE(c.all.iterations, c.one.iterations + 3) << c.one.method;
  EXPECT_LT(2 * c.all.iterations, lines.all.iterations) << lines.all.method;
}

TEST(DistributedSpaceTime, TwoLevelOnASphereWithoutKeyFrames) {
  const Mesh& mesh = test::icosphere_mesh();
  const TangentBundle bundle(mesh);
  const ConnectionLaplacian laplacian = connection_laplacian(bundle);
  const int frames = 20;
  const Problem p = moving_element(mesh, frames, Vec3(1, 0, 0), Vec3(-1, 0.05, 0), 0.3, false);
  const Comparison lines = compare(laplacian, frames, p);
  const Comparison c = compare(laplacian, frames, p, true);
  expect_same_field(c);
  EXPECT_NE(c.all.method.find("coarse correction (gamg on their block-diagonal"), std::string::npos) << c.all.method;
  EXPECT_LE(c.all.iterations, c.one.iterations + 3) << c.one.method;
  EXPECT_LT(2 * c.all.iterations, lines.all.iterations) << lines.all.method;
}

TEST(DistributedSpaceTime, TwoLevelWithKeyFramesOnly) {
  // No moving constraint: the coarse correction and the line solves, no local solve.
  const Mesh mesh = make_grid(GridSpec{33, 25, {-1, -1}, {1, 0.5}});
  const TangentBundle bundle(mesh);
  const ConnectionLaplacian laplacian = connection_laplacian(bundle);
  const int frames = 16;
  const auto n = static_cast<size_t>(mesh.num_vertices());
  Problem p{std::vector<char>(n * frames, 0), std::vector<cplx>(n * frames, cplx(0, 0))};
  for (size_t i = 0; i < n; ++i) {
    const Vec3& x = mesh.position(static_cast<int>(i));
    p.fixed[i] = p.fixed[(frames - 1) * n + i] = 1;
    p.values[i] = cplx(1, x.y());
    p.values[(frames - 1) * n + i] = cplx(-x.y(), x.x());
  }
  const Comparison lines = compare(laplacian, frames, p);
  const Comparison c = compare(laplacian, frames, p, true);
  expect_same_field(c);
  EXPECT_NE(c.all.method.find("coarse correction"), std::string::npos) << c.all.method;
  EXPECT_EQ(c.all.method.find("local solve"), std::string::npos) << c.all.method;
  EXPECT_LT(2 * c.all.iterations, lines.all.iterations) << lines.all.method;
}

// What the spacetime generator runs under mpirun (design/generate.cpp): no rank holds the
// whole problem. The partition first; each frame evaluated whole by one rank and sent out
// in shares (petsc_scatter_frame); the first guess on each rank's own lines; the solve on
// the shares; the result gathered on rank 0 alone; each rank's share kept for its VTK
// pieces and read back at any vertices (distributed_share_values), also after rank 0
// changed the field (distributed_refresh_share).
TEST(DistributedSpaceTime, SharesOfTheProblemAndOfTheResult) {
  const Mesh mesh = make_grid(GridSpec{31, 31, {-1, -1}, {1, 1}});
  const TangentBundle bundle(mesh);
  const ConnectionLaplacian laplacian = connection_laplacian(bundle);
  const int frames = 14;
  const auto n = static_cast<size_t>(mesh.num_vertices());
  const auto nf = static_cast<size_t>(frames);
  const Problem p = moving_element(mesh, frames, Vec3(-0.8, -0.7, 0), Vec3(0.8, 0.7, 0), 0.2, true);
  VertexShares shares = petsc_vertex_shares(laplacian);
  ASSERT_EQ(shares.ranks, 2);
  ASSERT_EQ(shares.owner.size(), n);
  const size_t nl = shares.owned.size();
  EXPECT_GT(nl, n / 4);
  EXPECT_LT(nl, 3 * n / 4);
  // Frame j evaluated by rank j mod 2 (here: read from the replicated problem there only).
  std::vector<char> fixed(nl * nf, 0);
  std::vector<cplx> z(nl * nf);
  for (size_t j = 0; j < nf; ++j) {
    const int root = static_cast<int>(j % 2);
    const bool mine = root == shares.rank;
    petsc_scatter_frame(shares, root,
                        mine ? std::span<const char>(p.fixed.data() + j * n, n) : std::span<const char>(),
                        mine ? std::span<const cplx>(p.values.data() + j * n, n) : std::span<const cplx>(),
                        std::span<char>(fixed.data() + j * nl, nl), std::span<cplx>(z.data() + j * nl, nl));
  }
  // The shares are the replicated arrays' entries, and each rank's first guess on its lines
  // is the replicated first guess's, exactly.
  const SpaceTimeSolver solver(laplacian, frames, 30.0);
  std::vector<cplx> guess(n * nf);
  solver.interpolate_in_time(p.fixed, p.values, guess);
  interpolate_lines_in_time(fixed, z, z, nl, nf);
  size_t wrong = 0;
  for (size_t j = 0; j < nf; ++j)
    for (size_t i = 0; i < nl; ++i) {
      const size_t at = j * n + static_cast<size_t>(shares.owned[i]);
      wrong += fixed[j * nl + i] != p.fixed[at] || z[j * nl + i] != guess[at];
    }
  EXPECT_EQ(wrong, 0u);

  SpaceTimeOptions options;
  options.distributed = true;
  const SolveReport r = petsc_spacetime_solve_shares(laplacian, shares, frames, 30.0, fixed, z, options);
  ASSERT_TRUE(r.success) << r.method;
  EXPECT_NE(r.method.find("2 ranks"), std::string::npos) << r.method;
  const bool root = shares.rank == 0;
  std::vector<cplx> field(root ? n * nf : 0);
  petsc_gather_to_root(shares, z, frames, field);
  // Rank 0's field is one process's to the tolerance, the fixed entries exactly.
  std::vector<cplx> one = guess;
  SpaceTimeOptions local;
  local.parallel = false;
  local.method = SpaceTimeMethod::cg;
  ASSERT_TRUE(solver.solve(p.fixed, p.values, one, local).success);
  if (root) {
    double largest = 0, difference = 0;
    size_t moved = 0;
    for (size_t k = 0; k < one.size(); ++k) {
      largest = std::max(largest, std::abs(one[k]));
      difference = std::max(difference, std::abs(field[k] - one[k]));
      moved += p.fixed[k] && field[k] != p.values[k];
    }
    EXPECT_GT(largest, 0.5);
    EXPECT_LE(difference, 1e-8 * largest);
    EXPECT_EQ(moved, 0u);
  }

  // The kept shares read back at every vertex (rank 0), at a few (rank 1): the gathered
  // field's values, the other rank's received.
  const std::vector<cplx> own = z;
  petsc_keep_share(shares, z, frames);
  ASSERT_TRUE(distributed_has_share());
  std::vector<int> points;
  if (root)
    for (size_t v = 0; v < n; ++v) points.push_back(static_cast<int>(v));
  else
    points = {0, static_cast<int>(n / 2), static_cast<int>(n - 1)};
  std::vector<cplx> read = distributed_share_values(points);
  ASSERT_EQ(read.size(), points.size() * nf);
  if (root) {
    EXPECT_TRUE(std::equal(read.begin(), read.end(), field.begin()));
  } else {
    for (size_t j = 0; j < nf; ++j)
      for (size_t q = 0; q < points.size(); ++q) {
        const auto v = static_cast<size_t>(points[q]);
        if (shares.owner[v] == shares.rank) {
          EXPECT_EQ(read[j * points.size() + q], own[j * nl + static_cast<size_t>(shares.local[v])]);
        }
        EXPECT_NEAR(std::abs(read[j * points.size() + q] - one[j * n + v]), 0, 1e-7);
      }
  }
  // Rank 0 changes its field; the shares follow.
  Field changed(TimeSampling{0, 1, frames}, root ? static_cast<int>(n) : 0);
  for (size_t k = 0; k < field.size(); ++k) changed.data()[k] = cplx(0, 1) * field[k] + cplx(static_cast<double>(k % 7), 0);
  distributed_refresh_share(changed);
  read = distributed_share_values(points);
  if (root) {
    EXPECT_TRUE(std::equal(read.begin(), read.end(), changed.data().begin()));
  } else {
    for (size_t j = 0; j < nf; ++j)
      for (size_t q = 0; q < points.size(); ++q) {
        const auto v = static_cast<size_t>(points[q]);
        const cplx expected = cplx(0, 1) * one[j * n + v] + cplx(static_cast<double>((j * n + v) % 7), 0);
        EXPECT_NEAR(std::abs(read[j * points.size() + q] - expected), 0, 1e-7);
      }
  }
}

// `tvf generate`'s path (a Design, as the CLI makes it): under mpirun the field comes back
// whole on rank 0 and empty on the others, which keep their shares; the shares read back
// at every vertex are rank 0's field.
TEST(DistributedSpaceTime, TheGeneratorGathersOnRankZeroAlone) {
  Design design(parse_scene(R"({"tvf": 1,
    "domain": {"grid": {"size": [25, 25], "min": [-1, -1], "max": [1, 1]}},
    "time": {"frames": 9, "range": [0, 1]},
    "generator": "spacetime",
    "elements": [{"kind": "singular", "type": "ccw_center", "path": [[-0.7, -0.6, 0], [0.7, 0.6, 1]]}],
    "keyframes": [{"t": 0, "elements": [{"kind": "singular", "type": "source", "at": [0, 0.5]}]}]})",
                            "gather test"));
  const Field& field = design.generate();
  const int n = design.space().mesh().num_vertices();
  EXPECT_NE(design.report().method.find("2 ranks"), std::string::npos) << design.report().method;
  ASSERT_EQ(field.num_vertices(), distributed_rank() == 0 ? n : 0);
  EXPECT_EQ(field.frames(), 9);
  ASSERT_TRUE(distributed_has_share());
  std::vector<int> all(static_cast<size_t>(n));
  for (int v = 0; v < n; ++v) all[static_cast<size_t>(v)] = v;
  const std::vector<cplx> read = distributed_share_values(all);
  if (distributed_rank() == 0) {
    EXPECT_TRUE(std::equal(read.begin(), read.end(), field.data().begin()));
  }
}

TEST(DistributedSpaceTime, NothingToSolveGivesZero) {
  const Mesh& mesh = test::grid_mesh();
  const TangentBundle bundle(mesh);
  const ConnectionLaplacian laplacian = connection_laplacian(bundle);
  const auto n = static_cast<size_t>(mesh.num_vertices());
  // A zero vector fixed at one vertex of the last frame: the minimiser is zero.
  std::vector<char> fixed(n * 3, 0);
  fixed.resize(n * 4, 1);
  std::fill(fixed.begin() + static_cast<std::ptrdiff_t>(n * 3 + 1), fixed.end(), char{0});
  const std::vector<cplx> values(n * 4, cplx(0, 0));
  std::vector<cplx> z(n * 4, cplx(2, 1));
  SpaceTimeOptions shared;
  shared.distributed = true;
  const SolveReport r = SpaceTimeSolver(laplacian, 4, 30.0).solve(fixed, values, z, shared);
  EXPECT_TRUE(r.success);
  EXPECT_EQ(*std::max_element(z.begin(), z.end(), [](cplx a, cplx b) { return std::abs(a) < std::abs(b); }),
            cplx(0, 0));
}

}  // namespace
}  // namespace tvf

int main(int argc, char** argv) {
  const tvf::DistributedSession session;
  ::testing::InitGoogleTest(&argc, argv);
  // Rank 0 reports; the others' failures still fail the run (their exit status).
  if (tvf::distributed_rank() != 0) {
    auto& listeners = ::testing::UnitTest::GetInstance()->listeners();
    delete listeners.Release(listeners.default_result_printer());
  }
  return RUN_ALL_TESTS();
}
