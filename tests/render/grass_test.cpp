#include "tvf/render/grass.h"

#include "support/test_paths.h"
#include "tvf/core/error.h"
#include "tvf/mesh/grid.h"
#include "tvf/mesh/primitives.h"

#include <gtest/gtest.h>

#include <cmath>
#include <filesystem>
#include <random>

namespace tvf {
namespace {

Field constant_field(const Mesh& mesh, int frames, const std::function<cplx(int frame)>& value) {
  Field f(TimeSampling{0.0, 1.0, frames}, mesh.num_vertices());
  for (int j = 0; j < frames; ++j)
    for (int v = 0; v < mesh.num_vertices(); ++v) f.at(j, v) = value(j);
  return f;
}

TEST(Fabrik, KeepsSegmentLengthsAndRootAndReachesAReachableTarget) {
  std::mt19937 rng(4);
  std::uniform_real_distribution<double> u(-1.0, 1.0);
  for (int trial = 0; trial < 200; ++trial) {
    const int n = 2 + trial % 7;
    const double l = 0.1 + 0.05 * (trial % 3);
    std::vector<Vec3> joints(static_cast<size_t>(n));
    const Vec3 root(u(rng), u(rng), 0);
    for (int i = 0; i < n; ++i) joints[static_cast<size_t>(i)] = root + Vec3(0, 0, i * l);
    // A target inside the reach (distance < (n − 1)·l) and above the ground.
    const double reach = (n - 1) * l;
    Vec3 d(u(rng), u(rng), std::abs(u(rng)) + 0.2);
    d.normalize();
    const Vec3 target = root + (0.3 + 0.65 * (u(rng) + 1) / 2) * reach * d;
    const IkResult r = solve_fabrik(joints, l, target, 200, 1e-9 * reach);
    EXPECT_EQ(joints[0], root);
    for (int i = 1; i < n; ++i)
      EXPECT_NEAR((joints[static_cast<size_t>(i)] - joints[static_cast<size_t>(i - 1)]).norm() / l, 1.0, 1e-12);
    if (n > 2) {  // two joints reach along one line only
      EXPECT_LT(r.tip_error, 1e-9 * reach) << trial;
    }
  }
}

TEST(Fabrik, OutOfReachPointsStraightAtTheTarget) {
  std::vector<Vec3> joints{Vec3(0, 0, 0), Vec3(0, 0, 1), Vec3(0, 0, 2)};
  const Vec3 target(10, 0, 1);
  solve_fabrik(joints, 1.0, target, 50, 1e-12);
  const Vec3 d = target.normalized();
  EXPECT_LT((joints[2] - 2 * d).norm(), 1e-6);
  EXPECT_LT((joints[1] - d).norm(), 1e-6);
}

TEST(Grass, RootsStayAndSegmentsKeepTheirLengthsOverAnAnimation) {
  const Mesh grid = make_grid({21, 21, {-1, -1}, {1, 1}});
  const TangentBundle bundle(grid);
  // A field that turns and changes strength over time.
  const Field field = constant_field(grid, 9, [](int j) { return std::polar(0.2 + 0.1 * j, 0.7 * j); });
  GrassOptions o;
  o.count = 500;
  o.segments = 5;
  Meadow meadow(bundle, field, o);
  std::vector<Vec3> roots;
  for (int k = 0; k < meadow.strands(); ++k) roots.push_back(meadow.root(k));
  for (int j = 0; j < 9; ++j) {
    meadow.pose(field.time().time(j));
    for (int k = 0; k < meadow.strands(); ++k) {
      const auto s = meadow.strand(k);
      ASSERT_EQ(s.size(), 6u);
      EXPECT_EQ(s[0], roots[static_cast<size_t>(k)]);
      EXPECT_EQ(s[0].z(), 0.0);
      for (size_t i = 1; i < s.size(); ++i)
        EXPECT_NEAR((s[i] - s[i - 1]).norm() / meadow.segment_length(k), 1.0, 1e-12);
    }
  }
  // Roots lie on the ground inside the domain.
  for (const Vec3& r : roots) {
    EXPECT_GE(r.x(), -1.0);
    EXPECT_LE(r.x(), 1.0);
    EXPECT_GE(r.y(), -1.0);
    EXPECT_LE(r.y(), 1.0);
  }
}

TEST(Grass, TipsFollowAUniformFieldAndBendMoreInAStrongerOne) {
  const Mesh grid = make_grid({11, 11, {0, 0}, {2, 2}});
  const TangentBundle bundle(grid);
  for (double angle : {0.0, 1.0, 2.5, -2.0}) {
    // Frame 0: weak; frame 1: at the full wind speed, direction `angle`.
    const Field field = constant_field(grid, 2, [&](int j) { return std::polar(j == 0 ? 0.3 : 1.0, angle); });
    GrassOptions o;
    o.count = 300;
    o.lean = 0;  // no random lean: every tip follows the field
    o.wind_speed = 1.0;
    o.ik_tolerance = 1e-6;
    o.ik_iterations = 1000;
    Meadow meadow(bundle, field, o);
    const Vec2 dir(std::cos(angle), std::sin(angle));
    std::vector<double> weak(static_cast<size_t>(meadow.strands()));
    meadow.pose(0.0);
    for (int k = 0; k < meadow.strands(); ++k) {
      const Vec3 d = meadow.strand(k).back() - meadow.root(k);
      weak[static_cast<size_t>(k)] = std::atan2(d.head<2>().norm(), d.z());
    }
    meadow.pose(1.0);
    for (int k = 0; k < meadow.strands(); ++k) {
      const Vec3 d = meadow.strand(k).back() - meadow.root(k);
      const Vec2 h = d.head<2>();
      ASSERT_GT(h.norm(), 0);
      // Horizontally along the field, to round-off (the chain stays in the vertical plane
      // through the root and the target).
      EXPECT_NEAR(h.normalized().dot(dir), 1.0, 1e-12);
      EXPECT_LT(std::abs(h.x() * dir.y() - h.y() * dir.x()), 1e-12);
      // The tip sits at its target; the chord leans by half the bend angle.
      EXPECT_LT((meadow.strand(k).back() - meadow.target(k)).norm(), 1e-6 * 4 * meadow.segment_length(k));
      const double lean = std::atan2(h.norm(), d.z());
      EXPECT_NEAR(lean, 0.5 * o.bend * kPi / 180, 1e-5);
      EXPECT_GT(lean, weak[static_cast<size_t>(k)] + 0.2);
      // Nothing goes under the ground.
      for (const Vec3& x : meadow.strand(k)) EXPECT_GE(x.z(), 0.0);
    }
  }
}

TEST(Grass, PosesChangeLittleBetweenFramesOfASlowlyTurningField) {
  // Warm-started FABRIK: a tip moves by about as much as its target does, so a slowly
  // varying field gives a coherent animation (no strand jumps to another solution).
  const Mesh grid = make_grid({11, 11, {0, 0}, {1, 1}});
  const TangentBundle bundle(grid);
  const int frames = 41;
  const Field field = constant_field(grid, frames, [](int j) { return std::polar(1.0, 0.05 * j); });
  GrassOptions o;
  o.count = 400;
  o.wind_speed = 1.0;
  Meadow meadow(bundle, field, o);
  meadow.pose(0.0);
  std::vector<Vec3> tips, targets;
  for (int k = 0; k < meadow.strands(); ++k) tips.push_back(meadow.strand(k).back()), targets.push_back(meadow.target(k));
  for (int j = 1; j < frames; ++j) {
    meadow.pose(field.time().time(j));
    for (int k = 0; k < meadow.strands(); ++k) {
      const auto kk = static_cast<size_t>(k);
      const double target_step = (meadow.target(k) - targets[kk]).norm();
      const double tip_step = (meadow.strand(k).back() - tips[kk]).norm();
      const double tolerance = 2 * o.ik_tolerance * 4 * meadow.segment_length(k);  // both tips within it
      EXPECT_LE(tip_step, target_step + tolerance) << "strand " << k << " frame " << j;
      tips[kk] = meadow.strand(k).back();
      targets[kk] = meadow.target(k);
    }
  }
}

TEST(Grass, AZeroFieldLeavesTheGrassStanding) {
  const Mesh grid = make_grid({5, 5, {0, 0}, {1, 1}});
  const TangentBundle bundle(grid);
  const Field field = constant_field(grid, 2, [](int) { return cplx(0, 0); });
  GrassOptions o;
  o.count = 50;
  o.lean = 0;
  Meadow meadow(bundle, field, o);
  meadow.pose(0.5);
  for (int k = 0; k < meadow.strands(); ++k) {
    const Vec3 d = meadow.strand(k).back() - meadow.root(k);
    EXPECT_EQ(d.head<2>().norm(), 0.0);
    EXPECT_NEAR(d.z(), 4 * meadow.segment_length(k), 1e-12);
  }
}

TEST(Grass, RefusesSurfacesAndBadOptions) {
  const Mesh sphere = make_icosphere(1);
  const TangentBundle sb(sphere);
  const Field sf(TimeSampling{}, sphere.num_vertices());
  EXPECT_THROW(Meadow(sb, sf, {}), Error);
  const Mesh grid = make_grid({5, 5, {0, 0}, {1, 1}});
  const TangentBundle bundle(grid);
  const Field field = constant_field(grid, 2, [](int) { return cplx(1, 0); });
  for (auto bad : std::vector<std::function<void(GrassOptions&)>>{
           [](GrassOptions& o) { o.count = 0; }, [](GrassOptions& o) { o.segments = 0; },
           [](GrassOptions& o) { o.length = std::nan(""); }, [](GrassOptions& o) { o.bend = -1; },
           [](GrassOptions& o) { o.wind_speed = -1; }}) {
    GrassOptions o;
    bad(o);
    EXPECT_THROW(Meadow(bundle, field, o), Error);
  }
  Meadow meadow(bundle, field, {});
  EXPECT_THROW(meadow.pose(2.0), Error);
}

TEST(Grass, PictureShowsBentGrassBrighterThanStandingGrass) {
  // The left half has no wind, the right half a strong one: bent strands catch the
  // overhead sun and show more of their length, so the right half is brighter.
  const Mesh grid = make_grid({21, 11, {0, 0}, {2, 1}});
  const TangentBundle bundle(grid);
  Field field(TimeSampling{0.0, 1.0, 1}, grid.num_vertices());
  for (int v = 0; v < grid.num_vertices(); ++v) field.at(0, v) = grid.position(v).x() > 1.0 ? cplx(0, 1) : cplx(0, 0);
  GrassOptions o;
  o.count = 4000;
  o.length = 0.05;
  Meadow meadow(bundle, field, o);
  meadow.pose(0.0);
  GrassRenderOptions ro;
  ro.image_size = 300;
  ro.elevation = 90;  // top-down: the two halves are the two halves of the picture
  GrassRenderer renderer(meadow, ro);
  const Image image = renderer.picture();
  EXPECT_EQ(image.width, renderer.width());
  auto brightness = [&](int x0, int x1) {
    double s = 0;
    for (int y = 0; y < image.height; ++y)
      for (int x = x0; x < x1; ++x) {
        const std::uint32_t p = image.at(x, y);
        s += ((p >> 16) & 255) + ((p >> 8) & 255) + (p & 255);
      }
    return s / ((x1 - x0) * image.height);
  };
  const int w = image.width;
  EXPECT_GT(brightness(w * 6 / 10, w * 9 / 10), 1.2 * brightness(w / 10, w * 4 / 10));
}

TEST(Grass, AnimationWritesFrames) {
  const Mesh grid = make_grid({9, 9, {0, 0}, {1, 1}});
  const TangentBundle bundle(grid);
  const Field field = constant_field(grid, 3, [](int j) { return std::polar(1.0, 0.5 * j); });
  test::TempDir dir;
  GrassAnimationOptions o;
  o.grass.count = 200;
  o.render.image_size = 64;
  o.frames_dir = (dir.path() / "frames").string();
  int calls = 0;
  o.progress = [&](int, int) { ++calls; };
  const AnimationReport r = write_grass_animation(bundle, field, o);
  EXPECT_EQ(r.frames, 3);
  EXPECT_EQ(calls, 3);
  EXPECT_TRUE(std::filesystem::exists(dir.path() / "frames" / "frame_00002.png"));
}

}  // namespace
}  // namespace tvf
