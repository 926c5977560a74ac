#include "tvf/field/world_vectors.h"

#include "support/test_meshes.h"

#include <gtest/gtest.h>

#include <random>

namespace tvf {
namespace {

Field random_field(int frames, int nv, unsigned seed) {
  Field field(TimeSampling{0.0, 1.0, frames}, nv);
  std::mt19937 rng(seed);
  std::normal_distribution<double> g;
  for (cplx& z : field.data()) z = {g(rng), g(rng)};
  return field;
}

TEST(WorldVectors, AreTheVertexBasesCombinedFrameMajor) {
  for (const auto& [name, mesh] : test::all_meshes()) {
    const TangentBundle bundle(*mesh);
    const int nv = mesh->num_vertices();
    const Field field = random_field(5, nv, 17);
    const std::vector<float> all = world_vectors_f32(bundle, field);
    ASSERT_EQ(all.size(), static_cast<size_t>(5 * nv * 3)) << name;
    for (int j = 0; j < 5; ++j) {
      const std::vector<float> one = world_vectors_f32(bundle, field, j);
      ASSERT_EQ(one.size(), static_cast<size_t>(nv * 3));
      for (int v = 0; v < nv; ++v) {
        const cplx z = field.at(j, v);
        const Vec3 w = z.real() * bundle.vertex_e1(v) + z.imag() * bundle.vertex_e2(v);
        for (int k = 0; k < 3; ++k) {
          const size_t i = (static_cast<size_t>(j) * static_cast<size_t>(nv) + static_cast<size_t>(v)) * 3 + static_cast<size_t>(k);
          EXPECT_EQ(all[i], static_cast<float>(w[k])) << name << " " << j << " " << v;
          EXPECT_EQ(one[static_cast<size_t>(v) * 3 + static_cast<size_t>(k)], all[i]);
        }
        // Tangent to the surface and as long as the tangent vector.
        const Eigen::Vector3f wf(&all[(static_cast<size_t>(j) * static_cast<size_t>(nv) + static_cast<size_t>(v)) * 3]);
        EXPECT_NEAR(wf.cast<double>().norm(), std::abs(z), 1e-6 * (1 + std::abs(z)));
        EXPECT_NEAR(wf.cast<double>().dot(bundle.vertex_normal(v)), 0.0, 1e-6 * (1 + std::abs(z)));
      }
    }
  }
}

TEST(WorldVectors, PlanarFieldIsXYZeroZ) {
  const Mesh& mesh = test::grid_mesh();
  const TangentBundle bundle(mesh);
  const Field field = random_field(2, mesh.num_vertices(), 4);
  const std::vector<float> w = world_vectors_f32(bundle, field);
  for (size_t i = 0; i < field.data().size(); ++i) {
    EXPECT_EQ(w[3 * i], static_cast<float>(field.data()[i].real()));
    EXPECT_EQ(w[3 * i + 1], static_cast<float>(field.data()[i].imag()));
    EXPECT_EQ(w[3 * i + 2], 0.0f);
  }
}

}  // namespace
}  // namespace tvf
