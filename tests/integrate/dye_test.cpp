#include "tvf/integrate/dye.h"

#include "support/test_fields.h"
#include "support/test_meshes.h"
#include "tvf/core/error.h"
#include "tvf/mesh/grid.h"

#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <limits>
#include <string>
#include <vector>

namespace tvf {
namespace {

using test::field_from;

// The incremental dye at its time against trace_streakline from scratch: the same
// releases, drops and gaps, positions within tol.
void expect_same(const DyeInjector& dye, const TangentBundle& bundle, const Field& field, const Vec3& seed,
                 double tol, const std::string& where) {
  StreaklineOptions o;
  o.t0 = dye.start();
  o.t1 = dye.time();
  o.release_spacing = dye.release_spacing();
  o.max_gap = std::numeric_limits<double>::infinity();  // the dye's particles: its releases only
  const Streakline ref = trace_streakline(bundle, field, seed, o);
  const Streakline got = dye.streakline(0);
  EXPECT_DOUBLE_EQ(got.t, ref.t) << where;
  EXPECT_EQ(got.released, ref.released) << where;
  EXPECT_EQ(got.left, ref.left) << where;
  ASSERT_EQ(got.points.size(), ref.points.size()) << where;
  for (size_t k = 0; k < ref.points.size(); ++k) {
    EXPECT_DOUBLE_EQ(got.points[k].release, ref.points[k].release) << where << " point " << k;
    EXPECT_EQ(got.points[k].gap_before, ref.points[k].gap_before) << where << " point " << k;
    EXPECT_NEAR((got.points[k].position - ref.points[k].position).norm(), 0.0, tol) << where << " point " << k;
  }
}

TEST(Dye, OfASteadyRotationLiesOnTheCircleThroughTheSeed) {
  // A steady field's dye is its streamline through the seed: the circle of the seed's
  // radius 0.5, the particle released at τ turned by t − τ, advanced picture by picture.
  const Mesh grid = make_grid(GridSpec{41, 41, {-1, -1}, {1, 1}});
  const TangentBundle bundle(grid);
  const Field field =
      field_from(bundle, TimeSampling{0, 4, 17}, [](const Vec3& x, double) { return Vec3(-x.y(), x.x(), 0); });
  const std::vector<Vec3> seeds{Vec3(0.5, 0, 0), Vec3(0, -0.25, 0)};
  DyeOptions o;
  o.release_spacing = 0.1;
  DyeInjector dye(bundle, field, seeds, 0.0, o);
  EXPECT_EQ(dye.num_seeds(), 2u);
  EXPECT_EQ(dye.streakline(0).points.size(), 1u);  // released at t0, at the seed
  for (int k = 1; k <= 13; ++k) dye.advance(0.25 * k);  // to t = 3.25 (almost a half turn more)
  EXPECT_DOUBLE_EQ(dye.time(), 3.25);
  for (size_t s = 0; s < 2; ++s) {
    const Streakline line = dye.streakline(s);
    EXPECT_EQ(line.released, 34);  // 0, 0.1, …, 3.2 and 3.25 at the seed
    EXPECT_EQ(line.left, 0);
    const double r = seeds[s].norm(), phase = std::atan2(seeds[s].y(), seeds[s].x());
    for (const StreakPoint& p : line.points) {
      const double angle = phase + dye.time() - p.release;
      EXPECT_NEAR(p.position.norm(), r, 1e-6);
      EXPECT_NEAR((p.position - Vec3(r * std::cos(angle), r * std::sin(angle), 0)).norm(), 0.0, 1e-5) << p.release;
    }
  }
  EXPECT_EQ(dye.released(), 68);
  EXPECT_EQ(dye.alive(), 68);
}

TEST(Dye, OnTheSphereStaysOnTheSeedsLatitude) {
  // A rotation about z on the unit sphere: the dye stays on the seed's circle of latitude
  // (z = 0.8) and the oldest particle has turned by the time since its release.
  const Mesh& sphere = test::icosphere_mesh();
  const TangentBundle bundle(sphere);
  const Field field =
      field_from(bundle, TimeSampling{0, 2, 9}, [](const Vec3& x, double) { return Vec3(-x.y(), x.x(), 0); });
  // A little outside the sphere: moved onto it.
  const std::vector<Vec3> seeds{1.02 * Vec3(0.6, 0, 0.8)};
  DyeInjector dye(bundle, field, seeds, 0.0);
  EXPECT_DOUBLE_EQ(dye.release_spacing(), 0.0625);  // a quarter of the frame spacing
  EXPECT_NEAR(dye.seed_position(0).norm(), 1.0, 0.01);
  for (int k = 1; k < 9; ++k) dye.advance(0.25 * k);
  const Streakline line = dye.streakline(0);
  EXPECT_EQ(line.left, 0);
  EXPECT_EQ(line.released, 33);
  for (const StreakPoint& p : line.points) EXPECT_NEAR(p.position.z(), 0.8, 0.03) << p.release;
  EXPECT_NEAR(std::atan2(line.points.front().position.y(), line.points.front().position.x()), 2.0, 0.06);
  // Equal to tracing it from scratch (the pictures are the field's frames).
  expect_same(dye, bundle, field, seeds[0], 1e-7, "sphere");
}

TEST(Dye, EqualsTracingTheStreaklineAtEveryPicture) {
  // The double gyre (time-dependent): at every picture the incremental dye is
  // trace_streakline's; to rounding when the pictures are the field's frames, to the
  // integration error when they fall between them.
  const Mesh grid = make_grid(GridSpec{41, 21, {0, 0}, {2, 1}});
  const TangentBundle bundle(grid);
  const TimeSampling time{0, 10, 21};
  const Field field = field_from(bundle, time, test::double_gyre);
  const Vec3 seed(0.9, 0.3, 0);
  {
    DyeInjector dye(bundle, field, std::vector<Vec3>{seed}, 0.0);
    for (int k = 1; k < time.frames; ++k) {
      dye.advance(time.time(k));
      expect_same(dye, bundle, field, seed, 1e-9, "frame " + std::to_string(k));
    }
    EXPECT_GT(dye.streakline(0).points.size(), 70u);
  }
  // Pictures 0.7 apart, between the frames (0.5 apart): the pictures' times cut the RK4
  // steps where one long carry does not, so the two differ by the integration error: as
  // much as either differs from a trace with an eighth of the step, and shrinking with the
  // step (RK4 on a field linear in each cell and frame interval: about h²).
  auto largest_difference = [&](double dt) {
    DyeOptions o;
    o.release_spacing = 0.1;
    o.flow.dt = dt;
    DyeInjector dye(bundle, field, std::vector<Vec3>{seed}, 1.0, o);
    double incremental = 0, integration = 0;
    for (int k = 1; k <= 12; ++k) {
      dye.advance(1.0 + 0.7 * k);
      expect_same(dye, bundle, field, seed, 1e-2, "picture " + std::to_string(k));
      StreaklineOptions so;
      so.t0 = 1.0;
      so.t1 = dye.time();
      so.release_spacing = 0.1;
      so.max_gap = std::numeric_limits<double>::infinity();
      so.flow.dt = dt;
      const Streakline ref = trace_streakline(bundle, field, seed, so);
      so.flow.dt = dt / 8;
      const Streakline fine = trace_streakline(bundle, field, seed, so);
      const Streakline got = dye.streakline(0);
      EXPECT_EQ(fine.points.size(), ref.points.size());
      EXPECT_EQ(got.points.size(), ref.points.size());
      for (size_t i = 0; i < std::min({ref.points.size(), fine.points.size(), got.points.size()}); ++i) {
        incremental = std::max(incremental, (got.points[i].position - ref.points[i].position).norm());
        integration = std::max(integration, (fine.points[i].position - ref.points[i].position).norm());
      }
    }
    EXPECT_GT(incremental, 0.0);
    EXPECT_LT(incremental, 2 * integration) << "dt " << dt;
    return incremental;
  };
  const double coarse = largest_difference(0.25);  // the default: half the frame spacing
  const double fine = largest_difference(0.25 / 4);
  EXPECT_LT(fine, coarse / 8);
  std::printf("incremental against traced, largest over 12 pictures: %.3g at dt 0.25, %.3g at dt 0.0625\n", coarse,
              fine);
}

TEST(Dye, DropsWhatLeavesTheDomainAsTracingDoes) {
  // Uniform flow to +x from the centre of [−1, 1]²: released at τ, at x = t − τ; what has
  // gone past x = 1 is dropped.
  const Mesh grid = make_grid(GridSpec{21, 21, {-1, -1}, {1, 1}});
  const TangentBundle bundle(grid);
  const Field field = field_from(bundle, TimeSampling{0, 2, 9}, [](const Vec3&, double) { return Vec3(1, 0, 0); });
  DyeOptions o;
  o.release_spacing = 0.25;
  DyeInjector dye(bundle, field, std::vector<Vec3>{Vec3(0, 0, 0)}, 0.0, o);
  for (int k = 1; k < 9; ++k) {
    dye.advance(0.25 * k);
    expect_same(dye, bundle, field, Vec3(0, 0, 0), 1e-9, "frame " + std::to_string(k));
  }
  const Streakline line = dye.streakline(0);
  EXPECT_EQ(line.released, 9);
  EXPECT_EQ(line.left, 4);
  ASSERT_EQ(line.points.size(), 5u);
  for (const StreakPoint& p : line.points) EXPECT_NEAR(p.position.x(), 2.0 - p.release, 1e-9);
  EXPECT_EQ(dye.alive(), 5);
}

TEST(Dye, TimelinesAreTracedAtEveryAdvance) {
  // A timeline beside the dye (none needed): at each time, trace_timeline's from the start
  // (the times are frame times, so the positions agree to rounding).
  const Mesh grid = make_grid(GridSpec{21, 21, {-1, -1}, {1, 1}});
  const TangentBundle bundle(grid);
  const Field field = field_from(bundle, TimeSampling{0, 2, 9}, [](const Vec3& x, double) { return Vec3(-x.y(), x.x(), 0); });
  DyeOptions o;
  o.timelines = {{Vec3(-0.5, 0, 0), Vec3(0.5, 0, 0)}};
  DyeInjector dye(bundle, field, std::vector<Vec3>{}, 0.5, o);
  EXPECT_EQ(dye.num_seeds(), 0u);
  ASSERT_EQ(dye.num_timelines(), 1u);
  for (const double t : {0.5, 1.0, 2.0}) {
    dye.advance(t);
    TimelineOptions to;
    to.t0 = 0.5;
    to.t1 = t;
    const Streakline want = trace_timeline(bundle, field, Vec3(-0.5, 0, 0), Vec3(0.5, 0, 0), to);
    const Streakline& got = dye.timeline(0);
    ASSERT_EQ(got.points.size(), want.points.size());
    for (size_t k = 0; k < want.points.size(); ++k) {
      EXPECT_EQ(got.points[k].release, want.points[k].release);
      EXPECT_NEAR((got.points[k].position - want.points[k].position).norm(), 0.0, 1e-12);
    }
    // The rotation turns it by t − 0.5.
    EXPECT_NEAR(std::atan2(got.points.back().position.y(), got.points.back().position.x()), t - 0.5, 1e-3);
  }
  // Its ends placed as seeds are: outside the domain, or one point, refused.
  o.timelines = {{Vec3(-0.5, 0, 0), Vec3(3, 0, 0)}};
  EXPECT_THROW(DyeInjector(bundle, field, std::vector<Vec3>{}, 0.0, o), Error);
  o.timelines = {{Vec3(0.2, 0.2, 0), Vec3(0.2, 0.2, 0)}};
  EXPECT_THROW(DyeInjector(bundle, field, std::vector<Vec3>{}, 0.0, o), Error);
}

TEST(Dye, RecordsWhereATimelineWasNotResolved) {
  // The saddle V = (λx, −λy), λ = 27, over t ∈ [0, 1]: a timeline across its stable manifold
  // x = 0 parts there by e^{λt}. Early on the refinement keeps neighbours within a mean edge
  // length; by t = 1 neighbours 1e-12 apart across x = 0 end e^27 × 1e-12 ≈ 0.5 apart while
  // still in the domain: torn. The record says at which pictures, from when and the worst.
  const Mesh grid = make_grid(GridSpec{21, 21, {-1, -1}, {1, 1}});
  const TangentBundle bundle(grid);
  constexpr double lambda = 27;
  const Field field =
      field_from(bundle, TimeSampling{0, 1, 11}, [](const Vec3& x, double) { return Vec3(lambda * x.x(), -lambda * x.y(), 0); });
  DyeOptions o;
  o.timelines = {{Vec3(-0.3, 0.6, 0), Vec3(0.5, 0.6, 0)}, {Vec3(0.2, 0.5, 0), Vec3(0.6, 0.5, 0)}};
  DyeInjector dye(bundle, field, std::vector<Vec3>{}, 0.0, o);
  ASSERT_EQ(dye.timeline_records().size(), 2u);
  EXPECT_EQ(dye.timeline_records()[0].times, 0);  // the constructor's own advance is not a picture
  int unresolved = 0;
  double first = -1, worst = -1, largest = 0;
  for (int k = 0; k <= 10; ++k) {
    const double t = 0.1 * k;
    dye.advance(t);
    const Streakline& line = dye.timeline(0);
    if (line.unresolved == 0) continue;
    EXPECT_EQ(line.unresolved_by, Streakline::Refinement::torn) << "t = " << t;
    if (unresolved++ == 0) first = t;
    if (line.largest_gap > largest) {
      largest = line.largest_gap;
      worst = t;
    }
  }
  const TimelineRecord& r = dye.timeline_records()[0];
  EXPECT_EQ(r.times, 11);
  ASSERT_GT(unresolved, 0);
  EXPECT_GT(first, 0.5);  // e^{λt} × 1e-12 stays below a mean edge length until t ≈ 0.94
  EXPECT_EQ(r.unresolved, unresolved);
  EXPECT_DOUBLE_EQ(r.first_unresolved, first);
  EXPECT_DOUBLE_EQ(r.worst_time, worst);
  EXPECT_DOUBLE_EQ(r.largest_gap, largest);
  EXPECT_GT(r.largest_gap, r.resolution);
  EXPECT_EQ(r.unresolved_by, Streakline::Refinement::torn);
  // The second line does not cross x = 0: its particles leave the domain (the line is broken,
  // not unresolved) and what stays is resolved.
  const TimelineRecord& r2 = dye.timeline_records()[1];
  EXPECT_EQ(r2.times, 11);
  EXPECT_EQ(r2.unresolved, 0);
  EXPECT_TRUE(std::isnan(r2.first_unresolved));
}

TEST(Dye, RefusesSeedsOutsideAndTimesBackwards) {
  const Mesh grid = make_grid(GridSpec{11, 11, {-1, -1}, {1, 1}});
  const TangentBundle bundle(grid);
  const Field field = field_from(bundle, TimeSampling{0, 1, 5}, [](const Vec3&, double) { return Vec3(1, 0, 0); });
  auto message = [&](const std::vector<Vec3>& seeds, double t0, const DyeOptions& o = {}) -> std::string {
    try {
      DyeInjector dye(bundle, field, seeds, t0, o);
    } catch (const Error& e) {
      return e.what();
    }
    return "";
  };
  EXPECT_EQ(message({Vec3(0, 0, 0), Vec3(2, 0.5, 0)}, 0), "the dye seed (2, 0.5) is outside the domain");
  // Off the plane (z = 0): refused, not projected (nor called outside for a huge z).
  EXPECT_EQ(message({Vec3(0.5, 0.5, 1e8)}, 0),
            "the dye seed (0.5, 0.5, 100000000) is off the planar domain, which lies at z = 0: give z = 0 or leave it "
            "out");
  EXPECT_NE(message({Vec3(0, 0, 0)}, 1.5).find("outside the field's time range [0, 1]"), std::string::npos);
  DyeOptions bad;
  bad.release_spacing = -0.1;
  EXPECT_EQ(message({Vec3(0, 0, 0)}, 0, bad), "dye release spacing -0.1 must be a positive time");
  bad.release_spacing = 1e-7;
  EXPECT_EQ(message({Vec3(0, 0, 0)}, 0, bad),
            "dye release spacing 1e-07 would release 1e+07 particles per seed over the field's time range [0, 1], "
            "more than 1e+06: give a larger spacing");
  EXPECT_EQ(message({Vec3(0, 0, 0)}, 0), "");
  DyeInjector dye(bundle, field, std::vector<Vec3>{Vec3(0, 0, 0)}, 0.5);
  EXPECT_THROW(dye.advance(0.25), Error);
  EXPECT_THROW(dye.advance(1.5), Error);

  // A surface: a seed more than three edge lengths off is refused with its distance.
  const Mesh& sphere = test::icosphere_mesh();
  const TangentBundle sb(sphere);
  const Field sf = field_from(sb, TimeSampling{0, 1, 5}, [](const Vec3& x, double) { return Vec3(-x.y(), x.x(), 0); });
  try {
    DyeInjector far(sb, sf, std::vector<Vec3>{Vec3(0, 0, 3)}, 0.0);
    ADD_FAILURE() << "a seed 2 from the sphere was accepted";
  } catch (const Error& e) {
    const std::string m = e.what();
    EXPECT_EQ(m.rfind("the dye seed (0, 0, 3) is 2", 0), 0u) << m;  // about 2 from the surface
    EXPECT_NE(m.find("from the surface, farther than"), std::string::npos) << m;
  }
  EXPECT_NO_THROW(DyeInjector(sb, sf, std::vector<Vec3>{Vec3(0, 0, 1.1)}, 0.0));
}

}  // namespace
}  // namespace tvf
