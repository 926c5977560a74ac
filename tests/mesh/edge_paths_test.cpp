#include "tvf/mesh/edge_paths.h"

#include "tvf/mesh/grid.h"

#include <gtest/gtest.h>

#include <cmath>
#include <limits>
#include <vector>

namespace tvf {
namespace {

// A 5 × 2 grid over [0, 4] × [0, 1]: unit edges along the rows, diagonals √2.
Mesh strip() { return make_grid(GridSpec{5, 2, Vec2(0, 0), Vec2(4, 1)}); }

int vertex_at(const Mesh& mesh, double x, double y) {
  for (int v = 0; v < mesh.num_vertices(); ++v)
    if ((mesh.position(v) - Vec3(x, y, 0)).norm() < 1e-12) return v;
  ADD_FAILURE() << "no vertex at (" << x << ", " << y << ")";
  return 0;
}

// Along the boundary both ways: from the bottom row's right end to its left end is 4 edge
// lengths along the bottom, though from each of those vertices the edge to its left
// neighbour is no outgoing halfedge's (the face above runs it left to right). Walking the
// heads of outgoing halfedges alone goes round by the top row and the diagonals (5.41).
TEST(EdgePaths, BoundaryEdgesAreWalkedBothWays) {
  const Mesh mesh = strip();
  const EdgePathSeed seed{vertex_at(mesh, 4, 0), 0.0};
  const std::vector<double> d = edge_path_distances(mesh, {&seed, 1}, 10.0);
  for (int i = 0; i <= 4; ++i) EXPECT_DOUBLE_EQ(d[static_cast<size_t>(vertex_at(mesh, i, 0))], 4 - i) << i;
  for (int i = 0; i <= 4; ++i) EXPECT_DOUBLE_EQ(d[static_cast<size_t>(vertex_at(mesh, i, 1))], 5 - i) << i;
}

// Vertices farther than the radius are not reached; every reached vertex is settled once,
// in order of distance, with its final distance; seeds start at their own distance, the
// smaller of two for one vertex.
TEST(EdgePaths, TheWalkStopsAtTheRadiusAndSettlesInOrder) {
  const Mesh mesh = strip();
  const std::vector<EdgePathSeed> seeds{{vertex_at(mesh, 0, 0), 0.7}, {vertex_at(mesh, 0, 0), 0.5}};
  std::vector<int> settled;
  std::vector<double> at;
  const std::vector<double> d = edge_path_distances(mesh, seeds, 2.6, [&](int v, double dv) {
    settled.push_back(v);
    at.push_back(dv);
    return true;
  });
  EXPECT_DOUBLE_EQ(d[static_cast<size_t>(vertex_at(mesh, 0, 0))], 0.5);
  EXPECT_DOUBLE_EQ(d[static_cast<size_t>(vertex_at(mesh, 2, 0))], 2.5);
  EXPECT_EQ(d[static_cast<size_t>(vertex_at(mesh, 3, 0))], std::numeric_limits<double>::infinity());
  size_t finite = 0;
  for (const double x : d) finite += std::isfinite(x) ? 1 : 0;
  ASSERT_EQ(settled.size(), finite);
  for (size_t k = 0; k < settled.size(); ++k) {
    EXPECT_EQ(at[k], d[static_cast<size_t>(settled[k])]);
    if (k > 0) {
      EXPECT_LE(at[k - 1], at[k]);
    }
  }
}

// `settle` returning false stops the walk; a seed beyond the radius keeps its distance but
// is not walked on from.
TEST(EdgePaths, SettleStopsTheWalkAndFarSeedsStayPut) {
  const Mesh mesh = strip();
  const EdgePathSeed seed{vertex_at(mesh, 2, 0), 0.0};
  int calls = 0;
  edge_path_distances(mesh, {&seed, 1}, 10.0, [&](int, double) { return ++calls < 3; });
  EXPECT_EQ(calls, 3);
  const EdgePathSeed far{vertex_at(mesh, 2, 0), 3.0};
  const std::vector<double> d = edge_path_distances(mesh, {&far, 1}, 2.0);
  for (int v = 0; v < mesh.num_vertices(); ++v)
    EXPECT_EQ(d[static_cast<size_t>(v)], v == far.vertex ? 3.0 : std::numeric_limits<double>::infinity()) << v;
}

}  // namespace
}  // namespace tvf
