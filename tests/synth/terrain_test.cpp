// Terrain meshes: height grids and displaced surfaces are valid meshes with exactly the
// heights asked for; per-frame folders appear whole; coloured PLY files read back.
#include "tvf/synth/terrain.h"

#include "support/test_paths.h"
#include "tvf/mesh/mesh_io.h"
#include "tvf/mesh/primitives.h"

#include <gtest/gtest.h>

#include <filesystem>

namespace tvf {
namespace {

namespace fs = std::filesystem;

TEST(Terrain, HeightFieldMeshReadsTheGrid) {
  // A height rising linearly to the east: z at each vertex is the ramp's value there.
  const int w = 40, h = 20;
  std::vector<float> height(static_cast<size_t>(w * h));
  for (int j = 0; j < h; ++j)
    for (int i = 0; i < w; ++i) height[static_cast<size_t>(j * w + i)] = (i + 0.5f) / w;
  const Mesh m = height_field_mesh(height, w, h, {0, 0}, {2, 1}, 21, 0.5);
  EXPECT_EQ(m.num_vertices(), 21 * 11);
  EXPECT_EQ(m.num_faces(), 2 * 20 * 10);
  EXPECT_EQ(m.euler_characteristic(), 1);
  for (int v = 0; v < m.num_vertices(); ++v) {
    const Vec3& p = m.position(v);
    const double expected = std::clamp(p.x() / 2, 0.5 / w, (w - 0.5) / w) * 0.5;
    ASSERT_NEAR(p.z(), expected, 1e-6) << v;
  }
}

TEST(Terrain, DisplacementMovesAlongTheNormals) {
  const Mesh sphere = make_icosphere(2);
  const TangentBundle bundle(sphere);
  std::vector<float> height(static_cast<size_t>(sphere.num_vertices()));
  for (size_t v = 0; v < height.size(); ++v) height[v] = static_cast<float>(v % 5) / 4.f;
  const Mesh d = displace_along_normals(bundle, height, 0.2);
  ASSERT_EQ(d.num_vertices(), sphere.num_vertices());
  EXPECT_EQ(d.euler_characteristic(), 2);
  for (int v = 0; v < d.num_vertices(); ++v) {
    const Vec3 move = d.position(v) - sphere.position(v);
    EXPECT_NEAR(move.dot(bundle.vertex_normal(v)), (height[static_cast<size_t>(v)] - 0.5) * 0.2, 1e-9);
    EXPECT_NEAR(move.cross(bundle.vertex_normal(v)).norm(), 0, 1e-9);
  }
}

TEST(Terrain, ColouredPlyReadsBack) {
  test::TempDir dir;
  const Mesh sphere = make_icosphere(1);
  std::vector<Vec3> colours(static_cast<size_t>(sphere.num_vertices()), Vec3(1, 0.5, 0));
  write_colored_ply((dir / "s.ply").string(), sphere, colours);
  const LoadedMesh back = load_mesh((dir / "s.ply").string());
  ASSERT_EQ(back.mesh.num_vertices(), sphere.num_vertices());
  ASSERT_EQ(back.mesh.num_faces(), sphere.num_faces());
  for (int v = 0; v < sphere.num_vertices(); ++v) EXPECT_LT((back.mesh.position(v) - sphere.position(v)).norm(), 1e-6);
  const std::string text = test::read_text(dir / "s.ply");
  EXPECT_NE(text.find("property uchar red"), std::string::npos);
}

TEST(Terrain, FramesFolderAppearsWholeOrNotAtAll) {
  test::TempDir dir;
  const Mesh sphere = make_icosphere(1);
  const TangentBundle bundle(sphere);
  std::vector<float> height(static_cast<size_t>(sphere.num_vertices()), 0.7f);
  {
    TerrainMeshWriter writer((dir / "meshes").string(), sphere, {});
    writer.add_surface(bundle, height);
    // Destroyed without finish(): nothing stays.
  }
  EXPECT_FALSE(fs::exists(dir / "meshes"));
  TerrainMeshWriter writer((dir / "meshes").string(), sphere, {});
  writer.add_surface(bundle, height);
  writer.add_surface(bundle, height);
  const auto files = writer.finish();
  ASSERT_EQ(files.size(), 2u);
  const LoadedMesh m = load_mesh((dir / "meshes" / "frame_00001.obj").string());
  EXPECT_EQ(m.mesh.num_vertices(), sphere.num_vertices());
  EXPECT_NE(test::error_of([&] { TerrainMeshWriter bad((dir / "x").string(), sphere, {"stl", 10, 0.1}); }).find("obj or ply"),
            std::string::npos);
}

}  // namespace
}  // namespace tvf
