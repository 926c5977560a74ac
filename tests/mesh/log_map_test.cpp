#include "tvf/mesh/log_map.h"
#include "tvf/mesh/heat_distance.h"

#include "support/test_meshes.h"
#include "tvf/mesh/grid.h"
#include "tvf/mesh/primitives.h"

#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <cstdio>

namespace tvf {
namespace {

// Exact log map and parallel transport on a sphere of radius 1 around p, for the frame
// (e1, e2) at p: returns log_p(x) in that frame and the transported e1 at x (world).
struct SphereTruth {
  cplx log;
  Vec3 e1_at_x;
};
SphereTruth sphere_truth(const Vec3& p, const Vec3& e1, const Vec3& e2, const Vec3& x) {
  const double r = std::acos(std::clamp(p.dot(x), -1.0, 1.0));
  const Vec3 u = (x - p.dot(x) * p).normalized();  // initial direction of the geodesic
  const Vec3 w = p.cross(u);                       // normal of the great circle
  const Vec3 u_at_x = -std::sin(r) * p + std::cos(r) * u;
  const cplx dir(u.dot(e1), u.dot(e2));
  return {r * dir / std::abs(dir), e1.dot(u) * u_at_x + e1.dot(w) * w};
}

TEST(LogMap, ExactOnPlanarDomains) {
  const Mesh grid = make_grid(GridSpec{21, 11, {-1, -0.5}, {3, 1.5}});
  const TangentBundle bundle(grid);
  const LogMap log(bundle);
  EXPECT_TRUE(log.exact());
  SurfacePoint p{7, Vec3(0.2, 0.3, 0.5)};
  const Face& f = grid.face(p.face);
  const Vec3 x = 0.2 * grid.position(f[0]) + 0.3 * grid.position(f[1]) + 0.5 * grid.position(f[2]);
  LocalChart chart;
  log.compute(p, chart);
  for (int v = 0; v < grid.num_vertices(); ++v) {
    const Vec3 d = grid.position(v) - x;
    EXPECT_EQ(chart.coords[static_cast<size_t>(v)], cplx(d.x(), d.y()));
    EXPECT_EQ(chart.frame[static_cast<size_t>(v)], cplx(1, 0));
  }
}

// The vector heat log map on a sphere against the closed form, for a point at a vertex
// and a point inside a face, within the radius an element's falloff gives weight to.
TEST(LogMap, MatchesGeodesicPolarCoordinatesOnTheSphere) {
  const Mesh sphere = make_icosphere(5);
  const TangentBundle bundle(sphere);
  const LogMap log(bundle);
  EXPECT_FALSE(log.exact());
  for (const SurfacePoint& p : {SurfacePoint{100, Vec3(1, 0, 0)}, SurfacePoint{2345, Vec3(0.2, 0.5, 0.3)}}) {
    const Face& f = sphere.face(p.face);
    const Vec3 x = p.bary[0] * sphere.position(f[0]) + p.bary[1] * sphere.position(f[1]) +
                   p.bary[2] * sphere.position(f[2]);
    const Vec3 pn = x.normalized();
    LocalChart chart;
    log.compute(p, chart);
    double max_dist_err = 0, max_angle_err = 0, max_frame_err = 0;
    int checked = 0;
    for (int v = 0; v < sphere.num_vertices(); ++v) {
      const Vec3& xv = sphere.position(v);
      const double r = std::acos(std::clamp(pn.dot(xv), -1.0, 1.0));
      if (r < 0.05 || r > 1.5) continue;  // away from the source point and the cut locus
      const SphereTruth truth = sphere_truth(pn, bundle.face_e1(p.face), bundle.face_e2(p.face), xv);
      const cplx got = chart.coords[static_cast<size_t>(v)];
      // Within a few edges of p the direction error is O(h / r): a looser bound there.
      const double near = r < 0.15 ? 3.0 : 1.0;
      max_dist_err = std::max(max_dist_err, std::abs(std::abs(got) - r) / r / near);
      max_angle_err = std::max(max_angle_err, std::abs(std::arg(got / truth.log)) / near);
      const cplx fr_truth = normalized(bundle.world_to_vertex(v, truth.e1_at_x));
      max_frame_err = std::max(max_frame_err, std::abs(std::arg(chart.frame[static_cast<size_t>(v)] / fr_truth)));
      ++checked;
    }
    EXPECT_GT(checked, 1000);
    EXPECT_LT(max_dist_err, 0.03) << "relative distance error (×1/3 within 0.15 of p)";
    EXPECT_LT(max_angle_err, 0.05) << "direction error (radians, ×1/3 within 0.15 of p)";
    EXPECT_LT(max_frame_err, 0.03) << "transport error (radians)";
  }
}

TEST(LogMap, UnchangedByUniformScaling) {
  const Mesh& s = test::icosphere_mesh();
  std::vector<Vec3> pos = s.positions();
  for (auto& x : pos) x *= 1000.0;
  const Mesh big(pos, s.faces(), "scaled");
  const TangentBundle b1(s), b2(big);
  const LogMap l1(b1), l2(b2);
  const SurfacePoint p{42, Vec3(0.3, 0.3, 0.4)};
  LocalChart c1, c2;
  l1.compute(p, c1);
  l2.compute(p, c2);
  for (size_t v = 0; v < c1.coords.size(); ++v) {
    EXPECT_LT(std::abs(c2.coords[v] / 1000.0 - c1.coords[v]), 1e-9 * (1 + std::abs(c1.coords[v])));
    EXPECT_LT(std::abs(c2.frame[v] - c1.frame[v]), 1e-9);
  }
}

}  // namespace
}  // namespace tvf

namespace tvf {
namespace {

// The heat method's geodesic distance on the unit sphere is the great-circle distance
// acos(p·x) from the nearest source, within the discretization's error.
TEST(GeodesicDistance, GreatCircleDistanceOnTheSphere) {
  const Mesh sphere = make_icosphere(5, 1.0);
  const TangentBundle bundle(sphere);
  const HeatDistance map(bundle);
  const SurfacePoint a = closest_point(sphere, Vec3(0.3, -0.2, 0.9).normalized());
  const SurfacePoint b = closest_point(sphere, Vec3(-0.5, 0.6, -0.4).normalized());
  auto at = [&](const SurfacePoint& p) {
    const Face& f = sphere.face(p.face);
    return Vec3(p.bary[0] * sphere.position(f[0]) + p.bary[1] * sphere.position(f[1]) +
                p.bary[2] * sphere.position(f[2]));
  };
  for (const bool both : {false, true}) {
    std::vector<SurfacePoint> sources{a};
    if (both) sources.push_back(b);
    const std::vector<double> d = map.distance(sources);
    double worst = 0, mean = 0;
    for (int v = 0; v < sphere.num_vertices(); ++v) {
      const Vec3 x = sphere.position(v).normalized();
      double exact = std::acos(std::clamp(x.dot(at(a).normalized()), -1.0, 1.0));
      if (both) exact = std::min(exact, std::acos(std::clamp(x.dot(at(b).normalized()), -1.0, 1.0)));
      const double err = std::abs(d[static_cast<size_t>(v)] - exact);
      worst = std::max(worst, err);
      mean += err;
    }
    mean /= sphere.num_vertices();
    EXPECT_LT(mean, 0.01) << "sources " << sources.size();
    EXPECT_LT(worst, 0.04) << "sources " << sources.size();  // the antipode's cone tip, the cut locus' ridge
  }
}

TEST(GeodesicDistance, StraightLineOnAPlane) {
  const Mesh& grid = test::grid_mesh();
  const TangentBundle bundle(grid);
  const HeatDistance map(bundle);
  const SurfacePoint p = closest_point(grid, Vec3(0.2, 0.1, 0));
  const std::vector<double> d = map.distance(std::vector<SurfacePoint>{p});
  for (int v = 0; v < grid.num_vertices(); ++v)
    EXPECT_NEAR(d[static_cast<size_t>(v)], (grid.position(v) - Vec3(0.2, 0.1, 0)).norm(), 1e-9);
}

}  // namespace
}  // namespace tvf

namespace tvf {
namespace {

// compute_local against compute within the radius: every vertex the whole mesh's chart
// puts within `radius` of p is in the patch, and its coordinates and frame are the same
// to `tol` (coordinates relative to the radius). Returns the largest coordinate error.
double local_chart_error(const Mesh& mesh, const SurfacePoint& p, double radius, double tol) {
  const TangentBundle bundle(mesh);
  const LogMap log(bundle);
  LocalChart global, local;
  log.compute(p, global);
  log.compute_local(p, radius, local);
  double worst = 0, worst_frame = 0;
  int inside = 0, beyond = 0;
  for (size_t v = 0; v < global.coords.size(); ++v) {
    if (!std::isfinite(local.coords[v].real())) ++beyond;
    if (std::abs(global.coords[v]) > radius) continue;
    ++inside;
    EXPECT_TRUE(std::isfinite(local.coords[v].real())) << "vertex " << v;
    worst = std::max(worst, std::abs(local.coords[v] - global.coords[v]) / radius);
    worst_frame = std::max(worst_frame, std::abs(local.frame[v] - global.frame[v]));
  }
  EXPECT_GT(inside, 30);
  EXPECT_GT(beyond, mesh.num_vertices() / 2) << "the patch should be a small part of the mesh";
  EXPECT_LT(worst, tol);
  EXPECT_LT(worst_frame, tol);
  std::printf("local chart: %d vertices within r = %g, %d beyond the patch, error %.2e (coords / r), %.2e (frame)\n",
              inside, radius, beyond, worst, worst_frame);
  return worst;
}

// The patch's heat flows agree with the whole mesh's to rounding (the frames), its
// Poisson solve (Neumann on the patch's boundary) to ~1 % of the radius (measured
// 0.35 % on this sphere, 0.1–2 % on a torus, the hemisphere and the bunny): below the
// discretization error the sphere test above allows the whole mesh's chart against the
// closed form (3 % of the distance), and checked against the closed form here too.
TEST(LogMap, LocalChartMatchesTheGlobalChartOnTheSphere) {
  const Mesh sphere = make_icosphere(5);
  const double tol = 1e-2;
  local_chart_error(sphere, SurfacePoint{100, Vec3(1, 0, 0)}, 0.2, tol);
  local_chart_error(sphere, SurfacePoint{2345, Vec3(0.2, 0.5, 0.3)}, 0.2, tol);
  local_chart_error(sphere, SurfacePoint{777, Vec3(0.6, 0.1, 0.3)}, 0.12, tol);
  // Against the closed form, with the bounds of MatchesGeodesicPolarCoordinatesOnTheSphere.
  const TangentBundle bundle(sphere);
  const LogMap log(bundle);
  const SurfacePoint p{2345, Vec3(0.2, 0.5, 0.3)};
  const Face& f = sphere.face(p.face);
  const Vec3 pn = (p.bary[0] * sphere.position(f[0]) + p.bary[1] * sphere.position(f[1]) +
                   p.bary[2] * sphere.position(f[2])).normalized();
  LocalChart chart;
  log.compute_local(p, 0.3, chart);
  int checked = 0;
  for (int v = 0; v < sphere.num_vertices(); ++v) {
    const Vec3& xv = sphere.position(v);
    const double r = std::acos(std::clamp(pn.dot(xv), -1.0, 1.0));
    if (r < 0.05 || r > 0.3) continue;
    const SphereTruth truth = sphere_truth(pn, bundle.face_e1(p.face), bundle.face_e2(p.face), xv);
    const cplx got = chart.coords[static_cast<size_t>(v)];
    const double near = r < 0.15 ? 3.0 : 1.0;
    EXPECT_LT(std::abs(std::abs(got) - r) / r / near, 0.03) << "vertex " << v;
    EXPECT_LT(std::abs(std::arg(got / truth.log)) / near, 0.05) << "vertex " << v;
    const cplx fr_truth = normalized(bundle.world_to_vertex(v, truth.e1_at_x));
    EXPECT_LT(std::abs(std::arg(chart.frame[static_cast<size_t>(v)] / fr_truth)), 0.03) << "vertex " << v;
    ++checked;
  }
  EXPECT_GT(checked, 200);
}

TEST(LogMap, LocalChartMatchesTheGlobalChartOnATorusAndNearABoundary) {
  // On the torus the two differ by more (measured 2.8 % and 1.5 % of the radius): the
  // heat method's own error, which the patch's boundary and the whole mesh's far side
  // (the inner, negatively curved ring) pull differently; below the 3 % the whole mesh's
  // chart is allowed against the sphere's closed form.
  const Mesh torus = make_torus(192, 96);
  local_chart_error(torus, SurfacePoint{500, Vec3(0.3, 0.3, 0.4)}, 0.3, 3e-2);
  local_chart_error(torus, SurfacePoint{20000, Vec3(0.1, 0.8, 0.1)}, 0.2, 3e-2);
  // The upper half of a sphere: p two edge lengths from the mesh's boundary, where the
  // patch reaches the boundary.
  const Mesh full = make_icosphere(5);
  std::vector<int> remap(static_cast<size_t>(full.num_vertices()), -1);
  std::vector<Vec3> pos;
  std::vector<Face> faces;
  for (int f = 0; f < full.num_faces(); ++f) {
    const Face& t = full.face(f);
    if (full.position(t[0]).z() < -1e-9 || full.position(t[1]).z() < -1e-9 || full.position(t[2]).z() < -1e-9)
      continue;
    Face g;
    for (size_t k = 0; k < 3; ++k) {
      int& r = remap[static_cast<size_t>(t[k])];
      if (r < 0) {
        r = static_cast<int>(pos.size());
        pos.push_back(full.position(t[k]));
      }
      g[k] = r;
    }
    faces.push_back(g);
  }
  const Mesh half(pos, faces);
  int near_rim = -1;
  for (int f = 0; f < half.num_faces() && near_rim < 0; ++f) {
    const Face& t = half.face(f);
    const double z = (half.position(t[0]) + half.position(t[1]) + half.position(t[2])).z() / 3;
    if (z > 0.05 && z < 0.07) near_rim = f;
  }
  ASSERT_GE(near_rim, 0);
  local_chart_error(half, SurfacePoint{near_rim, Vec3(1.0 / 3, 1.0 / 3, 1.0 / 3)}, 0.2, 1e-2);
}

}  // namespace
}  // namespace tvf
namespace tvf {
namespace {

// Where local and global charts differ, the local one is no further from the closed form:
// on the sphere its distance error within the radius is at most the whole mesh's (+ 1e-3
// of the radius). Measured (h 0.076, 0.038, 0.019; r 0.2–0.5): global 0.63–1.13 %, local
// 0.56–1.11 % of r.
TEST(LogMap, LocalChartIsAsCloseToTheClosedFormAsTheGlobalChart) {
  for (int sub : {4, 5}) {
    const Mesh sphere = make_icosphere(sub);
    const TangentBundle bundle(sphere);
    const LogMap log(bundle);
    const SurfacePoint p{2345, Vec3(0.2, 0.5, 0.3)};
    const Face& f = sphere.face(p.face);
    const Vec3 pn = (p.bary[0] * sphere.position(f[0]) + p.bary[1] * sphere.position(f[1]) +
                     p.bary[2] * sphere.position(f[2])).normalized();
    LocalChart g;
    log.compute(p, g);
    for (double rad : {0.2, 0.3, 0.5}) {
      LocalChart l;
      log.compute_local(p, rad, l);
      double eg = 0, el = 0;
      for (int v = 0; v < sphere.num_vertices(); ++v) {
        const double r = std::acos(std::clamp(pn.dot(sphere.position(v)), -1.0, 1.0));
        if (r < 0.05 || r > rad) continue;
        eg = std::max(eg, std::abs(std::abs(g.coords[static_cast<size_t>(v)]) - r) / rad);
        el = std::max(el, std::abs(std::abs(l.coords[static_cast<size_t>(v)]) - r) / rad);
      }
      EXPECT_GT(eg, 1e-3) << "the discretization's error, which the local chart must not exceed";
      EXPECT_LE(el, eg + 1e-3) << "subdivisions " << sub << ", radius " << rad;
    }
  }
}

}  // namespace
}  // namespace tvf
