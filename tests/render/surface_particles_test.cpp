// Leaves on a surface (render/surface_particles.h): carried along pathlines on the mesh,
// they stay on it; a rotation about z keeps each at its height and turns it by the angle
// the rotation gives; the up direction keeps its angle to the flow; pictures show them.
#include "tvf/render/surface_particles.h"

#include "support/test_meshes.h"
#include "support/test_paths.h"
#include "tvf/core/error.h"
#include "tvf/mesh/primitives.h"

#include <gtest/gtest.h>

#include <cmath>
#include <filesystem>

namespace tvf {
namespace {

// The rotation ω·(z × x) about the z axis, sampled at the vertices.
Field rotation(const TangentBundle& bundle, double omega, int frames) {
  const Mesh& mesh = bundle.mesh();
  Field field(TimeSampling{0, 1, frames}, mesh.num_vertices());
  for (int j = 0; j < frames; ++j)
    for (int v = 0; v < mesh.num_vertices(); ++v)
      field.at(j, v) = bundle.world_to_vertex(v, omega * Vec3::UnitZ().cross(mesh.position(v)));
  return field;
}

TEST(SurfaceParticles, LeavesStayOnTheSphereAndCircleTheAxis) {
  const Mesh sphere = make_icosphere(4, 1.0);
  const TangentBundle bundle(sphere);
  const double omega = 1.0;
  const Field field = rotation(bundle, omega, 11);
  ParticleOptions o;
  o.count = 300;
  o.spin = 0.7;
  SurfaceParticleSystem system(bundle, field, o);
  system.advance(0.0);
  const std::vector<SurfaceLeaf> start = system.leaves();
  ASSERT_EQ(start.size(), 300u);
  system.advance(1.0);
  const std::vector<SurfaceLeaf>& end = system.leaves();
  ASSERT_EQ(end.size(), 300u);
  EXPECT_EQ(system.respawned(), 0);  // a closed surface: nothing is lost
  // The faces of a level-4 icosphere are chords: the inscribed distance of its faces.
  const double inner = 0.995;
  int compared = 0;
  for (size_t k = 0; k < end.size(); ++k) {
    const SurfaceLeaf& a = start[k];
    const SurfaceLeaf& b = end[k];
    ASSERT_EQ(a.id, b.id);
    // On the mesh: the position is the point of its face, inside the sphere and out of the
    // faces' inscribed sphere.
    EXPECT_LT((b.position - surface_position(sphere, b.where)).norm(), 1e-12);
    EXPECT_LE(b.position.norm(), 1.0 + 1e-9);
    EXPECT_GE(b.position.norm(), inner);
    for (int c = 0; c < 3; ++c) EXPECT_GE(b.where.bary[c], -1e-9);
    // Up: unit, in the face's plane, at the spin angle from the flow direction.
    const Vec3& n = bundle.face_normal(b.where.face);
    EXPECT_NEAR(b.up.norm(), 1.0, 1e-9);
    EXPECT_NEAR(b.up.dot(n), 0.0, 1e-9);
    Vec3 v = Vec3::UnitZ().cross(b.position);
    v -= v.dot(n) * n;
    const double rho = std::hypot(a.position.x(), a.position.y());
    if (rho < 0.2) continue;  // near the poles the flow direction turns fast
    EXPECT_NEAR(std::atan2(v.normalized().cross(b.up).dot(n), v.normalized().dot(b.up)), 0.7, 0.02);
    // The rotation keeps the height and turns by ω·Δt = 1 radian about z.
    EXPECT_NEAR(b.position.z(), a.position.z(), 0.01);
    const double turned = std::remainder(std::atan2(b.position.y(), b.position.x()) -
                                             std::atan2(a.position.y(), a.position.x()),
                                         2 * kPi);
    EXPECT_NEAR(turned, omega * 1.0, 0.02) << rho;
    ++compared;
  }
  EXPECT_GT(compared, 250);
}

TEST(SurfaceParticles, LeavesCarriedOffAnOpenSurfaceComeBack) {
  // A hemisphere with a uniform flow through its rim: leaves leave and are placed anew.
  const Mesh& mesh = test::hemisphere_mesh();
  const TangentBundle bundle(mesh);
  Field field(TimeSampling{0, 1, 3}, mesh.num_vertices());
  for (int j = 0; j < 3; ++j)
    for (int v = 0; v < mesh.num_vertices(); ++v) {
      const Vec3& x = mesh.position(v);
      field.at(j, v) = bundle.world_to_vertex(v, Vec3(3 * (Vec3::UnitX() - x.x() * x)));
    }
  ParticleOptions o;
  o.count = 200;
  SurfaceParticleSystem system(bundle, field, o);
  system.advance(0.0);
  system.advance(1.0);
  EXPECT_GT(system.respawned(), 20);
  EXPECT_EQ(system.leaves().size(), 200u);
  for (const SurfaceLeaf& l : system.leaves()) EXPECT_LT((l.position - surface_position(mesh, l.where)).norm(), 1e-12);
}

TEST(SurfaceParticles, PicturesShowTheLeavesOnTheSurface) {
  const Mesh sphere = make_icosphere(3, 1.0);
  const TangentBundle bundle(sphere);
  const Field field = rotation(bundle, 1.0, 5);
  test::TempDir dir;
  ParticleAnimationOptions o;
  o.particles.count = 150;
  o.particles.image_size = 160;
  o.particles.size = 12;
  o.frames = 3;
  o.frames_dir = (dir / "frames").string();
  const AnimationReport r = write_particle_animation(bundle, field, o);
  EXPECT_EQ(r.frames, 3);
  EXPECT_EQ(r.width, 160);
  const Image img = read_png((dir / "frames" / "frame_00002.png").string());
  // Leaf colours are reds, oranges and yellows: red well above blue. The ground is a pale
  // blue-gray (blue ≥ red) and the background white.
  int leaf = 0, white = 0;
  for (const auto px : img.pixels) {
    const int r8 = static_cast<int>((px >> 16) & 255u), b8 = static_cast<int>(px & 255u);
    leaf += r8 > b8 + 60;
    white += px == 0xFFFFFFu;
  }
  EXPECT_GT(leaf, 300);
  EXPECT_GT(white, 160 * 160 / 5);
  // Planar domains are refused by the surface system, naming why.
  const Mesh& grid = test::grid_mesh();
  const TangentBundle flat(grid);
  const Field f2(TimeSampling{0, 1, 2}, grid.num_vertices());
  EXPECT_NE(test::error_of([&] { SurfaceParticleSystem s(flat, f2); }).find("planar"), std::string::npos);
}

}  // namespace
}  // namespace tvf
