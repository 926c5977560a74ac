// Crowds on a surface (render/surface_crowd.h): agents walk on the mesh to goals by the
// geodesic distance, around obstacle regions, and reach them.
#include "tvf/render/surface_crowd.h"

#include "support/test_meshes.h"
#include "support/test_paths.h"
#include "tvf/core/error.h"
#include "tvf/mesh/primitives.h"

#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <fstream>
#include <string>

namespace tvf {
namespace {

TEST(SurfaceCrowd, AgentsWalkOnTheSphereToTheGoalAroundAnObstacle) {
  const Mesh sphere = make_icosphere(4, 1.0);
  const TangentBundle bundle(sphere);
  const Field still(TimeSampling{0, 1, 41}, sphere.num_vertices());  // no field: the goal term alone
  SurfaceCrowdSpec spec;
  spec.agents = 30;
  spec.weight_goal = 1.0;
  spec.weight_field = 0.0;
  spec.speed = 4.0;  // world units per unit time: the half circumference (π) well within the time range
  spec.starts = {{Vec3(0, 0, -1), 0.3}};
  spec.goals = {{Vec3(0, 0, 1), 0.25}};
  spec.obstacles = {{Vec3(1, 0, 0), 0.5}};  // a cap on the equator in the way of some
  const SurfaceCrowdResult r = simulate_surface_crowd(bundle, still, spec);
  ASSERT_EQ(r.arrived.size(), 30u);
  // The potential grows as the geodesic distance from the goal cap (the goal faces'
  // centres, within an angular radius ≈ 2·asin(0.125)), up to a constant: only its
  // gradient steers. (The heat method from a whole region rounds φ over the region.)
  const double cap = 2 * std::asin(0.125);
  std::vector<double> diff;
  for (int v = 0; v < sphere.num_vertices(); ++v) {
    const Vec3 x = sphere.position(v).normalized();
    if (x.x() > -0.1) continue;  // the obstacle's side: geodesics round it are longer
    if (std::acos(x.z()) < cap + 0.2) continue;       // in and near the goal
    diff.push_back(r.distance[static_cast<size_t>(v)] - (std::acos(x.z()) - cap));
  }
  ASSERT_GT(diff.size(), 800u);
  double mean = 0;
  for (double d : diff) mean += d;
  mean /= static_cast<double>(diff.size());
  double worst = 0;
  for (double d : diff) worst = std::max(worst, std::abs(d - mean));
  EXPECT_LT(worst, 0.05) << "offset " << mean;
  EXPECT_LT(std::abs(mean), 0.15);
  for (size_t a = 0; a < r.arrived.size(); ++a) {
    EXPECT_GE(r.arrived[a], 1) << "agent " << a;  // everyone reaches the goal
    for (size_t k = 0; k < r.positions[a].size(); ++k) {
      const Vec3& x = r.positions[a][k];
      EXPECT_LE(x.norm(), 1.0 + 1e-9);  // on the mesh
      EXPECT_GT(x.norm(), 0.99);
      EXPECT_FALSE(r.obstacle_face[static_cast<size_t>(r.where[a][k].face)]) << "agent " << a << " picture " << k;
    }
    // Arrived agents stay in the goal.
    const Vec3& last = r.positions[a].back();
    EXPECT_GT(last.z(), 0.9);
  }
}

// The trajectories as CSV, alone (no pictures): one row per agent and picture with the
// simulated world positions, digit for digit, and the arrival flag from the first picture
// at a goal on; no output at all is refused.
TEST(SurfaceCrowd, TrajectoriesAsCsv) {
  const Mesh sphere = make_icosphere(3, 1.0);
  const TangentBundle bundle(sphere);
  const Field still(TimeSampling{0, 1, 11}, sphere.num_vertices());
  SurfaceCrowdSpec spec;
  spec.agents = 4;
  spec.weight_goal = 1.0;
  spec.weight_field = 0.0;
  spec.speed = 6.0;
  spec.starts = {{Vec3(0, 0, -1), 0.3}};
  spec.goals = {{Vec3(0, 0, 1), 0.3}};
  const test::TempDir dir;
  SurfaceCrowdAnimationOptions options;
  options.csv = (dir / "crowd.csv").string();
  SurfaceCrowdResult r;
  const AnimationReport report = write_surface_crowd_animation(bundle, still, spec, options, &r);
  ASSERT_EQ(report.files, std::vector<std::string>{options.csv});
  EXPECT_EQ(report.frames, 11);
  std::ifstream in(options.csv);
  std::string line;
  std::getline(in, line);
  EXPECT_EQ(line, "agent,frame,t,x,y,z,arrived");
  size_t rows = 0;
  int arrivals = 0;
  while (std::getline(in, line)) {
    int a = 0, k = 0, arrived = 0;
    double t = 0, x = 0, y = 0, z = 0;
    ASSERT_EQ(std::sscanf(line.c_str(), "%d,%d,%lf,%lf,%lf,%lf,%d", &a, &k, &t, &x, &y, &z, &arrived), 7) << line;
    const auto ua = static_cast<size_t>(a), uk = static_cast<size_t>(k);
    EXPECT_EQ(ua, rows / 11);
    EXPECT_EQ(uk, rows % 11);
    EXPECT_EQ(t, r.times[uk]);
    EXPECT_EQ(Vec3(x, y, z), r.positions[ua][uk]) << line;
    EXPECT_EQ(arrived, r.arrived[ua] >= 0 && r.arrived[ua] <= k ? 1 : 0);
    arrivals += arrived;
    ++rows;
  }
  EXPECT_EQ(rows, 4u * 11u);
  EXPECT_GT(arrivals, 0);  // they reach the goal within the time range
  SurfaceCrowdAnimationOptions none;
  EXPECT_EQ(test::error_of([&] { write_surface_crowd_animation(bundle, still, spec, none); }),
            "crowd: give a folder for the PNG frames, an MP4 file or a CSV file to write");
}

// Avoidance on the sphere: 40 agents crowded in a small start cap walk to the goal; with
// a separation every two of those still on their way are at least (nearly) that far
// apart at every picture, from the start on; without, the crowd's agents come much closer.
TEST(SurfaceCrowd, AvoidanceKeepsAgentsApartOnTheSphere) {
  const Mesh sphere = make_icosphere(4, 1.0);
  const TangentBundle bundle(sphere);
  const Field still(TimeSampling{0, 1, 21}, sphere.num_vertices());
  SurfaceCrowdSpec spec;
  spec.agents = 40;
  spec.weight_goal = 1.0;
  spec.weight_field = 0.0;
  spec.speed = 4.0;
  spec.starts = {{Vec3(0, 0, -1), 0.35}};
  spec.goals = {{Vec3(0, 0, 1), 0.25}};
  auto closest = [](const SurfaceCrowdResult& r) {
    double least = 1e9;
    for (size_t k = 0; k < r.times.size(); ++k)
      for (size_t a = 0; a < r.positions.size(); ++a)
        for (size_t b = a + 1; b < r.positions.size(); ++b) {
          const auto on_way = [&](size_t i) { return r.arrived[i] < 0 || static_cast<size_t>(r.arrived[i]) > k; };
          if (on_way(a) && on_way(b)) least = std::min(least, (r.positions[a][k] - r.positions[b][k]).norm());
        }
    return least;
  };
  const double free_closest = closest(simulate_surface_crowd(bundle, still, spec));
  spec.separation = 0.06;
  const SurfaceCrowdResult r = simulate_surface_crowd(bundle, still, spec);
  const double kept = closest(r);
  EXPECT_GT(kept, 0.9 * spec.separation) << "without avoidance: " << free_closest;
  EXPECT_LT(free_closest, 0.5 * spec.separation);
  for (size_t a = 0; a < r.arrived.size(); ++a) EXPECT_GE(r.arrived[a], 1) << "agent " << a;  // they still arrive
  for (const auto& path : r.positions)
    for (const Vec3& x : path) EXPECT_NEAR(x.norm(), 1.0, 0.01);  // on the mesh
}

TEST(SurfaceCrowd, BadSpecsAreNamed) {
  const Mesh sphere = make_icosphere(2, 1.0);
  const TangentBundle bundle(sphere);
  const Field still(TimeSampling{0, 1, 3}, sphere.num_vertices());
  SurfaceCrowdSpec spec;
  spec.starts = {{Vec3(0, 0, -1), 0.3}};
  spec.goals = {{Vec3(5, 5, 5), 0.1}};  // off the surface
  EXPECT_NE(test::error_of([&] { simulate_surface_crowd(bundle, still, spec); }).find("goals hold no face"),
            std::string::npos);
  test::TempDir dir;
  test::write_text(dir / "c.json", R"({"start": [{"ball": {"center": [0, 0, -1], "radius": 0.3}}],
    "goals": [{"circle": {"center": [0, 0], "radius": 0.3}}]})");
  const std::string e = test::error_of([&] { load_surface_crowd_spec((dir / "c.json").string()); });
  EXPECT_NE(e.find("c.json"), std::string::npos) << e;
  EXPECT_NE(e.find("goals[0]"), std::string::npos) << e;
  EXPECT_NE(e.find("ball"), std::string::npos) << e;
  // The same reader as planar crowd files: the line and column of the bad value.
  test::write_text(dir / "d.json", "{\"start\": [{\"ball\": {\"center\": [0, 0, -1], \"radius\": 0.3}}],\n"
                                   " \"goals\": [{\"ball\": {\"center\": [0, 0, 1], \"radius\": 0.3}}],\n  \"speed\": true}");
  const std::string d = test::error_of([&] { load_surface_crowd_spec((dir / "d.json").string()); });
  EXPECT_EQ(d, (dir / "d.json").string() + ": speed (line 3, column 12): expected a number") << d;
  // Avoidance: a distance only (the planar weight is not a surface key).
  test::write_text(dir / "a.json", R"({"start": [{"ball": {"center": [0, 0, -1], "radius": 0.3}}],
    "goals": [{"ball": {"center": [0, 0, 1], "radius": 0.3}}], "avoidance": {"distance": 0.05, "weight": 1}})");
  const std::string w = test::error_of([&] { load_surface_crowd_spec((dir / "a.json").string()); });
  EXPECT_NE(w.find("avoidance"), std::string::npos) << w;
  EXPECT_NE(w.find("weight"), std::string::npos) << w;
  test::write_text(dir / "b.json", R"({"start": [{"ball": {"center": [0, 0, -1], "radius": 0.3}}],
    "goals": [{"ball": {"center": [0, 0, 1], "radius": 0.3}}], "avoidance": {"distance": 0.05}})");
  EXPECT_EQ(load_surface_crowd_spec((dir / "b.json").string()).separation, 0.05);
}

}  // namespace
}  // namespace tvf
