// The planar applications of §9: painterly animation (strokes carried by pathlines inside
// a mask, shaped along streamlines, coverage kept even), crowd steering (fast marching
// distances, agents reaching goals around obstacles), and particles with self-spin
// (constant angle to the advection direction).
#include "tvf/render/crowd.h"
#include "tvf/render/painterly.h"
#include "tvf/render/particles.h"

#include "support/test_paths.h"
#include "tvf/core/error.h"
#include "tvf/core/error_location.h"
#include "tvf/field/field_sampler.h"
#include "tvf/field/point_locator.h"
#include "tvf/integrate/pathline.h"
#include "tvf/mesh/grid.h"

#include <gtest/gtest.h>
#include <nlohmann/json.hpp>

#include <algorithm>
#include <cmath>
#include <limits>

namespace tvf {
namespace {

template <class F>
Field sample(const Mesh& mesh, TimeSampling ts, F&& f) {
  Field field(ts, mesh.num_vertices());
  for (int j = 0; j < ts.frames; ++j)
    for (int v = 0; v < mesh.num_vertices(); ++v)
      field.at(j, v) = f(cplx(mesh.position(v).x(), mesh.position(v).y()), ts.time(j));
  return field;
}

// A picture with a horizontal colour ramp (red grows to the right) and vertical stripes of
// blue, so that every pixel's colour tells where it is.
Image ramp(int w, int h) {
  Image img(w, h);
  for (int y = 0; y < h; ++y)
    for (int x = 0; x < w; ++x)
      img.at(x, y) = rgb(static_cast<std::uint8_t>(255 * x / (w - 1)), static_cast<std::uint8_t>(255 * y / (h - 1)),
                         static_cast<std::uint8_t>((x / 8) % 2 ? 200 : 40));
  return img;
}

// --- Fast marching and crowds -------------------------------------------------------------

TEST(FastMarching, EmptyGridGivesEuclideanDistanceToFirstOrder) {
  // A point source in the middle of an empty grid: φ approaches the distance r, first-order
  // in h (the upwind scheme overestimates off the axes, most on the diagonals), and the
  // error shrinks as the grid is refined.
  double previous = std::numeric_limits<double>::infinity();
  for (int n : {41, 81, 161}) {
    const double h = 2.0 / (n - 1);
    const int c = n / 2;
    std::vector<double> cost(static_cast<size_t>(n * n), 1.0);
    std::vector<char> source(static_cast<size_t>(n * n), 0);
    source[static_cast<size_t>(c * n + c)] = 1;
    const auto phi = fast_marching(n, n, h, cost, source);
    double worst = 0, worst_axis = 0;
    for (int j = 0; j < n; ++j)
      for (int i = 0; i < n; ++i) {
        const double r = h * std::hypot(i - c, j - c);
        const double e = phi[static_cast<size_t>(j * n + i)] - r;
        EXPECT_GE(e, -1e-12) << "fast marching never undercuts the distance";
        worst = std::max(worst, std::abs(e));
        if (i == c || j == c) worst_axis = std::max(worst_axis, std::abs(e));
      }
    EXPECT_LT(worst_axis, 1e-12) << "exact along the grid axes";
    // First-order with a point source: the error grows like h·log(r/h) (the source's
    // kink); here bounded by h·(1 + ln(r_max/h)), r_max = √2 (0.051, 0.031, 0.018 measured
    // for h = 0.05, 0.025, 0.0125), and it falls by at least a quarter each time h halves.
    const double r_max = std::sqrt(2.0);
    EXPECT_LT(worst, h * (1 + std::log(r_max / h))) << n;
    EXPECT_LT(worst, 0.75 * previous) << "refining the grid reduces the error";
    previous = worst;
  }
}

TEST(FastMarching, PlaneWaveIsExactAndObstaclesBlock) {
  const int n = 30;
  const double h = 0.1;
  std::vector<double> cost(n * n, 1.0);
  std::vector<char> source(n * n, 0);
  for (int j = 0; j < n; ++j) source[static_cast<size_t>(j * n)] = 1;  // the column x = 0
  // A wall across the grid at column 10 with a gap in rows 0..2.
  for (int j = 3; j < n; ++j) cost[static_cast<size_t>(j * n + 10)] = std::numeric_limits<double>::infinity();
  const auto phi = fast_marching(n, n, h, cost, source);
  for (int j = 0; j < n; ++j)
    for (int i = 0; i < 10; ++i) EXPECT_NEAR(phi[static_cast<size_t>(j * n + i)], i * h, 1e-12);
  EXPECT_TRUE(std::isinf(phi[static_cast<size_t>(20 * n + 10)]));
  // Behind the wall the way goes round through the gap: longer than straight across.
  EXPECT_GT(phi[static_cast<size_t>(25 * n + 12)], 12 * h + 15 * h);
}

TEST(Crowd, WithoutTheFieldAgentsReachTheGoalAroundAnObstacle) {
  const Mesh grid = make_grid(GridSpec{33, 33, {-1, -1}, {1, 1}});
  const TangentBundle bundle(grid);
  // A field that would push everyone upwards: with ω_F = 0 it must not matter.
  const Field field = sample(grid, TimeSampling{0, 1, 41}, [](cplx, double) { return cplx(0, 1); });
  CrowdSpec spec;
  spec.agents = 30;
  spec.weight_goal = 1;
  spec.weight_field = 0;
  spec.speed = 4;
  spec.starts = {CrowdShape::rectangle({-0.95, -0.3}, {-0.75, 0.3})};
  spec.goals = {CrowdShape::rectangle({0.75, -0.3}, {0.95, 0.3})};
  const CrowdShape wall = CrowdShape::circle({0, 0}, 0.4);
  spec.obstacles = {wall};
  const CrowdResult r = simulate_crowd(bundle, field, spec);
  ASSERT_EQ(r.positions.size(), 30u);
  double max_detour = 0;
  for (size_t a = 0; a < r.positions.size(); ++a) {
    EXPECT_GE(r.arrived[a], 0) << "agent " << a << " did not reach the goal; it ended at " << r.positions[a].back().transpose();
    for (const Vec2& p : r.positions[a]) {
      EXPECT_GT(wall.distance(p), 0) << "agent " << a << " entered the obstacle at " << p.transpose();
      max_detour = std::max(max_detour, std::abs(p.y()));
    }
    EXPECT_TRUE(spec.goals[0].contains(r.positions[a].back()));
  }
  EXPECT_GT(max_detour, 0.4) << "agents went round the obstacle";
  EXPECT_EQ(r.contacts, 0) << "G alone steers clear of the obstacle (no step had to be pushed out)";
  // The potential is the travel time: at the start it exceeds the straight distance to
  // the goal (the obstacle is in the way).
  const double h = r.h;
  const int i = static_cast<int>(std::lround((-0.85 + 1) / h)), j = static_cast<int>(std::lround((0 + 1) / h));
  EXPECT_GT(r.potential[static_cast<size_t>(j * r.nx + i)], 1.6 + 0.05);
}

TEST(Crowd, WithoutTheGoalTermAgentsFollowTheReferencePathlines) {
  const Mesh grid = make_grid(GridSpec{17, 17, {-1, -1}, {1, 1}});
  const TangentBundle bundle(grid);
  const Field field = sample(grid, TimeSampling{0, 1, 11}, [](cplx, double t) { return cplx(0.3, 0.5 + 0.4 * t); });
  CrowdSpec spec;
  spec.agents = 5;
  spec.weight_goal = 0;
  spec.weight_field = 1;
  spec.starts = {CrowdShape::rectangle({-0.5, -0.9}, {0.0, -0.7})};
  spec.goals = {CrowdShape::rectangle({-1, 0.9}, {1, 1})};
  const CrowdResult r = simulate_crowd(bundle, field, spec);
  for (size_t a = 0; a < r.positions.size(); ++a) {
    const Vec2 d = r.positions[a].back() - r.positions[a].front();
    // ∫ F dt over [0, 1]: (0.3, 0.5 + 0.2); the field is linear in t, which the midpoint rule integrates exactly.
    EXPECT_NEAR(d.x(), 0.3, 1e-9);
    EXPECT_NEAR(d.y(), 0.7, 1e-9);
    EXPECT_LT((r.reference[a].back() - r.positions[a].back()).norm(), 1e-9) << "on the reference pathline";
  }
}

// A dense crowd through a gap: 60 agents of separation 0.08 (their start box holds them
// only a little apart), a wall with one opening between them and the goal.
CrowdSpec dense_crowd(double separation) {
  CrowdSpec spec;
  spec.agents = 60;
  spec.weight_goal = 1;
  spec.weight_field = 0;
  spec.speed = 3;
  spec.separation = separation;
  spec.starts = {CrowdShape::rectangle({-0.95, -0.5}, {-0.4, 0.5})};
  spec.goals = {CrowdShape::rectangle({0.7, -0.4}, {0.95, 0.4})};
  spec.obstacles = {CrowdShape::rectangle({-0.05, -1.0}, {0.05, -0.15}), CrowdShape::rectangle({-0.05, 0.15}, {0.05, 1.0})};
  return spec;
}

// Least distance between two agents that are both still on their way, over all pictures.
double least_distance(const CrowdResult& r) {
  double least = std::numeric_limits<double>::infinity();
  for (size_t k = 0; k < r.times.size(); ++k)
    for (size_t a = 0; a < r.positions.size(); ++a)
      for (size_t b = a + 1; b < r.positions.size(); ++b) {
        auto on_way = [&](size_t i) { return r.arrived[i] < 0 || static_cast<size_t>(r.arrived[i]) > k; };
        if (on_way(a) && on_way(b)) least = std::min(least, (r.positions[a][k] - r.positions[b][k]).norm());
      }
  return least;
}

// Whether the segment from a to b enters the inside of rectangle o (its boundary is
// allowed: agents slide along walls): Liang–Barsky clipping against the rectangle shrunk
// by a small margin.
bool segment_enters(const CrowdShape& o, const Vec2& a, const Vec2& b) {
  const double eps = 1e-7;
  const Vec2 lo = o.min.array() + eps, hi = o.max.array() - eps;
  double t0 = 0, t1 = 1;
  const Vec2 d = b - a;
  for (int i = 0; i < 2; ++i) {
    if (d[i] == 0) {
      if (a[i] <= lo[i] || a[i] >= hi[i]) return false;
      continue;
    }
    double ta = (lo[i] - a[i]) / d[i], tb = (hi[i] - a[i]) / d[i];
    if (ta > tb) std::swap(ta, tb);
    t0 = std::max(t0, ta);
    t1 = std::min(t1, tb);
    if (t0 >= t1) return false;
  }
  return true;
}

// Steps (one per picture, steps_per_frame = 1) whose straight segment enters an obstacle:
// a jump through a wall, a slide along the domain's edge under a wall that meets it, or a
// corner cut.
int steps_through_obstacles(const CrowdResult& r, const std::vector<CrowdShape>& obstacles) {
  int through = 0;
  for (const auto& path : r.positions)
    for (size_t k = 1; k < path.size(); ++k)
      for (const auto& o : obstacles) through += segment_enters(o, path[k - 1], path[k]);
  return through;
}

// Issue 16: with avoidance the separation push made steps long enough to jump the 0.1-thick
// wall (8 steps through it), and an agent pushed onto the domain's edge walked along it
// under a wall that meets the edge. Two rectangles from the domain's edges leave a gap;
// every step, after the push, the clamping to the domain and the separation, is checked
// against the obstacles along its whole length.
TEST(Crowd, NoStepPassesThroughAnObstacle) {
  const Mesh grid = make_grid(GridSpec{49, 49, {-1, -1}, {1, 1}});
  const TangentBundle bundle(grid);
  const Field field = sample(grid, TimeSampling{0, 1, 41}, [](cplx, double) { return cplx(2, 0); });
  const Field up = sample(grid, TimeSampling{0, 1, 41}, [](cplx, double) { return cplx(1.5, 1.5); });
  for (const Field* f : {&field, &up})
    for (const double sep : {0.0, 0.05, 0.08}) {
      CrowdSpec spec = dense_crowd(sep);
      spec.weight_goal = 0.5;
      spec.weight_field = 0.5;
      spec.steps_per_frame = 1;
      spec.avoidance_weight = 4;
      ASSERT_EQ(spec.obstacles.size(), 2u);
      EXPECT_EQ(spec.obstacles[0].min.y(), -1.0);  // both walls meet the domain's edge
      EXPECT_EQ(spec.obstacles[1].max.y(), 1.0);
      const CrowdResult r = simulate_crowd(bundle, *f, spec);
      EXPECT_EQ(steps_through_obstacles(r, spec.obstacles), 0) << "separation " << sep << (f == &up ? " (field up)" : "");
      // Not a crowd that simply stands still: some agents got through the gap.
      long past = 0;
      for (const auto& path : r.positions) past += path.back().x() > 0.05;
      EXPECT_GT(past, 0) << "separation " << sep;
    }
}

TEST(Crowd, AvoidingAgentsKeepTheirDistanceAndStillReachTheGoal) {
  const Mesh grid = make_grid(GridSpec{33, 33, {-1, -1}, {1, 1}});
  const TangentBundle bundle(grid);
  const Field field = sample(grid, TimeSampling{0, 1.5, 91}, [](cplx, double) { return cplx(0, 1); });
  const double sep = 0.08;
  // Without avoidance the crowd squeezes through the gap: agents come much closer.
  const CrowdResult free = simulate_crowd(bundle, field, dense_crowd(0));
  EXPECT_LT(least_distance(free), 0.5 * sep);
  const CrowdResult r = simulate_crowd(bundle, field, dense_crowd(sep));
  EXPECT_GE(least_distance(r), sep * (1 - 1e-6));
  for (size_t a = 0; a < r.positions.size(); ++a) {
    EXPECT_GE(r.arrived[a], 0) << "agent " << a << " did not reach the goal; it ended at " << r.positions[a].back().transpose();
    for (const Vec2& p : r.positions[a])
      for (const auto& o : dense_crowd(sep).obstacles) EXPECT_GE(o.distance(p), 0) << "agent " << a << " at " << p.transpose();
  }
  // Avoidance makes them queue: the last arrival comes later than without it.
  EXPECT_GT(*std::max_element(r.arrived.begin(), r.arrived.end()),
            *std::max_element(free.arrived.begin(), free.arrived.end()));
  // A start box too small for the agents at that distance is an error naming it.
  CrowdSpec tight = dense_crowd(0.5);
  std::string msg;
  try {
    simulate_crowd(bundle, field, tight);
  } catch (const Error& e) {
    msg = e.what();
  }
  EXPECT_NE(msg.find("avoidance.distance"), std::string::npos) << msg;
}

TEST(Crowd, ExampleCrowdFilesRead) {
  const CrowdSpec plain = load_crowd_spec(test::source_dir() + "/examples/13_crowd/crowd.json");
  EXPECT_EQ(plain.separation, 0.0);
  const CrowdSpec dense = load_crowd_spec(test::source_dir() + "/examples/13_crowd/crowd_dense.json");
  EXPECT_EQ(dense.agents, 120);
  EXPECT_DOUBLE_EQ(dense.separation, 0.045);
  EXPECT_DOUBLE_EQ(dense.avoidance_weight, 1.0);
}

TEST(Crowd, BadCrowdFilesNameTheJsonPath) {
  auto message = [](const char* text) {
    try {
      parse_crowd_spec(nlohmann::json::parse(text), "c.json");
    } catch (const Error& e) {
      return std::string(e.what());
    }
    return std::string("no error");
  };
  EXPECT_NE(message(R"({"start": [], "goals": [], "agnets": 3})").find("agnets"), std::string::npos);
  EXPECT_NE(message(R"({"start": [{"circle": {"center": [0, 0], "radius": -1}}], "goals": []})")
                .find("start[0].circle.radius"),
            std::string::npos);
  EXPECT_NE(message(R"({"start": [{"circle": {"center": [0, 0], "radius": 1}}], "goals": [{"square": 1}]})")
                .find("goals[0]"),
            std::string::npos);
  EXPECT_NE(message(R"({"goals": []})").find("c.json: start"), std::string::npos);
  EXPECT_NE(message(R"({"start": [{"circle": {"center": [0, 0], "radius": 1}}], "goals": [{"circle": {"center": [0, 0], "radius": 1}}], "avoidance": {"distance": -1}})")
                .find("avoidance.distance"),
            std::string::npos);
  EXPECT_NE(message(R"({"start": [{"circle": {"center": [0, 0], "radius": 1}}], "goals": [{"circle": {"center": [0, 0], "radius": 1}}], "avoidance": {"weight": 1}})")
                .find("avoidance"),
            std::string::npos);
}

// A crowd file is read as a scene is (core/json_text.h): each error names the file, the
// JSON path, the line and the column, in the sentence and in the location fields.
TEST(Crowd, BadCrowdFilesNameLineAndColumn) {
  test::TempDir dir;
  auto located = [&](const std::string& text) {
    test::write_text(dir / "c.json", text);
    try {
      load_crowd_spec((dir / "c.json").string());
    } catch (const LocatedError& e) {
      return std::make_pair(std::string(e.what()), e.location());
    }
    return std::make_pair(std::string("no error"), ErrorLocation{});
  };
  const std::string file = (dir / "c.json").string();
  const std::string shapes = R"("start": [{"circle": {"center": [0, 0], "radius": 1}}],)"
                             "\n"
                             R"( "goals": [{"circle": {"center": [1, 1], "radius": 1}}])";
  // A typo'd key: the key's value on line 2, column 12.
  auto [typo, at_typo] = located("{" + shapes + ",\n \"agnets\": 3}");
  EXPECT_EQ(typo, file + ": agnets (line 3, column 12): unknown key") << typo;
  EXPECT_EQ(at_typo.file, file);
  EXPECT_EQ(at_typo.json_path, "agnets");
  EXPECT_EQ(at_typo.line, 3);
  EXPECT_EQ(at_typo.column, 12);
  // A wrong type deep inside: goals[0].circle.radius is a string.
  auto [type, at_type] = located(R"({"start": [{"circle": {"center": [0, 0], "radius": 1}}],)"
                                 "\n"
                                 R"( "goals": [{"circle": {"center": [1, 1], "radius": "big"}}]})");
  EXPECT_EQ(type, file + ": goals[0].circle.radius (line 2, column 52): expected a number") << type;
  EXPECT_EQ(at_type.json_path, "goals[0].circle.radius");
  EXPECT_EQ(at_type.line, 2);
  EXPECT_EQ(at_type.column, 52);
  // Broken JSON: the reader's own line and column.
  auto [broken, at_broken] = located("{" + shapes + ",\n \"agents\": 3,\n}");
  EXPECT_EQ(at_broken.file, file);
  EXPECT_EQ(at_broken.line, 4);
  EXPECT_EQ(at_broken.column, 1);
  EXPECT_EQ(broken.rfind(file + ": line 4, column 1: ", 0), 0u) << broken;
  // A value without a JSON path (the whole file is not an object) says so plainly.
  auto [array, at_array] = located("[1, 2]");
  EXPECT_EQ(array.rfind(file + ": expected an object", 0), 0u) << array;
  EXPECT_EQ(at_array.line, 0);
}

// --- Particles ------------------------------------------------------------------------------

TEST(Particles, AngleToTheAdvectionDirectionStaysConstant) {
  const Mesh grid = make_grid(GridSpec{33, 33, {-1, -1}, {1, 1}});
  const TangentBundle bundle(grid);
  // A rotating flow whose centre drifts: the advection direction turns along every path.
  const Field field = sample(grid, TimeSampling{0, 1, 21}, [](cplx z, double t) {
    const cplx c(-0.2 + 0.4 * t, 0.1);
    return cplx(0, 1) * (z - c) + cplx(0.3, 0);
  });
  ParticleOptions o;
  o.count = 300;
  o.image_size = 64;
  ParticleSystem system(bundle, field, o);
  const FieldSampler sampler(bundle, field);
  system.advance(0);
  std::vector<Particle> before = system.particles();
  double turned = 0;
  for (int k = 1; k <= 10; ++k) {
    const double t = 0.1 * k;
    system.advance(t);
    const auto& now = system.particles();
    for (size_t i = 0; i < now.size(); ++i) {
      const Particle& p = now[i];
      const Vec2 v = sampler.world(p.where, t).head<2>();
      ASSERT_GT(v.norm(), 1e-6);
      const Vec2 d = v.normalized();
      // Signed angle from the advection direction to up.
      const double angle = std::atan2(d.x() * p.up.y() - d.y() * p.up.x(), d.dot(p.up));
      EXPECT_NEAR(std::remainder(angle - p.angle, 2 * kPi), 0.0, 1e-9);
      EXPECT_NEAR(p.up.norm(), 1.0, 1e-12);
      if (p.id == before[i].id) {
        // Carried along the pathline from its previous place.
        PathlineOptions po;
        po.t_start = t - 0.1;
        po.t_end = t;
        po.stop_at_singular_faces = false;
        po.stop_speed = 0;
        const Pathline line = trace_pathline(bundle, field, before[i].where, po);
        EXPECT_LT((line.points.back().head<2>() - p.position).norm(), 1e-12);
        turned = std::max(turned, std::acos(std::clamp(before[i].up.dot(p.up), -1.0, 1.0)));
      }
    }
    before = now;
  }
  EXPECT_GT(turned, 0.1) << "the leaves spin as the flow turns";
}

// --- Painterly ------------------------------------------------------------------------------

TEST(Painterly, StrokesFollowTheFieldInsideTheMaskAndStayPutOutside) {
  const Mesh grid = make_grid(GridSpec{17, 17, {0, 0}, {1, 1}});
  const TangentBundle bundle(grid);
  // A uniform flow to the right: strokes inside the mask are straight, horizontal, and
  // move right by |V|·Δt = 0.2 (20 pixels of a 100-pixel picture) per step.
  const Field field = sample(grid, TimeSampling{0, 1, 11}, [](cplx, double) { return cplx(1, 0); });
  Image mask(100, 100);
  for (int y = 0; y < 100; ++y)
    for (int x = 0; x < 100; ++x) mask.at(x, y) = y >= 50 ? 0x00FFFFFFu : 0u;  // the lower half moves
  PainterlyOptions o;
  o.stroke_width = 4;
  o.stroke_length = 12;
  o.density = 1;
  PainterlyAnimator painter(bundle, field, ramp(100, 100), mask, o);
  painter.advance(0.0);
  const auto first = painter.strokes();
  ASSERT_GT(first.size(), 50u);
  for (const auto& s : first) {
    EXPECT_EQ(s.moving, s.centre.y() >= 50);
    if (!s.moving) continue;
    EXPECT_NEAR(s.path.front().y(), s.centre.y(), 1e-9);
    EXPECT_NEAR(s.path.back().y(), s.centre.y(), 1e-9);
    const double len = s.path.back().x() - s.path.front().x();
    if (s.centre.x() > 10 && s.centre.x() < 90) {
      EXPECT_NEAR(len, 12.0, 1e-6) << "a straight stroke of full length";
    }
  }
  painter.advance(0.2);
  const auto& second = painter.strokes();
  int moved = 0;
  for (const auto& s : second) {
    for (const auto& f : first)
      if (f.id == s.id) {
        if (f.moving && f.centre.x() < 75) {
          EXPECT_NEAR(s.centre.x() - f.centre.x(), 20.0, 1e-9);
          EXPECT_NEAR(s.centre.y(), f.centre.y(), 1e-9);
          ++moved;
        }
        if (!f.moving) {
          EXPECT_EQ(s.centre, f.centre);
          EXPECT_EQ(s.path, f.path) << "strokes outside the mask keep their shape";
        }
      }
    // Colour from the picture at the stroke's centre.
    const int i = std::clamp(static_cast<int>(s.centre.x()), 0, 99), j = std::clamp(static_cast<int>(s.centre.y()), 0, 99);
    EXPECT_EQ(s.colour, ramp(100, 100).at(i, j));
  }
  EXPECT_GT(moved, 10);
  // Coverage: every cell keeps at least one stroke — the left band the flow emptied was
  // refilled — and none holds more than max_per_cell.
  EXPECT_GT(painter.added(), 0);
  const double cell = std::sqrt(o.stroke_width * o.stroke_length / o.density);
  const int cx = static_cast<int>(std::ceil(100 / cell)), cy = cx;
  std::vector<int> count(static_cast<size_t>(cx * cy), 0);
  for (const auto& s : second)
    ++count[static_cast<size_t>(std::min(cy - 1, static_cast<int>(s.centre.y() / cell)) * cx +
                                std::min(cx - 1, static_cast<int>(s.centre.x() / cell)))];
  for (int c : count) {
    EXPECT_GE(c, 1);
    EXPECT_LE(c, o.max_per_cell);
  }
  // The picture: strokes change it, but it keeps the picture's colours where they are.
  const Image pic = painter.picture();
  EXPECT_EQ(pic.width, 100);
  EXPECT_NE(pic.pixels, ramp(100, 100).pixels);
}

// The same fault as the crowd's (issue 16 item 13), in the painterly strokes: the mask was
// checked only where a frame's travel ended, so a stroke carried 20 pixels across a
// 4-pixel band where the field does not apply moved on beyond it. It now stops in the band.
TEST(Painterly, AStrokeCarriedAcrossAThinMaskedBandStopsInIt) {
  const Mesh grid = make_grid(GridSpec{17, 17, {0, 0}, {1, 1}});
  const TangentBundle bundle(grid);
  const Field field = sample(grid, TimeSampling{0, 1, 11}, [](cplx, double) { return cplx(1, 0); });
  Image mask(100, 100);
  for (int y = 0; y < 100; ++y)
    for (int x = 0; x < 100; ++x) mask.at(x, y) = x >= 48 && x < 52 ? 0u : 0x00FFFFFFu;
  PainterlyOptions o;
  o.stroke_width = 4;
  o.stroke_length = 12;
  o.density = 1;
  PainterlyAnimator painter(bundle, field, ramp(100, 100), mask, o);
  painter.advance(0.0);
  const auto first = painter.strokes();
  painter.advance(0.2);  // 20 pixels to the right
  int across = 0, stopped = 0;
  for (const auto& s : painter.strokes())
    for (const auto& f : first)
      if (f.id == s.id && f.moving && f.centre.x() > 32 && f.centre.x() < 47) {
        // Its way crosses x = 48: it ends in the band, not beyond it.
        EXPECT_GE(s.centre.x(), 48 - 1e-9) << "stroke " << s.id;
        EXPECT_LE(s.centre.x(), 48.5 + 1e-9) << "stroke " << s.id << " went on across the band";
        EXPECT_FALSE(s.moving);
        ++across;
        stopped += !s.moving;
      }
  EXPECT_GT(across, 3);
  EXPECT_EQ(stopped, across);
}

TEST(Painterly, BadOptionsAndSurfacesAreErrors) {
  const Mesh grid = make_grid(GridSpec{5, 5, {0, 0}, {1, 1}});
  const TangentBundle bundle(grid);
  const Field field = sample(grid, TimeSampling{0, 1, 2}, [](cplx, double) { return cplx(1, 0); });
  PainterlyOptions o;
  o.density = 0;
  EXPECT_THROW(PainterlyAnimator(bundle, field, ramp(32, 32), Image(), o), Error);
  o.density = 1;
  o.stroke_width = std::nan("");
  EXPECT_THROW(PainterlyAnimator(bundle, field, ramp(32, 32), Image(), o), Error);
  PainterlyAnimationOptions a;
  EXPECT_THROW(write_painterly_animation(bundle, field, ramp(32, 32), Image(), a), Error) << "no output given";
}

}  // namespace
}  // namespace tvf
