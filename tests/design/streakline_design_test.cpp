// Streaklines as a design element (issue 20): the constraints a sketched streakline puts
// on the solve (exact values, the dye front), and what a user sees — the streakline that
// `tvf streaklines` traces in the generated field from the same seed over the same release
// interval lies on the sketch.
#include "tvf/design/streakline_design.h"

#include "tvf/analysis/coherence.h"
#include "tvf/core/error.h"
#include "tvf/design/generate.h"
#include "tvf/integrate/streakline.h"
#include "tvf/mesh/grid.h"
#include "tvf/mesh/mesh_io.h"
#include "tvf/scene/scene_json.h"

#include "support/test_paths.h"

#include <fmt/format.h>
#include <gtest/gtest.h>

#include <algorithm>
#include <array>
#include <cmath>
#include <map>
#include <numbers>
#include <string>
#include <vector>

namespace tvf {
namespace {

using nlohmann::json;

// --- the constraints themselves

// A straight streakline along y = 0.01 (between two grid rows of a 33² grid on [-1, 1]²,
// h = 1/16) from x = −0.5 to 0.5, released over [0, 0.5]: u = 1 / 0.5 = 2.
Scene straight_scene(double attach) {
  return parse_scene(fmt::format(R"({{"tvf": 1, "domain": {{"grid": {{"size": [33, 33]}}}}, "time": {{"frames": 21}},
    "generator": "spacetime",
    "elements": [{{"kind": "streakline", "points": [[-0.5, 0.01], [0.5, 0.01]], "t": 0.5, "from": 0,
                  "attach": {}}}]}})",
                                 attach),
                     "straight.json");
}

TEST(StreaklineConstraints, FixTheTangentTimesTheReleaseSpeedExactly) {
  const Scene scene = straight_scene(0);
  const auto space = make_design_space(scene);
  const StreaklineConstraints c(*space, scene);
  ASSERT_EQ(c.size(), 1u);
  EXPECT_DOUBLE_EQ(c.length(0), 1.0);
  EXPECT_DOUBLE_EQ(c.speed(0), 2.0);
  const auto nv = static_cast<size_t>(space->mesh().num_vertices());
  std::vector<char> fixed(nv, 0);
  std::vector<cplx> values(nv, cplx(0, 0));
  c.constrain(0.5, fixed, values);  // the whole polyline
  int count = 0;
  for (size_t v = 0; v < nv; ++v) {
    if (!fixed[v]) continue;
    ++count;
    const Vec3& x = space->mesh().position(static_cast<int>(v));
    // The corners of the faces between the rows y = 0 and y = h, within [−0.5, 0.5] (and
    // the corners of the end faces, one column beyond).
    EXPECT_TRUE(std::abs(x.y()) < 1e-12 || std::abs(x.y() - 0.0625) < 1e-12) << x.transpose();
    EXPECT_LE(std::abs(x.x()), 0.5 + 0.0625 + 1e-12) << x.transpose();
    EXPECT_NEAR(std::abs(values[v] - cplx(2, 0)), 0, 1e-12) << x.transpose();
  }
  EXPECT_EQ(count, 2 * 17);  // x = −0.5 … 0.5 on both rows
}

TEST(StreaklineConstraints, AttachmentPullsOntoThePolylineInProportionToTheOffset) {
  const double c_attach = 3.0, h = 0.0625;
  const Scene scene = straight_scene(c_attach);
  const auto space = make_design_space(scene);
  const StreaklineConstraints c(*space, scene);
  const auto nv = static_cast<size_t>(space->mesh().num_vertices());
  std::vector<char> fixed(nv, 0);
  std::vector<cplx> values(nv, cplx(0, 0));
  c.constrain(0.5, fixed, values);
  for (size_t v = 0; v < nv; ++v) {
    if (!fixed[v]) continue;
    const double y = space->mesh().position(static_cast<int>(v)).y();
    // u·(T − c·y′·n) with T = (1, 0), n = (0, 1), y′ = y − 0.01: below the line pushed up,
    // above it pushed down.
    const cplx expected(2, -2 * c_attach * (y - 0.01));
    EXPECT_NEAR(std::abs(values[v] - expected), 0, 1e-12) << y;
    EXPECT_TRUE(std::abs(y) < 1e-12 || std::abs(y - h) < 1e-12);
  }
}

TEST(StreaklineConstraints, FollowTheDyeFrontAndOnlyWithinTheReleaseInterval) {
  const Scene scene = straight_scene(0);
  const auto space = make_design_space(scene);
  const StreaklineConstraints c(*space, scene);
  const auto nv = static_cast<size_t>(space->mesh().num_vertices());
  const double h = space->mesh().mean_edge_length(), dt = 0.05;
  // The fixed vertices' least and greatest x (−2, −2 when none is fixed).
  auto extent = [&](double t) {
    std::vector<char> fixed(nv, 0);
    std::vector<cplx> values(nv, cplx(0, 0));
    c.constrain(t, fixed, values);
    double x_min = 2, x_max = -2;
    for (size_t v = 0; v < nv; ++v)
      if (fixed[v]) {
        x_min = std::min(x_min, space->mesh().position(static_cast<int>(v)).x());
        x_max = std::max(x_max, space->mesh().position(static_cast<int>(v)).x());
      }
    return x_max < x_min ? std::pair(-2.0, -2.0) : std::pair(x_min, x_max);
  };
  auto furthest = [&](double t) { return extent(t).second; };
  // At t′ the dye covers x ≤ −0.5 + u·t′; the constraints lead it by u·Δt + 2h (and reach
  // the far corner of the face holding the last sample, one column more).
  for (double t : {0.0, 0.1, 0.2, 0.3}) {
    const double front = -0.5 + 2 * (t + dt) + 2 * h;
    EXPECT_GE(furthest(t), -0.5 + 2 * t) << t;
    EXPECT_LE(furthest(t), front + 0.0625 + 1e-12) << t;
    EXPECT_GE(furthest(t), front - 0.0625 - 1e-12) << t;
  }
  // After t the constraints let go from the seed end at 4u = 8 per unit time, counted from
  // the frame after t (which still holds the whole polyline): at 0.6 the first 0.4 of it
  // are free, from 0.7 (0.05 + 0.125 after it, 1.2 > 1) all.
  EXPECT_DOUBLE_EQ(extent(0.55).first, -0.5);
  EXPECT_GE(extent(0.6).first, -0.5 + 0.4 - 0.0625 - 1e-12);
  EXPECT_LE(extent(0.6).first, -0.5 + 0.4 + 0.0625 / 4 + 1e-12);
  EXPECT_DOUBLE_EQ(extent(0.6).second, 0.5);
  EXPECT_EQ(furthest(0.7), -2) << "free once the constraints have let go of the whole polyline";
  Scene later = scene;
  std::get<StreaklineElement>(later.elements[0]).from = 0.2;
  const StreaklineConstraints c2(*space, later);
  std::vector<char> fixed(nv, 0);
  std::vector<cplx> values(nv, cplx(0, 0));
  c2.constrain(0.15, fixed, values);
  EXPECT_EQ(std::count(fixed.begin(), fixed.end(), 1), 0) << "a frame before from (0.2, itself a frame) is free";
}

TEST(CompareStreakline, MeasuresBothWays) {
  // Two parallel segments 0.1 apart: 0.1 both ways. A traced curve that covers half the
  // sketch: the uncovered half's end is 0.5 away from it.
  const std::vector<Vec3> sketch_line{Vec3(0, 0, 0), Vec3(1, 0, 0)};
  const StreaklineMatch a = compare_streakline(sketch_line, std::vector<Vec3>{Vec3(0, 0.1, 0), Vec3(1, 0.1, 0)});
  EXPECT_NEAR(a.hausdorff, 0.1, 1e-15);
  EXPECT_NEAR(a.mean, 0.1, 1e-15);
  const StreaklineMatch b = compare_streakline(sketch_line, std::vector<Vec3>{Vec3(0, 0, 0), Vec3(0.5, 0, 0)});
  EXPECT_NEAR(b.hausdorff, 0.5, 1e-15);
  EXPECT_TRUE(std::isinf(compare_streakline(sketch_line, std::vector<Vec3>{Vec3(0, 0, 0)}).hausdorff));
}

TEST(CompareStreakline, TheFrechetDistanceWalksBothCurvesFromTheSeed) {
  // The traced dye is oldest first (trace_streakline): the oldest particle is furthest
  // along the sketch. Parallel 0.1 apart: 0.1. Covering the sketch's first half: 0.5 (the
  // sketch's end against the oldest particle). The same points youngest first: the curves
  // walked against each other, 1.
  const std::vector<Vec3> sketch_line{Vec3(0, 0, 0), Vec3(1, 0, 0)};
  EXPECT_NEAR(compare_streakline(sketch_line, std::vector<Vec3>{Vec3(1, 0.1, 0), Vec3(0, 0.1, 0)}).frechet, 0.1, 1e-12);
  EXPECT_NEAR(compare_streakline(sketch_line, std::vector<Vec3>{Vec3(0.5, 0, 0), Vec3(0, 0, 0)}).frechet, 0.5, 1e-12);
  EXPECT_NEAR(compare_streakline(sketch_line, std::vector<Vec3>{Vec3(0, 0, 0), Vec3(1, 0, 0)}).frechet, 1.0, 1e-12);
  // A sketch that goes out and comes back 0.01 beside itself, against dye that only went
  // out: Hausdorff and mean are about the gap, the Fréchet distance is the whole way back.
  const std::vector<Vec3> hairpin{Vec3(0, 0, 0), Vec3(1, 0, 0), Vec3(0, 0.01, 0)};
  const StreaklineMatch m = compare_streakline(hairpin, std::vector<Vec3>{Vec3(1, 0, 0), Vec3(0, 0, 0)});
  EXPECT_LT(m.hausdorff, 0.011);
  EXPECT_LT(m.mean, 0.011);
  EXPECT_NEAR(m.frechet, 1.0, 1e-3);
  EXPECT_TRUE(std::isinf(compare_streakline(sketch_line, std::vector<Vec3>{Vec3(0, 0, 0)}).frechet));
}

// --- what the user sees: the traced streakline against the sketch
// A curved sketch: nine points on a half circle of radius 0.55 about (−0.1, −0.5), from
// the seed (−0.65, −0.5) over the top to (0.45, −0.5); released over [0.2, 0.8]. Beside it
// a counter-clockwise centre at (0.5, 0.5), so that without the streakline the field is
// not zero.
std::vector<Vec3> sketch() {
  std::vector<Vec3> p;
  for (int k = 0; k <= 8; ++k) {
    const double a = std::numbers::pi * (1 - k / 8.0);
    p.emplace_back(-0.1 + 0.55 * std::cos(a), -0.5 + 0.55 * std::sin(a), 0.0);
  }
  return p;
}

Scene curved_scene(int n, const std::string& generator, bool with_streakline, double attach = 0) {
  json j = json::parse(R"({"tvf": 1, "domain": {"grid": {"size": [33, 33]}}, "time": {"frames": 41},
    "generator": "spacetime",
    "elements": [{"kind": "singular", "type": "ccw_center", "path": [[0.5, 0.5, 0]]}]})");
  j["domain"]["grid"]["size"] = {n, n};
  j["generator"] = generator;
  if (with_streakline) {
    json points = json::array();
    for (const Vec3& p : sketch()) points.push_back({p.x(), p.y()});
    j["elements"].push_back({{"kind", "streakline"}, {"points", points}, {"t", 0.8}, {"from", 0.2}, {"attach", attach}});
  }
  return scene_from_json(j, "curved.json");
}

TEST(SketchSelfApproach, IsTheClosestPairOfPartsThatAreNotOneStretch) {
  const double h = 0.05;
  // A U whose sides are 0.03 apart: its seed and its end.
  const std::vector<Vec3> u{Vec3(-0.5, 0, 0), Vec3(0.5, 0, 0), Vec3(0.5, 0.03, 0), Vec3(-0.5, 0.03, 0)};
  const SketchSelfApproach a = sketch_self_approach(u, h);
  EXPECT_NEAR(a.distance, 0.03, 1e-12);
  EXPECT_NEAR(a.along, 2.03, 1e-12);
  EXPECT_LT((a.a - u.front()).norm(), 1e-12);
  EXPECT_LT((a.b - u.back()).norm(), 1e-12);
  // A corner of 20° is one stretch of curve (its sides part at sin 10° > 1/8 of the way
  // along); one of 10° is two parts, 8h along and 0.7h apart.
  auto v = [](double degrees) {
    const double r = degrees * std::numbers::pi / 180;
    return std::vector<Vec3>{Vec3(-0.6, 0, 0), Vec3(0.2, 0, 0), Vec3(0.2 - 0.8 * std::cos(r), 0.8 * std::sin(r), 0)};
  };
  EXPECT_TRUE(std::isinf(sketch_self_approach(v(20), h).distance));
  const double ten = sketch_self_approach(v(10), h).distance;  // 8h sin 5° = 0.70h, to the sampling (h/4)
  EXPECT_GT(ten, 0.69 * h);
  EXPECT_LT(ten, 0.76 * h);
  EXPECT_TRUE(std::isinf(sketch_self_approach(sketch(), h).distance)) << "the half circle";
  // A closed loop (a square of side 0.5, last point on the seed) is one stretch round its
  // closing point; pinched to 0.02 across its middle, the pinch is the approach.
  const std::vector<Vec3> square{Vec3(0, 0, 0), Vec3(0.5, 0, 0), Vec3(0.5, 0.5, 0), Vec3(0, 0.5, 0), Vec3(0, 0, 0)};
  EXPECT_TRUE(std::isinf(sketch_self_approach(square, h).distance)) << sketch_self_approach(square, h).distance;
  const std::vector<Vec3> pinched{Vec3(0, 0, 0),     Vec3(0.5, 0, 0),   Vec3(0.5, 0.5, 0), Vec3(0.26, 0.5, 0),
                                  Vec3(0.26, 0.2, 0), Vec3(0.24, 0.2, 0), Vec3(0.24, 0.5, 0), Vec3(0, 0.5, 0),
                                  Vec3(0, 0, 0)};
  const SketchSelfApproach p = sketch_self_approach(pinched, h);
  EXPECT_NEAR(p.distance, 0.02, 1e-9);
  EXPECT_NEAR(p.a.x(), 0.26, 1e-9);
  EXPECT_NEAR(p.b.x(), 0.24, 1e-9);
}

struct Apart {
  bool warned = false;
  double frechet = 0;
};

// `sketch` added to the scene `j` as a streakline element (t 0.8, from 0.2, `attach`) and
// generated: whether generate warned that it comes close to itself, and the Fréchet
// distance, in mean edge lengths, of the dye traced over [0.2, 0.8] from the sketch.
Apart generate_sketch(json j, const std::vector<Vec3>& sketch, double attach) {
  json points = json::array();
  for (const Vec3& p : sketch) points.push_back({p.x(), p.y()});
  j["elements"].push_back({{"kind", "streakline"}, {"points", points}, {"t", 0.8}, {"from", 0.2}, {"attach", attach}});
  const Scene scene = scene_from_json(j, "sketch.json");
  const auto space = make_design_space(scene);
  GenerateReport report;
  const Field field = generate(*space, scene, {}, &report);
  StreaklineOptions o;
  o.t0 = 0.2;
  o.t1 = 0.8;
  const Streakline traced = trace_streakline(space->bundle(), field, sketch.front(), o);
  std::vector<Vec3> line;
  for (const StreakPoint& p : traced.points) line.push_back(p.position);
  Apart out;
  out.frechet = compare_streakline(sketch, line).frechet / space->mesh().mean_edge_length();
  for (const std::string& w : report.warnings) out.warned |= w.find("the sketch comes within") != std::string::npos;
  return out;
}

// A U on 33² (31 frames, spacetime) whose sides are `edges` mean edge lengths apart, with
// the given attach.
Apart u_sketch(double edges, double attach) {
  const json j = json::parse(R"({"tvf": 1, "domain": {"grid": {"size": [33, 33]}}, "time": {"frames": 31},
    "generator": "spacetime", "solver": {"region_radius": 0.1}, "falloff": 8,
    "elements": [{"kind": "singular", "type": "ccw_center", "path": [[0.45, 0.55, 0]]}]})");
  const double h = make_grid(GridSpec{33, 33, {-1, -1}, {1, 1}}).mean_edge_length(), d = edges * h;
  return generate_sketch(
      j, {Vec3(-0.5, -0.5, 0), Vec3(0.5, -0.5, 0), Vec3(0.5, -0.5 + d, 0), Vec3(-0.5, -0.5 + d, 0)}, attach);
}

TEST(StreaklineDesign, ASketchWhosePartsComeTooCloseIsWarnedOfAndIsNotFollowed) {
  // Measured (kSketchApartEdges): with attach 20 at 0.75 edge lengths apart the dye is 10
  // off, at 1.25 0.7; without attach at 1 edge 4.7 off, at 6 1.9.
  const struct {
    double edges, attach;
    bool warned;
  } cases[] = {{0.75, 20, true}, {1.25, 20, false}, {1.0, 0, true}, {6.0, 0, false}};
  for (const auto& c : cases) {
    const Apart a = u_sketch(c.edges, c.attach);
    SCOPED_TRACE(fmt::format("{} edge lengths apart, attach {}: Fréchet {:.2f} edge lengths", c.edges, c.attach,
                             a.frechet));
    EXPECT_EQ(a.warned, c.warned);
    if (c.warned)
      EXPECT_GT(a.frechet, 3.0);
    else
      EXPECT_LT(a.frechet, 2.5);
  }
}

TEST(StreaklineDesign, AClosedLoopIsNotWarnedOfWhereItCloses) {
  // A loop sketched round a centre, its last point on the seed (the readers take it): the
  // seed and the oldest dye beside it are one stretch of curve, not two parts that come
  // close, so generate does not warn (it said "comes within 0 mean edge lengths of itself"
  // of every closed loop); the dye traced in the field follows the loop.
  const json j = json::parse(R"({"tvf": 1, "domain": {"grid": {"size": [33, 33]}}, "time": {"frames": 21},
    "generator": "spacetime", "falloff": 4,
    "elements": [{"kind": "singular", "type": "ccw_center", "path": [[0, 0, 0]]}]})");
  std::vector<Vec3> loop;
  for (int k = 0; k <= 24; ++k) {
    const double a = 2 * std::numbers::pi * (k % 24) / 24;
    loop.emplace_back(0.5 * std::cos(a), 0.5 * std::sin(a), 0);
  }
  const Apart a = generate_sketch(j, loop, 20);
  EXPECT_FALSE(a.warned);
  EXPECT_LT(a.frechet, 2) << "Fréchet " << a.frechet << " edge lengths";
}

struct Match {
  double hausdorff = 0, mean = 0, frechet = 0;  // world units
  int points = 0, left = 0;
};

// The streakline traced in the generated field from the sketch's seed over [0.2, 0.8]
// against the sketch (compare_streakline: distances both ways).
Match compare(const Scene& scene) {
  const auto space = make_design_space(scene);
  const Field field = generate(*space, scene);
  StreaklineOptions o;
  o.t0 = 0.2;
  o.t1 = 0.8;
  const Streakline traced = trace_streakline(space->bundle(), field, sketch().front(), o);
  std::vector<Vec3> line;
  for (const StreakPoint& p : traced.points) line.push_back(p.position);
  Match m;
  m.points = static_cast<int>(line.size());
  m.left = traced.left;
  const StreaklineMatch d = compare_streakline(sketch(), line);
  m.hausdorff = d.hausdorff;
  m.mean = d.mean;
  m.frechet = d.frechet;
  return m;
}

TEST(StreaklineDesign, TheTracedStreaklineLiesOnTheSketchAt33And65) {
  for (int n : {33, 65}) {
    const double h = 2.0 / (n - 1);
    const Match m = compare(curved_scene(n, "spacetime", true));
    SCOPED_TRACE(fmt::format("{}²: Hausdorff {:.4f} ({:.2f} h), mean {:.4f} ({:.2f} h), {} points, {} left", n,
                             m.hausdorff, m.hausdorff / h, m.mean, m.mean / h, m.points, m.left));
    // Within one edge length (mean within a quarter): the constraints sit at the corners of
    // the faces the sketch crosses and the field between them is interpolated linearly
    // (measured: 0.26 h at 33²); at the sketch's 22.5° corners the tangent turns over
    // u·Δt + h on either side, which cuts them by about ρ·θ/4 ≈ 0.01 (0.16 h at 33², 0.3 h
    // at 65²). The release and the dye front are exact in time.
    EXPECT_LT(m.hausdorff, 1.0 * h);
    EXPECT_LT(m.mean, 0.25 * h);
    // In order too: the dye released at each time lies along the sketch from the seed.
    EXPECT_LT(m.frechet, 1.0 * h);
    EXPECT_EQ(m.left, 0);
  }
}

TEST(StreaklineDesign, TheFieldChangesSmoothlyFromFrameToFrame) {
  // Requirement 1 (temporal coherence): y_i = Σ_k ‖V_k(t_{i+1}) − V_k(t_i)‖ changes by less
  // than 1 from one frame to the next, across the release's start (t = 0.2), as the dye
  // front passes each corner of the sketch, and after t = 0.8 (measured: 0.66 at most, the
  // series itself up to 2.25). With the polyline's own tangents the front switched each
  // corner's constraint on at once: y jumped from 1.9 to 3.8 and back every third frame.
  const Scene scene = curved_scene(33, "spacetime", true);
  const auto space = make_design_space(scene);
  const std::vector<double> y = coherence(generate(*space, scene));
  ASSERT_EQ(y.size(), 40u);
  double worst = 0;
  for (size_t i = 1; i < y.size(); ++i) worst = std::max(worst, std::abs(y[i] - y[i - 1]));
  EXPECT_LT(worst, 1.0);
  EXPECT_GT(*std::max_element(y.begin(), y.end()), 1.0) << "the field does change";
}

TEST(StreaklineDesign, WithoutTheStreaklineTheTracedDyeIsNowhereNearTheSketch) {
  // The same measure discriminates: the centre's field alone carries the dye elsewhere.
  const Match m = compare(curved_scene(33, "spacetime", false));
  EXPECT_GT(m.hausdorff, 0.3);
}

TEST(StreaklineDesign, ThePerFrameConstrainedGeneratorReproducesItToo) {
  const double h = 2.0 / 32;
  const Match m = compare(curved_scene(33, "constrained", true));
  EXPECT_LT(m.hausdorff, 1.0 * h) << m.hausdorff / h;
}

TEST(StreaklineDesign, TheBasisGeneratorWarnsThatItLeavesTheStreaklineOut) {
  const auto warnings = design_warnings(curved_scene(33, "basis", true));
  ASSERT_EQ(warnings.size(), 1u);
  EXPECT_NE(warnings[0].find("elements[1]: a streakline is reproduced by the constrained and spacetime generators only"),
            std::string::npos)
      << warnings[0];
}

// On a surface (the designer's Streakline tool draws on meshes too): an S-shaped sketch on
// the unit sphere's front, nine points of (x, −1, z) normalised, x from −0.6 to 0.6,
// z = 0.2 + 0.25 sin 2πu, released over [0.2, 0.8], beside a centre at the north. The
// traced dye lies on it as on the plane (measured: Hausdorff 0.31 h, mean 0.08 h, h the
// mean edge length ≈ 0.075 at 4 subdivisions); without it, far off.
std::vector<Vec3> sphere_sketch() {
  std::vector<Vec3> p;
  for (int k = 0; k <= 8; ++k) {
    const double u = k / 8.0;
    p.push_back(Vec3(-0.6 + 1.2 * u, -1, 0.2 + 0.25 * std::sin(2 * std::numbers::pi * u)).normalized());
  }
  return p;
}

Match compare_on_sphere(bool with_streakline, double* h) {
  json j = json::parse(R"({"tvf": 1, "domain": {"sphere": {"subdivisions": 4}}, "time": {"frames": 41},
    "generator": "spacetime", "solver": {"region_radius": 0.1}, "falloff": 8,
    "elements": [{"kind": "singular", "type": "ccw_center", "path": [[0, 0, 1, 0]]}]})");
  if (with_streakline) {
    json points = json::array();
    for (const Vec3& p : sphere_sketch()) points.push_back({p.x(), p.y(), p.z()});
    j["elements"].push_back({{"kind", "streakline"}, {"points", points}, {"t", 0.8}, {"from", 0.2}});
  }
  const Scene scene = scene_from_json(j, "sphere.json");
  const auto space = make_design_space(scene);
  *h = space->mesh().mean_edge_length();
  const Field field = generate(*space, scene);
  StreaklineOptions o;
  o.t0 = 0.2;
  o.t1 = 0.8;
  const Streakline traced = trace_streakline(space->bundle(), field, sphere_sketch().front(), o);
  std::vector<Vec3> line;
  for (const StreakPoint& p : traced.points) line.push_back(p.position);
  const StreaklineMatch d = compare_streakline(sphere_sketch(), line);
  return {d.hausdorff, d.mean, d.frechet, static_cast<int>(line.size()), traced.left};
}

TEST(StreaklineDesign, OnTheSphereTheTracedStreaklineLiesOnTheSketch) {
  double h = 0;
  const Match m = compare_on_sphere(true, &h);
  SCOPED_TRACE(fmt::format("sphere: Hausdorff {:.4f} ({:.2f} h), mean {:.4f} ({:.2f} h), {} points", m.hausdorff,
                           m.hausdorff / h, m.mean, m.mean / h, m.points));
  EXPECT_LT(m.hausdorff, 1.0 * h);
  EXPECT_LT(m.mean, 0.25 * h);
  EXPECT_LT(m.frechet, 1.0 * h);
  EXPECT_EQ(m.left, 0);
  const Match free = compare_on_sphere(false, &h);
  EXPECT_GT(free.hausdorff, 0.3) << "without the streakline the dye goes elsewhere";
}

TEST(StreaklineDesign, OnASurfaceASketchThatMeetsItselfIsRefused) {
  // On the sphere (subdivisions 4) the reader cannot test a sketch (it is known only once
  // snapped onto the surface): generate refuses one that crosses itself, or folds back along
  // itself, with the JSON place and the two segments, and takes a sharp V, a closed loop and
  // a path that passes the other side of the sphere (close in space through the inside, far
  // over the surface).
  auto sketch_scene = [](const std::vector<Vec3>& sketch) {
    json j = json::parse(R"({"tvf": 1, "domain": {"sphere": {"subdivisions": 4}}, "time": {"frames": 5},
      "generator": "constrained", "elements": [{"kind": "singular", "type": "ccw_center", "path": [[0, 0, 1, 0]]}]})");
    json points = json::array();
    for (const Vec3& p : sketch) points.push_back({p.x(), p.y(), p.z()});
    j["elements"].push_back({{"kind", "streakline"}, {"points", points}, {"t", 0.8}, {"from", 0.2}});
    return scene_from_json(j, "sphere.json");
  };
  // Points on the unit sphere by longitude and latitude (degrees).
  auto at = [](double lon, double lat) {
    const double a = lon * std::numbers::pi / 180, b = lat * std::numbers::pi / 180;
    return Vec3(std::cos(b) * std::cos(a), std::cos(b) * std::sin(a), std::sin(b));
  };
  const Scene crossing = sketch_scene({at(0, 0), at(40, 30), at(40, 0), at(0, 30)});  
  const auto space = make_design_space(crossing);
  auto refusal = [&](const Scene& scene) {
    try {
      generate(*space, scene);
    } catch (const Error& e) {
      return std::string(e.what());
    }
    return std::string();
  };
  // The segments 0 (0,0)→(40,30) and 2 (40,0)→(0,30) cross.
  EXPECT_EQ(refusal(crossing),
            "scene: elements[1].points: the sketch crosses or folds back onto itself on the surface (its "
            "segments from points[0] and points[2]): two parts of the dye cannot be at one point at t; sketch a "
            "streakline that does not meet itself");
  const std::string folds = refusal(sketch_scene({at(0, 0), at(40, 0), at(20, 0)}));  // along the equator
  EXPECT_NE(folds.find("(its segments from points[0] and points[1])"), std::string::npos) << folds;
  const std::string touches = refusal(sketch_scene({at(0, 0), at(40, 0), at(40, 30), at(20, 0)}));  // ends on segment 0
  EXPECT_NE(touches.find("(its segments from points[0] and points[2])"), std::string::npos) << touches;
  EXPECT_EQ(refusal(sketch_scene({at(0, 0), at(40, 30), at(41, 0)})), "");            // a sharp V
  EXPECT_EQ(refusal(sketch_scene({at(0, 0), at(40, 0), at(20, 30), at(0, 0)})), "");  // a closed loop
  EXPECT_EQ(refusal(sketch_scene({at(0, 20), at(90, 20), at(180, 20), at(270, 20), at(355, 20)})), "");  // round
  EXPECT_EQ(refusal(sketch_scene({at(0, 0), at(0, 60), at(180, 60), at(180, 0)})), "");  // over the pole and down
}

// The unit cube [0, 1]³, 4 × 4 squares a face, written as an OFF file in `dir`.
std::string unit_cube(const test::TempDir& dir) {
  std::vector<Vec3> positions;
  std::vector<Face> faces;
  std::map<std::array<int, 3>, int> index;  // vertices by their coordinates in quarters
  auto vertex = [&](std::array<int, 3> q) {
    const auto [it, added] = index.try_emplace(q, static_cast<int>(positions.size()));
    if (added) positions.emplace_back(q[0] / 4.0, q[1] / 4.0, q[2] / 4.0);
    return it->second;
  };
  for (int axis = 0; axis < 3; ++axis)
    for (int side = 0; side <= 1; ++side)
      for (int i = 0; i < 4; ++i)
        for (int j = 0; j < 4; ++j) {
          auto at = [&](int a, int b) {
            std::array<int, 3> q{};
            q[axis] = 4 * side, q[(axis + 1) % 3] = a, q[(axis + 2) % 3] = b;
            return vertex(q);
          };
          const int v00 = at(i, j), v10 = at(i + 1, j), v11 = at(i + 1, j + 1), v01 = at(i, j + 1);
          if (side == 1)
            faces.push_back({v00, v10, v11}), faces.push_back({v00, v11, v01});
          else
            faces.push_back({v00, v11, v10}), faces.push_back({v00, v01, v11});
        }
  const std::string path = (dir / "cube.off").string();
  save_mesh(Mesh(positions, faces), path);
  return path;
}

// What generate says of a streakline sketched on the cube ("" when it generates).
std::string cube_sketch_refusal(const std::string& cube, const std::vector<Vec3>& sketch) {
  json j = {{"tvf", 1}, {"domain", {{"mesh", cube}}}, {"time", {{"frames", 5}}}, {"generator", "constrained"},
            {"elements", json::array({{{"kind", "singular"}, {"type", "ccw_center"}, {"path", {{0.5, 0.5, 0, 0}}}}})}};
  json points = json::array();
  for (const Vec3& p : sketch) points.push_back({p.x(), p.y(), p.z()});
  j["elements"].push_back({{"kind", "streakline"}, {"points", points}, {"t", 0.8}, {"from", 0.2}});
  const Scene scene = scene_from_json(j, "cube.json");
  const auto space = make_design_space(scene);
  try {
    generate(*space, scene);
  } catch (const Error& e) {
    return e.what();
  }
  return "";
}

TEST(StreaklineDesign, OnASurfaceASketchRoundACreaseIsNotAFold) {
  // A sketch off the cube (within a quarter of its diagonal: nearer is moved onto it, farther
  // refused) whose points snap onto an edge or a corner and then go on over the next face is
  // a simple path on the surface. Seen folded (and refused) before: the turn at
  // a crease tested in one face's plane (round the corner), and pieces a hair long where the
  // sketch's points snap onto nearly one point of an edge (the two pieces either side then
  // touched).
  const test::TempDir dir;
  const std::string cube = unit_cube(dir);
  // Up the face x = 1 along its diagonal to the corner (1, 1, 1), then down the edge
  // x = y = 1 and over the face y = 1: a 135° turn on the surface.
  EXPECT_EQ(cube_sketch_refusal(cube, {{1, 0.5, 0.5}, {1.1, 1.1, 1.1}, {1.15, 1.125, 1.1}, {0.5, 1, 0.5}}), "");
  // Along z = 0.6 over the edge x = y = 1; the middle segment's points all snap to within
  // 1e-7 of (1, 1, 0.6).
  EXPECT_EQ(cube_sketch_refusal(cube, {{1, 0.5, 0.6}, {1.2, 1.2, 0.6}, {1.3, 1.1, 0.6000001}, {0.5, 1, 0.6}}), "");
  // A real fold: up the edge x = y = 1 to z = 0.8 and back down it.
  const std::string folds = cube_sketch_refusal(cube, {{1, 0.5, 0.6}, {1.2, 1.1, 0.8}, {1.1, 1.2, 0.8}, {0.5, 1, 0.6}});
  EXPECT_NE(folds.find("crosses or folds back onto itself on the surface"), std::string::npos) << folds;
}

TEST(StreaklineDesign, OnASurfaceASketchOfNoLengthIsRefused) {
  // Points off the cube's corner (1, 1, 1), in the cone of directions that snap onto it: the
  // sketch has no length on the surface, as a planar sketch of equal points (which the
  // reader refuses).
  const test::TempDir dir;
  EXPECT_EQ(cube_sketch_refusal(unit_cube(dir), {{1.1, 1.1, 1.1}, {1.15, 1.125, 1.1}, {1.125, 1.15, 1.1}}),
            "scene: elements[1].points: must have a length > 0 on the surface (its points all land on one "
            "point of it)");
}

}  // namespace
}  // namespace tvf
