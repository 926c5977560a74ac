// Region re-solves of one frame (region_solve.h): a cancelled pair leaves no singular face,
// every value outside the region is kept bit for bit, and the fill inside obeys the
// maximum principle.
#include "tvf/analysis/singularities.h"
#include "tvf/scene/design_space.h"
#include "tvf/edit/region_solve.h"

#include <gtest/gtest.h>

#include <algorithm>

namespace tvf {
namespace {

// V = f·g (complex product, so zeros and indices add): f = (x² − a²) + i(y − 0.013) has a
// source at x = a and a saddle at x = −a (the saddle–source normal form of eq. 1 before
// the cancellation); g = i·((x + 0.613) + i(y − 0.687)) a centre far from them (positions
// off the grid lines).
std::vector<cplx> pair_and_centre(const Mesh& mesh, double a) {
  std::vector<cplx> z(static_cast<size_t>(mesh.num_vertices()));
  for (int v = 0; v < mesh.num_vertices(); ++v) {
    const Vec3& p = mesh.position(v);
    const cplx f(p.x() * p.x() - a * a, p.y() - 0.013);
    const cplx g = cplx(0, 1) * cplx(p.x() + 0.613, p.y() - 0.687);
    z[static_cast<size_t>(v)] = f * g;
  }
  return z;
}

TEST(RegionSolve, CancellingAPairKeepsEverythingOutsideTheRegion) {
  GridSpec g;
  g.nx = g.ny = 41;
  const DesignSpace space(make_grid(g));
  const std::vector<cplx> z = pair_and_centre(space.mesh(), 0.213);
  const auto before = find_singularities(space.bundle(), z);
  ASSERT_EQ(before.size(), 3u);
  const auto source = std::find_if(before.begin(), before.end(), [](const Singularity& s) {
    return s.index == 1 && s.position.x() > 0;
  });
  const auto saddle = std::find_if(before.begin(), before.end(), [](const Singularity& s) { return s.index == -1; });
  ASSERT_NE(source, before.end());
  ASSERT_NE(saddle, before.end());

  const ConnectionLaplacian L = connection_laplacian(space.bundle());
  RegionSolver solver(space.bundle(), L);
  const RegionResult r = solver.cancel(z, source->where.face, saddle->where.face);
  ASSERT_TRUE(r.success);
  // Only the centre is left, exactly where it was.
  const auto after = find_singularities(space.bundle(), r.values);
  ASSERT_EQ(after.size(), 1u);
  EXPECT_EQ(after[0].where.face, std::find_if(before.begin(), before.end(), [](const Singularity& s) {
                                   return s.position.x() < -0.4;
                                 })->where.face);
  // Outside the interior, the values are the input's, bit for bit. Inside, a fill obeys the
  // maximum principle: no length above the largest on the region's boundary (the vertices
  // next to the interior). Both fills of region_solve do (the harmonic fill of z, whose
  // length is subharmonic, and the fill of directions scaled by the harmonic fill of |z|).
  double boundary_max = 0;
  int interior = 0;
  for (size_t v = 0; v < z.size(); ++v) {
    if (!r.interior[v]) {
      EXPECT_EQ(r.values[v], z[v]);
      for (Eigen::SparseMatrix<cplx>::InnerIterator it(L.matrix, static_cast<Eigen::Index>(v)); it; ++it)
        if (r.interior[static_cast<size_t>(it.row())]) boundary_max = std::max(boundary_max, std::abs(z[v]));
    } else {
      ++interior;
    }
  }
  for (size_t v = 0; v < z.size(); ++v) {
    if (r.interior[v]) {
      EXPECT_LE(std::abs(r.values[v]), boundary_max * (1 + 1e-12)) << v;
    }
  }
  EXPECT_GT(interior, 0);
  // The region holds the pair and not the centre.
  EXPECT_TRUE(std::binary_search(r.faces.begin(), r.faces.end(), source->where.face));
  EXPECT_TRUE(std::binary_search(r.faces.begin(), r.faces.end(), saddle->where.face));
  EXPECT_FALSE(std::binary_search(r.faces.begin(), r.faces.end(), after[0].where.face));
}

TEST(RegionSolve, PastingANeighbourhoodPlacesItsSingularity) {
  // Paste the source's neighbourhood (values of the field around (0.2, 0)) at (0.2, −0.5)
  // after cancelling the pair: the region around the pasted disc gets exactly the pasted
  // singularity and its partner is created nowhere else (the disc holds the index, the
  // fill around it none).
  GridSpec g;
  g.nx = g.ny = 41;
  const DesignSpace space(make_grid(g));
  const Mesh& mesh = space.mesh();
  const ConnectionLaplacian L = connection_laplacian(space.bundle());
  RegionSolver solver(space.bundle(), L);
  // A uniform field with a pair pasted: the pinned disc holds the pair of eq. 1 (index sum 0).
  std::vector<cplx> z(static_cast<size_t>(mesh.num_vertices()), cplx(1, 0));
  std::vector<int> pinned;
  std::vector<cplx> values;
  for (int v = 0; v < mesh.num_vertices(); ++v) {
    const Vec3& p = mesh.position(v);
    const double x = p.x(), y = p.y() + 0.5;
    if (std::hypot(x, y) > 0.35) continue;
    pinned.push_back(v);
    values.emplace_back(x * x - 0.04, y - 0.01);
  }
  const RegionResult r = solver.paste(z, pinned, values);
  ASSERT_TRUE(r.success);
  const auto after = find_singularities(space.bundle(), r.values);
  ASSERT_EQ(after.size(), 2u);
  for (const auto& s : after) EXPECT_LT((s.position - Vec3(0, -0.5, 0)).norm(), 0.3);
  EXPECT_EQ(after[0].index + after[1].index, 0);
}

}  // namespace
}  // namespace tvf
