#include "tvf/integrate/streakline.h"

#include "support/test_fields.h"
#include "support/test_meshes.h"
#include "tvf/core/error.h"
#include "tvf/field/point_locator.h"
#include "tvf/mesh/grid.h"

#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <limits>
#include <numbers>

namespace tvf {
namespace {

using test::field_from;

TEST(Streakline, OfASteadyRotationIsTheCircleThroughTheSeed) {
  // A steady field's streakline is its streamline: here the circle of radius 0.5, and the
  // particle released at τ has turned by t1 − τ.
  const Mesh grid = make_grid(GridSpec{41, 41, {-1, -1}, {1, 1}});
  const TangentBundle bundle(grid);
  const Field field = field_from(bundle, TimeSampling{0, 4, 17}, [](const Vec3& x, double) { return Vec3(-x.y(), x.x(), 0); });
  StreaklineOptions o;
  o.t0 = 0.5;
  o.t1 = 3.5;
  o.release_spacing = 0.1;
  const Streakline s = trace_streakline(bundle, field, Vec3(0.5, 0, 0), o);
  EXPECT_DOUBLE_EQ(s.t, 3.5);
  EXPECT_EQ(s.released, 31);
  EXPECT_EQ(s.left, 0);
  ASSERT_EQ(s.points.size(), 31u);
  EXPECT_DOUBLE_EQ(s.points.front().release, 0.5);
  EXPECT_DOUBLE_EQ(s.points.back().release, 3.5);
  for (const StreakPoint& p : s.points) {
    const double angle = o.t1 - p.release;
    EXPECT_NEAR(p.position.norm(), 0.5, 1e-6);
    EXPECT_NEAR((p.position - Vec3(0.5 * std::cos(angle), 0.5 * std::sin(angle), 0)).norm(), 0.0, 1e-5) << p.release;
  }
}

TEST(Streakline, OfAUniformTranslationIsAnEvenlySpacedSegment) {
  const Mesh grid = make_grid(GridSpec{21, 21, {-1, -1}, {1, 1}});
  const TangentBundle bundle(grid);
  const Vec3 v(0.3, 0.1, 0);
  const Field field = field_from(bundle, TimeSampling{0, 2, 9}, [&](const Vec3&, double) { return v; });
  StreaklineOptions o;
  o.t0 = 0;
  o.t1 = 2;
  o.release_spacing = 0.125;
  const Vec3 seed(-0.5, -0.2, 0);
  const Streakline s = trace_streakline(bundle, field, seed, o);
  ASSERT_EQ(s.points.size(), 17u);
  for (size_t k = 0; k < s.points.size(); ++k) {
    const StreakPoint& p = s.points[k];
    EXPECT_NEAR((p.position - (seed + (o.t1 - p.release) * v)).norm(), 0.0, 1e-9) << k;
    if (k > 0) {
      EXPECT_NEAR((p.position - s.points[k - 1].position).norm(), v.norm() * 0.125, 1e-9);
    }
  }
  // The default spacing: a quarter of the frame spacing (0.25 / 4); the first release not
  // on the grid of releases still ends with the one at t1.
  o.release_spacing = 0;
  o.t0 = 0.01;
  const Streakline d = trace_streakline(bundle, field, seed, o);
  EXPECT_EQ(d.released, 33);
  EXPECT_DOUBLE_EQ(d.points.back().release, 2.0);
}

TEST(Streakline, DropsWhatLeavesTheDomain) {
  const Mesh grid = make_grid(GridSpec{21, 21, {-1, -1}, {1, 1}});
  const TangentBundle bundle(grid);
  const Field field = field_from(bundle, TimeSampling{0, 2, 9}, [](const Vec3&, double) { return Vec3(1, 0, 0); });
  StreaklineOptions o;
  o.t0 = 0;
  o.t1 = 2;
  o.release_spacing = 0.25;
  o.max_gap = std::numeric_limits<double>::infinity();  // the releases only
  const Streakline s = trace_streakline(bundle, field, Vec3(0, 0, 0), o);
  // Released at τ, at x = 2 − τ at t1: inside for τ ≥ 1 (x = 1 is on the boundary: in).
  EXPECT_EQ(s.released, 9);
  EXPECT_EQ(s.left, 4);
  EXPECT_EQ(s.points.size(), 5u);
  // Neighbours 0.25 apart, more than the mean edge length: counted, and the largest gap.
  EXPECT_EQ(s.unresolved, 4);
  EXPECT_NEAR(s.largest_gap, 0.25, 1e-9);
  EXPECT_DOUBLE_EQ(s.resolution, grid.mean_edge_length());
}

TEST(Streakline, ReleasesAreAddedWhereNeighboursPartEachWhereItsReleaseTimeSays) {
  // Uniform flow to +x: the particle released at τ is at x = 2 − τ at t1 = 2. Releases a
  // quarter apart end a quarter apart, more than the mean edge length (about 0.12): releases
  // are added halfway until neighbours are within it, each where its own time puts it.
  const Mesh grid = make_grid(GridSpec{41, 21, {-1, -1}, {3, 1}});
  const TangentBundle bundle(grid);
  const Field field = field_from(bundle, TimeSampling{0, 2, 9}, [](const Vec3&, double) { return Vec3(1, 0, 0); });
  StreaklineOptions o;
  o.t0 = 0;
  o.t1 = 2;
  o.release_spacing = 0.25;
  const Streakline s = trace_streakline(bundle, field, Vec3(0, 0, 0), o);
  const double h = grid.mean_edge_length();
  EXPECT_GT(s.released, 9);
  EXPECT_EQ(s.left, 0);
  EXPECT_EQ(s.unresolved, 0);
  EXPECT_LE(s.largest_gap, h);
  EXPECT_DOUBLE_EQ(s.resolution, h);
  ASSERT_EQ(s.points.size(), static_cast<size_t>(s.released));
  for (size_t k = 0; k < s.points.size(); ++k) {
    EXPECT_NEAR((s.points[k].position - Vec3(2.0 - s.points[k].release, 0, 0)).norm(), 0.0, 1e-9);
    if (k > 0) {
      EXPECT_GT(s.points[k].release, s.points[k - 1].release);
      EXPECT_LE((s.points[k].position - s.points[k - 1].position).norm(), h + 1e-12);
    }
  }
  // Out of additions: what is left too far apart is counted.
  o.max_added = 3;
  const Streakline few = trace_streakline(bundle, field, Vec3(0, 0, 0), o);
  EXPECT_EQ(few.released, 12);
  EXPECT_GT(few.unresolved, 0);
  EXPECT_NEAR(few.largest_gap, 0.25, 1e-9);
  // A negative or NaN gap is no distance.
  o.max_gap = -1;
  EXPECT_THROW(trace_streakline(bundle, field, Vec3(0, 0, 0), o), Error);
}

TEST(Streakline, RefusesBadTimesAndSeeds) {
  const Mesh grid = make_grid(GridSpec{11, 11, {-1, -1}, {1, 1}});
  const TangentBundle bundle(grid);
  const Field field = field_from(bundle, TimeSampling{0, 1, 5}, [](const Vec3&, double) { return Vec3(1, 0, 0); });
  StreaklineOptions o;
  o.t0 = 0.8;
  o.t1 = 0.2;
  EXPECT_THROW(trace_streakline(bundle, field, Vec3(0, 0, 0), o), Error);
  o.t0 = 0;
  o.t1 = 1.5;
  EXPECT_THROW(trace_streakline(bundle, field, Vec3(0, 0, 0), o), Error);
  o.t1 = 1;
  EXPECT_THROW(trace_streakline(bundle, field, Vec3(2, 0, 0), o), Error);
  o.release_spacing = -0.1;
  EXPECT_THROW(trace_streakline(bundle, field, Vec3(0, 0, 0), o), Error);
  // More releases than kMaxReleases over [t0, t1]: refused before anything is allocated
  // (1e-9 over [0, 1] would be a billion particles, 100 GB).
  o.release_spacing = 1e-9;
  try {
    trace_streakline(bundle, field, Vec3(0, 0, 0), o);
    ADD_FAILURE() << "not refused";
  } catch (const Error& e) {
    EXPECT_NE(std::string(e.what()).find("release spacing 1e-09 would release 1e+09 particles"), std::string::npos)
        << e.what();
  }
  // A timeline of more particles than its limit.
  TimelineOptions t;
  t.t0 = 0;
  t.t1 = 1;
  t.count = t.max_points + 1;
  EXPECT_THROW(trace_timeline(bundle, field, Vec3(-0.5, 0, 0), Vec3(0.5, 0, 0), t), Error);
}

TEST(Streakline, OnTheSphereStaysOnTheSeedsLatitude) {
  const Mesh& sphere = test::icosphere_mesh();
  const TangentBundle bundle(sphere);
  const Field field = field_from(bundle, TimeSampling{0, 2, 9}, [](const Vec3& x, double) { return Vec3(-x.y(), x.x(), 0); });
  StreaklineOptions o;
  o.t0 = 0;
  o.t1 = 2;
  const Streakline s = trace_streakline(bundle, field, Vec3(0.6, 0, 0.8), o);
  EXPECT_EQ(s.left, 0);
  for (const StreakPoint& p : s.points) EXPECT_NEAR(p.position.z(), 0.8, 0.03);
  EXPECT_NEAR(std::atan2(s.points.front().position.y(), s.points.front().position.x()), 2.0, 0.06);
}

// On a surface a seed or a line's end is moved to its closest point, within three mean edge
// lengths (as the dye renderers' seeds): one far off would land wherever the nearest part
// of the surface happens to be (a seed at (5, 5, 5) by CGAL's camel, whose box is ±0.5,
// was traced from its back without a word).
TEST(Streakline, OnASurfaceASeedFarOffIsRefused) {
  const Mesh& sphere = test::icosphere_mesh();
  const TangentBundle bundle(sphere);
  const Field field = field_from(bundle, TimeSampling{0, 1, 5}, [](const Vec3& x, double) { return Vec3(-x.y(), x.x(), 0); });
  const double h = sphere.mean_edge_length();
  auto refusal = [&](auto&& trace) {
    try {
      trace();
    } catch (const Error& e) {
      return std::string(e.what());
    }
    return std::string("not refused");
  };
  StreaklineOptions o;
  o.t0 = 0;
  o.t1 = 1;
  const std::string far = refusal([&] { trace_streakline(bundle, field, Vec3(3, 3, 3), o); });
  EXPECT_NE(far.find("the streakline seed (3, 3, 3) is 4.2"), std::string::npos) << far;
  EXPECT_NE(far.find("from the surface, farther than"), std::string::npos) << far;
  EXPECT_NE(far.find("(three edge lengths)"), std::string::npos) << far;
  const std::string nan = refusal([&] { trace_streakline(bundle, field, Vec3(NAN, 0, 1), o); });
  EXPECT_NE(nan.find("the streakline seed must have finite coordinates"), std::string::npos) << nan;
  // Two edge lengths above the pole: moved onto it and traced; a larger reach given takes more.
  EXPECT_EQ(trace_streakline(bundle, field, Vec3(0, 0, 1 + 2 * h), o).left, 0);
  o.max_seed_distance = 5;
  EXPECT_EQ(trace_streakline(bundle, field, Vec3(3, 3, 3), o).left, 0);
  TimelineOptions t;
  t.t0 = 0;
  t.t1 = 1;
  const std::string end = refusal([&] { trace_timeline(bundle, field, Vec3(1, 0, 0), Vec3(0, 0, -3), t); });
  EXPECT_NE(end.find("the timeline's last point (0, 0, -3) is 2"), std::string::npos) << end;
  EXPECT_NE(trace_timeline(bundle, field, Vec3(1 + h, 0, 0), Vec3(0, 1, 0), t).points.size(), 0u);
}

TEST(Timeline, IsTheSegmentCarriedAndRefinedWhereItStretches) {
  const Mesh grid = make_grid(GridSpec{41, 41, {-1, -1}, {1, 1}});
  const TangentBundle bundle(grid);
  // Uniform translation: the segment moves by (t1 − t0)·v.
  const Vec3 v(0.2, 0.3, 0);
  const Field uniform = field_from(bundle, TimeSampling{0, 1, 5}, [&](const Vec3&, double) { return v; });
  TimelineOptions o;
  o.t0 = 0.25;
  o.t1 = 1;
  o.count = 11;
  o.max_gap = 1;  // no refinement
  const Vec3 a(-0.6, -0.6, 0), b(0.2, -0.4, 0);
  const Streakline line = trace_timeline(bundle, uniform, a, b, o);
  ASSERT_EQ(line.points.size(), 11u);
  for (const StreakPoint& p : line.points)
    EXPECT_NEAR((p.position - ((1 - p.release) * a + p.release * b + 0.75 * v)).norm(), 0.0, 1e-9);
  // A saddle V = (x, −y) stretches a segment along x by e^{t1 − t0}: points are added until
  // neighbours are at most max_gap apart, and each sits at its parameter's image.
  const Field saddle = field_from(bundle, TimeSampling{0, 1, 11}, [](const Vec3& x, double) { return Vec3(x.x(), -x.y(), 0); });
  o.t0 = 0;
  o.t1 = 1;
  o.count = 5;
  o.max_gap = 0.05;
  const Streakline s = trace_timeline(bundle, saddle, Vec3(-0.3, 0.5, 0), Vec3(0.3, 0.5, 0), o);
  ASSERT_GT(s.points.size(), 5u);
  EXPECT_EQ(s.left, 0);
  for (size_t k = 0; k < s.points.size(); ++k) {
    const double x0 = -0.3 + 0.6 * s.points[k].release;
    EXPECT_NEAR((s.points[k].position - Vec3(x0 * std::exp(1.0), 0.5 * std::exp(-1.0), 0)).norm(), 0.0, 1e-6);
    if (k > 0) {
      EXPECT_LE((s.points[k].position - s.points[k - 1].position).norm(), 0.05 + 1e-9);
    }
  }
  EXPECT_EQ(s.unresolved, 0);
  EXPECT_EQ(s.unresolved_by, Streakline::Refinement::resolved);
  EXPECT_THROW(trace_timeline(bundle, saddle, Vec3(-3, 0, 0), Vec3(0, 0, 0), o), Error);
  // Out of particles: the gaps left are counted and the reason named.
  o.max_points = 8;
  const Streakline few = trace_timeline(bundle, saddle, Vec3(-0.3, 0.5, 0), Vec3(0.3, 0.5, 0), o);
  EXPECT_EQ(few.released, 8);
  EXPECT_GT(few.unresolved, 0);
  EXPECT_GT(few.largest_gap, 0.05);
  EXPECT_EQ(few.unresolved_by, Streakline::Refinement::out_of_particles);
  // Both ends at one point: no line.
  EXPECT_THROW(trace_timeline(bundle, saddle, Vec3(0.2, 0.2, 0), Vec3(0.2, 0.2, 0), o), Error);
}

TEST(Timeline, ABudgetThatRunsOutHalvesTheWidestGapsFirst) {
  // V = (x², 0) carries x0 to x0 / (1 − x0 t): the segment [0, 0.45] on y = 0 ends at
  // [0, 0.818] at t = 1, stretched 3.3 times at its right end and not at its left. Asked for
  // neighbours 1e-4 apart with 100 particles, the widest gaps are halved first, so the line
  // is about evenly resolved: its largest gap within twice the even spacing (halving in
  // order along the line instead leaves the right end ~2.8 times that).
  const Mesh grid = make_grid(GridSpec{41, 41, {-1, -1}, {1, 1}});
  const TangentBundle bundle(grid);
  const Field field = field_from(bundle, TimeSampling{0, 1, 11}, [](const Vec3& x, double) { return Vec3(x.x() * x.x(), 0, 0); });
  TimelineOptions o;
  o.t0 = 0;
  o.t1 = 1;
  o.count = 5;
  o.max_gap = 1e-4;
  o.max_points = 100;
  const Streakline s = trace_timeline(bundle, field, Vec3(0, 0, 0), Vec3(0.45, 0, 0), o);
  ASSERT_EQ(s.released, 100);
  EXPECT_EQ(s.unresolved_by, Streakline::Refinement::out_of_particles);
  const double length = s.points.back().position.x() - s.points.front().position.x();
  EXPECT_NEAR(length, 0.45 / (1 - 0.45), 0.01);
  EXPECT_LT(s.largest_gap, 2.0 * length / 99);
}

TEST(Timeline, RunsOnInsideUpToWhereItLeavesTheDomain) {
  // V = (x², 0) carries x0 to x0 / (1 − x0 t): of the segment [0.2, 0.9] on y = 0 the part
  // x0 < 0.5 is inside at t = 1, stretched over [0.25, 1]. With 5 particles at t0 only
  // 0.2 and 0.375 stay (at 0.25 and 0.6); the pair of which one left is halved as well, so
  // the line runs on to the wall x = 1, every point where the closed form puts it.
  const Mesh grid = make_grid(GridSpec{41, 41, {-1, -1}, {1, 1}});
  const TangentBundle bundle(grid);
  const Field field = field_from(bundle, TimeSampling{0, 1, 11}, [](const Vec3& x, double) { return Vec3(x.x() * x.x(), 0, 0); });
  TimelineOptions o;
  o.t0 = 0;
  o.t1 = 1;
  o.count = 5;
  const Streakline s = trace_timeline(bundle, field, Vec3(0.2, 0, 0), Vec3(0.9, 0, 0), o);
  ASSERT_GE(s.points.size(), 2u);
  EXPECT_GT(s.left, 0);
  EXPECT_EQ(s.unresolved, 0);
  EXPECT_LE(s.largest_gap, s.resolution);
  double last = 0;
  for (const StreakPoint& p : s.points) {
    EXPECT_FALSE(p.gap_before);  // one piece: what left, left past its end
    const double x0 = 0.2 + 0.7 * p.release;
    EXPECT_NEAR(p.position.x(), x0 / (1 - x0), 3e-3) << "s = " << p.release;  // x² sampled piecewise linearly
    EXPECT_NEAR(p.position.y(), 0.0, 1e-12);
    last = std::max(last, p.position.x());
  }
  EXPECT_NEAR(s.points.front().position.x(), 0.25, 3e-3);
  EXPECT_GT(last, 1.0 - s.resolution);
}

TEST(Timeline, FindsWhatStaysBetweenParticlesThatLeft) {
  // The saddle V = (27x, −27y): of the segment y = 0.6, x ∈ [−0.3, 0.5] only the particles
  // within e^{−13.5}·… of its stable separatrix x = 0 are inside at t = 0.5, and every one of
  // the 100 placed at t0 has gone through the left or right wall. The pair that left on
  // either side is halved until particles that stay are found; they lie along the unstable
  // separatrix y = 0 from wall to wall, resolved (one point before).
  const Mesh grid = make_grid(GridSpec{21, 21, {-1, -1}, {1, 1}});
  const TangentBundle bundle(grid);
  const Field field =
      field_from(bundle, TimeSampling{0, 1, 11}, [](const Vec3& x, double) { return Vec3(27 * x.x(), -27 * x.y(), 0); });
  TimelineOptions o;
  o.t0 = 0;
  o.t1 = 0.5;
  const Streakline s = trace_timeline(bundle, field, Vec3(-0.3, 0.6, 0), Vec3(0.5, 0.6, 0), o);
  ASSERT_GE(s.points.size(), 10u);
  EXPECT_GE(s.left, 100);
  EXPECT_EQ(s.unresolved, 0);
  double lo = 1, hi = -1;
  for (const StreakPoint& p : s.points) {
    EXPECT_NEAR(p.position.y(), 0.6 * std::exp(-27 * 0.5), 1e-4);
    lo = std::min(lo, p.position.x());
    hi = std::max(hi, p.position.x());
  }
  EXPECT_LT(lo, -1 + s.resolution);
  EXPECT_GT(hi, 1 - s.resolution);
}

TEST(Timeline, OnASurfaceIsTheShortestPathOverIt) {
  // Ends at either pole, (±1, 0, 0): the chord between them runs through the centre, but the
  // line at t0 is the shortest path over the sphere, half a great circle (length π, less
  // the icosphere's faceting), every neighbour within a mean edge length.
  const Mesh& sphere = test::icosphere_mesh();
  const TangentBundle bundle(sphere);
  const Field field = field_from(bundle, TimeSampling{0, 1, 5}, [](const Vec3& x, double) { return Vec3(-x.y(), x.x(), 0); });
  TimelineOptions o;
  o.t0 = 0;
  o.t1 = 0;
  const Streakline pole_to_pole = trace_timeline(bundle, field, Vec3(1, 0, 0), Vec3(-1, 0, 0), o);
  EXPECT_EQ(pole_to_pole.unresolved, 0);
  EXPECT_LE(pole_to_pole.largest_gap, sphere.mean_edge_length());
  EXPECT_NEAR((pole_to_pole.points.front().position - Vec3(1, 0, 0)).norm(), 0.0, 0.02);
  EXPECT_NEAR((pole_to_pole.points.back().position - Vec3(-1, 0, 0)).norm(), 0.0, 0.02);
  for (const StreakPoint& p : pole_to_pole.points) EXPECT_NEAR(p.position.norm(), 1.0, 0.02);
  double length = 0;
  for (size_t k = 1; k < pole_to_pole.points.size(); ++k)
    length += (pole_to_pole.points[k].position - pole_to_pole.points[k - 1].position).norm();
  EXPECT_NEAR(length, M_PI, 0.02 * M_PI);
  // A chord over a quarter of the equator snaps to one arc: carried round the axis by 1 rad.
  o.t1 = 1;
  const Streakline s = trace_timeline(bundle, field, Vec3(1, 0, 0), Vec3(0, 1, 0), o);
  EXPECT_EQ(s.unresolved, 0);
  EXPECT_NEAR(std::atan2(s.points.front().position.y(), s.points.front().position.x()), 1.0, 0.05);
  EXPECT_NEAR(std::atan2(s.points.back().position.y(), s.points.back().position.x()), 1.0 + M_PI / 2, 0.05);
}

TEST(Timeline, OnAThinPartGoesOverItsRimNotThroughIt) {
  // From the top of a slab a fiftieth of an edge length thick to the point under it on the
  // bottom: the line at t0 runs to the rim, over it and back (about 0.5 long),
  // every particle on the surface and each within a mean edge length of the next. Its
  // particles were the closest surface points of the chords of a path straightened
  // through the slab: a line 0.04 long whose particles jumped from one sheet to the other.
  const Mesh& slab = test::slab_mesh();
  const TangentBundle bundle(slab);
  const Field still = field_from(bundle, TimeSampling{0, 1, 3}, [](const Vec3&, double) { return Vec3(0, 0, 0); });
  TimelineOptions o;
  o.t0 = 0;
  o.t1 = 0;
  const Vec3 p(0.75, 0.52, test::kSlabThickness), q(0.75, 0.48, 0);
  const Streakline line = trace_timeline(bundle, still, p, q, o);
  EXPECT_EQ(line.unresolved, 0);
  EXPECT_LE(line.largest_gap, slab.mean_edge_length());
  double length = 0, rim = 0;
  for (size_t k = 1; k < line.points.size(); ++k) {
    length += (line.points[k].position - line.points[k - 1].position).norm();
    rim = std::max(rim, line.points[k].position.x());
  }
  // Particles on either side of the rim, their chord short of the path over it by at most
  // their distance along it.
  EXPECT_GT(rim, 1 - line.largest_gap);
  EXPECT_NEAR(length, std::hypot(0.5 + test::kSlabThickness, 0.04), 2 * line.largest_gap);
}

TEST(Timeline, ASegmentBetweenPiecesOfASurfaceIsRefused) {
  // Two unit squares ten apart: no path over the surface joins a point of one to a point of
  // the other, so there is no line.
  const Mesh squares({{0, 0, 0}, {1, 0, 0}, {1, 1, 0}, {0, 1, 0}, {0, 0, 10}, {1, 0, 10}, {1, 1, 10}, {0, 1, 10}},
                     {{0, 1, 2}, {0, 2, 3}, {4, 5, 6}, {4, 6, 7}});
  const TangentBundle bundle(squares);
  const Field field = field_from(bundle, TimeSampling{0, 1, 3}, [](const Vec3&, double) { return Vec3(0.1, 0, 0); });
  TimelineOptions o;
  o.t0 = 0;
  o.t1 = 1;
  try {
    trace_timeline(bundle, field, Vec3(0.5, 0.5, 0), Vec3(0.5, 0.5, 10), o);
    ADD_FAILURE() << "not refused";
  } catch (const Error& e) {
    EXPECT_NE(std::string(e.what()).find("lie on separate pieces of the surface: no path over it joins them"),
              std::string::npos)
        << e.what();
  }
  // Within one square the segment is taken.
  EXPECT_EQ(trace_timeline(bundle, field, Vec3(0.2, 0.5, 10), Vec3(0.8, 0.5, 10), o).left, 0);
}

// The saddle V = c(t) (x, −y), c = 6 sin 2πt, stretches the segment y = 0.5,
// x ∈ [−0.1, 0.1] along x by e^K, K = 6 (1 − cos 2πt) / 2π: to 6.7 times its length at
// t = 0.5, and brings it back by t = 1. The timeline is that segment, drawn at t = 0.
class StretchedAndBack : public ::testing::Test {
protected:
  const Mesh grid = make_grid(GridSpec{41, 41, {-1, -1}, {1, 1}});
  const TangentBundle bundle{grid};
  const Field saddle = field_from(bundle, TimeSampling{0, 1, 41}, [](const Vec3& x, double t) -> Vec3 {
    return 6 * std::sin(2 * std::numbers::pi * t) * Vec3(x.x(), -x.y(), 0);
  });
  const FlowMap flow{bundle, saddle};
  const PointLocator locator{grid};
  const Vec3 a{-0.1, 0.5, 0}, b{0.1, 0.5, 0};
  TimelineOptions options() const {
    TimelineOptions o;
    o.t0 = 0;
    o.count = 5;
    o.max_gap = 0.02;
    return o;
  }
  // The line as trace_timeline draws it afresh at t.
  Streakline afresh(double t) const {
    TimelineOptions o = options();
    o.t1 = t;
    return trace_timeline(bundle, saddle, a, b, o);
  }
  // Resolved at t, each particle where the flow map carries its parameter's start.
  void expect_resolved_and_carried(const Streakline& s, double t) const {
    EXPECT_EQ(s.unresolved, 0) << "t = " << t;
    EXPECT_LE(s.largest_gap, 0.02) << "t = " << t;
    for (const StreakPoint& p : s.points) {
      const Vec3 start = (1 - p.release) * a + p.release * b;
      const Vec3 there = surface_position(grid, flow.advect(locator.closest(start), 0, t).where);
      EXPECT_NEAR((p.position - there).norm(), 0.0, 1e-9) << "t = " << t << ", s = " << p.release;
    }
  }
};

// Advanced frame by frame, the particles added while it stretched go again as it draws
// together: at t = 1 the line holds about what tracing it afresh holds, not the particles
// of its longest time, resolved at every frame.
TEST_F(StretchedAndBack, AMaterialLineDropsWhatItAddedWhereItDrawsTogetherAgain) {
  MaterialLine line(flow, a, b, options());
  size_t most = 0;
  for (int k = 1; k <= 40; ++k) {
    const double t = k / 40.0;
    line.advance(t);
    most = std::max(most, line.line().points.size());
    expect_resolved_and_carried(line.line(), t);
  }
  const Streakline once = afresh(1);
  EXPECT_GE(most, 4 * once.points.size());  // it did stretch
  EXPECT_LE(line.line().points.size(), 2 * once.points.size());
  EXPECT_GE(line.line().points.size(), once.points.size());
}

// The whole contraction in one advance (t = 0.5 → 1): every particle the stretch added goes
// at once, so the line holds about what tracing it afresh holds (25 against 17: the added
// ones go where neighbours are within half the gap, the refinement adds where they are
// beyond it), not half the stretch's particles (one of two neighbours per advance kept 65
// of 129).
TEST_F(StretchedAndBack, AMaterialLineDropsAWholeContractionInOneAdvance) {
  MaterialLine line(flow, a, b, options());
  line.advance(0.5);
  const size_t stretched = line.line().points.size();
  line.advance(1.0);
  const Streakline once = afresh(1);
  std::printf("  stretched %zu, after the contraction %zu, afresh %zu\n", stretched, line.line().points.size(),
              once.points.size());
  EXPECT_GE(stretched, 4 * once.points.size());
  EXPECT_LE(line.line().points.size(), 2 * once.points.size());
  expect_resolved_and_carried(line.line(), 1);
}

TEST(MaterialLine, IsRefinedAsItStretchesEachParticleAtItsParametersImage) {
  // The saddle V = (x, −y) stretches a segment along y = 0.5 by e^{t − t0}. Advanced picture
  // by picture (times between frames too), every particle sits at its parameter's image, the
  // particles added at earlier times stay, neighbours are within max_gap at every time, and
  // the line agrees with trace_timeline's at the end.
  const Mesh grid = make_grid(GridSpec{41, 41, {-1, -1}, {1, 1}});
  const TangentBundle bundle(grid);
  const Field saddle = field_from(bundle, TimeSampling{0, 1, 11}, [](const Vec3& x, double) { return Vec3(x.x(), -x.y(), 0); });
  const FlowMap flow(bundle, saddle);
  TimelineOptions o;
  o.t0 = 0;
  o.count = 5;
  o.max_gap = 0.05;
  const Vec3 a(-0.3, 0.5, 0), b(0.3, 0.5, 0);
  MaterialLine line(flow, a, b, o);
  // Filled in where it is drawn to within a mean edge length (0.057 here): 0.6 long, so at
  // least 12 particles.
  EXPECT_EQ(line.time(), 0.0);
  EXPECT_GE(line.line().points.size(), 12u);
  EXPECT_EQ(line.line().unresolved, 0);
  size_t before = line.line().points.size();
  for (const double t : {0.25, 0.5, 0.55, 0.8, 1.0}) {
    line.advance(t);
    const Streakline& s = line.line();
    EXPECT_EQ(s.t, t);
    EXPECT_GE(s.points.size(), before);
    before = s.points.size();
    EXPECT_EQ(s.unresolved, 0);
    EXPECT_LE(s.largest_gap, 0.05);
    for (size_t k = 0; k < s.points.size(); ++k) {
      const double x0 = -0.3 + 0.6 * s.points[k].release;
      EXPECT_NEAR((s.points[k].position - Vec3(x0 * std::exp(t), 0.5 * std::exp(-t), 0)).norm(), 0.0, 1e-6);
      if (k > 0) {
        EXPECT_GT(s.points[k].release, s.points[k - 1].release);
      }
    }
  }
  o.t1 = 1;
  const Streakline once = trace_timeline(bundle, saddle, a, b, o);
  EXPECT_GE(line.line().points.size(), once.points.size());
  // (0.55 is no frame time: the steps split there, so the two agree to the RK4 error.)
  EXPECT_NEAR((line.line().points.front().position - once.points.front().position).norm(), 0.0, 1e-6);
  // Backwards to t0: each particle where it started, to the integration error.
  line.advance(0);
  for (const StreakPoint& p : line.line().points)
    EXPECT_NEAR((p.position - ((1 - p.release) * a + p.release * b)).norm(), 0.0, 1e-6);
  EXPECT_THROW(line.advance(1.5), Error);
  // Refused as trace_timeline refuses.
  EXPECT_THROW(MaterialLine(flow, a, a, o), Error);
  o.count = 1;
  EXPECT_THROW(MaterialLine(flow, a, b, o), Error);
}

}  // namespace
}  // namespace tvf
