// Surface synthesis: the walked neighbourhoods are exact on a flat mesh, frames keep the
// exemplar's statistics on a sphere and change little under a slowly varying field.
#include "tvf/synth/surface_synthesis.h"

#include "support/test_paths.h"
#include "synth_test_support.h"
#include "tvf/mesh/face_subdivision.h"
#include "tvf/mesh/grid.h"
#include "tvf/mesh/primitives.h"

#include <gtest/gtest.h>

namespace tvf {
namespace {

Vec3 tap_position(const Mesh& mesh, const Tap& t) {
  Vec3 p = Vec3::Zero();
  for (size_t i = 0; i < 4; ++i) p += static_cast<double>(t.weight[i]) * mesh.position(t.sample[i]);
  return p;
}

TEST(SurfaceSynthesis, WalkedNeighbourhoodsAreTheRotatedGridOnAFlatMesh) {
  const Mesh grid = make_grid(GridSpec{41, 41, {-1, -1}, {1, 1}});
  const TangentBundle bundle(grid);
  const double angle = 0.7;
  const Field field = test::field_from(grid, TimeSampling{0, 1, 2}, [&](const Vec3&, double) { return std::polar(2.0, angle); });
  SynthesisOptions o;
  o.levels = 1;
  o.frame_levels = 1;
  o.iterations_first = 1;
  o.neighbourhood = 5;
  o.texel = 0.03;
  o.density = 1;
  SurfaceSynthesizer synth(bundle, field, make_procedural_exemplar(ProceduralExemplar::stripes, 16), o);
  synth.advance(0);
  const Neighbourhoods& nb = synth.neighbourhoods();
  ASSERT_EQ(nb.count(), grid.num_vertices());
  const cplx u = std::polar(1.0, angle), v = cplx(0, -1) * u;  // v: u turned clockwise
  const int centre = 20 * 41 + 20;  // the vertex at the origin
  for (int r = 0; r < 5; ++r)
    for (int c = 0; c < 5; ++c) {
      const cplx expected = 0.03 * (double(c - 2) * u + double(r - 2) * v);
      const Vec3 p = tap_position(grid, nb.taps[static_cast<size_t>(centre * 25 + r * 5 + c)]);
      EXPECT_NEAR(p.x(), expected.real(), 1e-6) << r << "," << c;
      EXPECT_NEAR(p.y(), expected.imag(), 1e-6) << r << "," << c;
    }
}

TEST(SurfaceSynthesis, WalkedNeighbourhoodsStayOnTheSphereAtTheirDistance) {
  const Mesh sphere = make_icosphere(4);
  const TangentBundle bundle(sphere);
  const Field field = test::field_from(sphere, TimeSampling{0, 1, 2}, [&](const Vec3& p, double) { return cplx(-p.y(), p.x()); });
  SynthesisOptions o;
  o.levels = 1;
  o.iterations_first = 1;
  o.frame_levels = 1;
  o.density = 1;
  SurfaceSynthesizer synth(bundle, field, make_procedural_exemplar(ProceduralExemplar::stripes, 16), o);
  synth.advance(0);
  const Neighbourhoods& nb = synth.neighbourhoods();
  const double h = synth.texel();
  for (int v = 0; v < sphere.num_vertices(); v += 97) {
    const Vec3 c = tap_position(sphere, nb.taps[static_cast<size_t>(v * 49 + 3 * 7 + 3)]);
    EXPECT_LT((c - sphere.position(v)).norm(), 1e-7);  // walks start a hair inside a face
    // The corner tap is about 3√2 spacings away (geodesic, so a little less in a straight line).
    const Vec3 corner = tap_position(sphere, nb.taps[static_cast<size_t>(v * 49)]);
    EXPECT_NEAR((corner - c).norm(), 3 * std::sqrt(2.0) * h, 0.15 * 3 * std::sqrt(2.0) * h) << v;
  }
}

TEST(SurfaceSynthesis, SphereFramesKeepStatisticsAndChangeLittle) {
  const Mesh sphere = make_icosphere(4);  // 2,562 vertices
  const TangentBundle bundle(sphere);
  // A slowly turning rotation field: world vectors axis(t) × p.
  Field rotation(TimeSampling{0, 1, 21}, sphere.num_vertices());
  for (int j = 0; j < 21; ++j) {
    const double t = rotation.time().time(j);
    const Vec3 axis = Vec3(std::sin(0.3 * t), 0, std::cos(0.3 * t));
    for (int v = 0; v < sphere.num_vertices(); ++v)
      rotation.at(j, v) = bundle.world_to_vertex(v, axis.cross(sphere.position(v)));
  }
  const Exemplar e = make_procedural_exemplar(ProceduralExemplar::pebbles, 32, 4);
  SynthesisOptions o;
  o.levels = 2;
  o.frame_levels = 1;
  o.texel = sphere.mean_edge_length();
  o.density = 1;
  SurfaceSynthesizer synth(bundle, rotation, e, o);
  const SynthesisFrameReport first = synth.advance(0);
  const double hist = test::histogram_distance(test::histogram(e.pixels, 3, 16), test::histogram(synth.values(), 3, 16), 3);
  EXPECT_LT(hist, 0.4) << hist;
  EXPECT_EQ(first.uncovered, 0.0);
  std::vector<float> shuffled;
  random_exemplar_pixels(e, sphere.num_vertices(), 5, shuffled);
  SurfaceSynthesizer other(bundle, rotation, e, [&] { auto p = o; p.seed = 77; return p; }());
  other.advance(0);
  auto mean_difference = [](const std::vector<float>& a, const std::vector<float>& b) {
    double s = 0;
    for (size_t i = 0; i < a.size(); ++i) s += std::abs(a[i] - b[i]);
    return s / static_cast<double>(a.size());
  };
  const double unrelated = mean_difference(synth.values(), other.values());
  std::vector<float> previous = synth.values();
  double worst = 0;
  for (int k = 1; k <= 3; ++k) {
    synth.advance(0.05 * k);
    worst = std::max(worst, mean_difference(previous, synth.values()));
    previous = synth.values();
  }
  EXPECT_LT(worst, 0.35 * unrelated) << worst << " vs " << unrelated;
}

// Refined samples: density 2 synthesizes on the faces split in four (|V| + |E| samples),
// the field resampled there, and the result still looks like the exemplar; the automatic
// density gives at least 60,000 samples.
TEST(SurfaceSynthesis, RefinedSamplesAreFinerThanTheMeshAndKeepTheStatistics) {
  const Mesh sphere = make_icosphere(3);  // 642 vertices, 1,920 edges
  const TangentBundle bundle(sphere);
  Field rotation(TimeSampling{0, 1, 3}, sphere.num_vertices());
  for (int j = 0; j < 3; ++j)
    for (int v = 0; v < sphere.num_vertices(); ++v)
      rotation.at(j, v) = bundle.world_to_vertex(v, Vec3(0, 0, 1).cross(sphere.position(v)));
  const Exemplar e = make_procedural_exemplar(ProceduralExemplar::pebbles, 32, 4);
  SynthesisOptions o;
  o.levels = 2;
  o.frame_levels = 1;
  o.density = 2;
  SurfaceSynthesizer synth(bundle, rotation, e, o);
  EXPECT_EQ(synth.density(), 2);
  ASSERT_EQ(synth.sample_mesh().num_vertices(), sphere.num_vertices() + sphere.num_edges());
  EXPECT_NEAR(synth.texel(), synth.sample_mesh().mean_edge_length(), 1e-12);
  EXPECT_LT(synth.texel(), 0.6 * sphere.mean_edge_length());
  const SynthesisFrameReport first = synth.advance(0);
  ASSERT_EQ(synth.values().size(), static_cast<size_t>(synth.sample_mesh().num_vertices()) * 3);
  EXPECT_EQ(first.uncovered, 0.0);
  const double hist = test::histogram_distance(test::histogram(e.pixels, 3, 16), test::histogram(synth.values(), 3, 16), 3);
  EXPECT_LT(hist, 0.4) << hist;
  synth.advance(0.5);
  EXPECT_EQ(synth.colours().size(), static_cast<size_t>(synth.sample_mesh().num_vertices()));
  ASSERT_EQ(&synth.sample_bundle().mesh(), &synth.sample_mesh());
  // Automatic density: the smallest with 60,000 samples, at most 8 per edge (this small
  // mesh reaches the cap; a 20,000-vertex one gets 2).
  SynthesisOptions a = o;
  a.density = 0;
  SurfaceSynthesizer automatic(bundle, rotation, e, a);
  EXPECT_EQ(automatic.density(), 8);
  EXPECT_EQ(automatic.sample_mesh().num_vertices(), subdivision_vertex_count(sphere, 8));
  const Mesh large = make_icosphere(5);  // 10,242 vertices: 2 gives 40,962, 3 gives 92,162
  const TangentBundle large_bundle(large);
  const Field still(TimeSampling{0, 1, 2}, large.num_vertices());
  SurfaceSynthesizer large_automatic(large_bundle, still, e, a);
  EXPECT_EQ(large_automatic.density(), 3);
  SynthesisOptions bad = o;
  bad.density = 9;
  EXPECT_NE(test::error_of([&] { SurfaceSynthesizer s(bundle, rotation, e, bad); }).find("density"), std::string::npos);
}

// The field resampled on a subdivision: on a flat grid a linear field is reproduced exactly
// at the new vertices (barycentric interpolation is exact, the bases are the same); on a
// sphere a rotation field keeps its length and stays the rotation, up to the facets.
TEST(SurfaceSynthesis, ResampledFieldIsTheFieldAtTheNewVertices) {
  const Mesh grid = make_grid(GridSpec{5, 5, {-1, -1}, {1, 1}});
  const TangentBundle gb(grid);
  const Field linear = test::field_from(grid, TimeSampling{0, 1, 2}, [](const Vec3& p, double t) {
    return cplx(p.x() + 2 * p.y() + t, 0.5 - p.x() * t);
  });
  const FaceSubdivision sub = subdivide_faces(grid, 3);
  const TangentBundle sb(sub.mesh);
  const Field fine = resample_field(gb, linear, sb, sub);
  ASSERT_EQ(fine.num_vertices(), sub.mesh.num_vertices());
  ASSERT_EQ(fine.frames(), 2);
  for (int v = 0; v < sub.mesh.num_vertices(); v += 7)
    for (int j = 0; j < 2; ++j) {
      const Vec3& p = sub.mesh.position(v);
      const double t = j;
      EXPECT_NEAR(std::abs(fine.at(j, v) - cplx(p.x() + 2 * p.y() + t, 0.5 - p.x() * t)), 0.0, 1e-9) << v;
    }
  const Mesh sphere = make_icosphere(2);
  const TangentBundle b(sphere);
  Field rotation(TimeSampling{0, 1, 2}, sphere.num_vertices());
  for (int j = 0; j < 2; ++j)
    for (int v = 0; v < sphere.num_vertices(); ++v)
      rotation.at(j, v) = b.world_to_vertex(v, Vec3(0, 0, 1).cross(sphere.position(v)));
  const FaceSubdivision s2 = subdivide_faces(sphere, 2);
  const TangentBundle b2(s2.mesh);
  const Field r2 = resample_field(b, rotation, b2, s2);
  for (int v = 0; v < s2.mesh.num_vertices(); ++v) {
    const Vec3 p = s2.mesh.position(v);
    const Vec3 want = Vec3(0, 0, 1).cross(p);
    const Vec3 got = b2.vertex_to_world(v, r2.at(0, v));
    EXPECT_LT((got - want).norm(), 0.1 * std::max(want.norm(), 0.05)) << v;
  }
}

}  // namespace
}  // namespace tvf
