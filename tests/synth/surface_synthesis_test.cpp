// Surface synthesis: the walked neighbourhoods are exact on a flat mesh, frames keep the
// exemplar's statistics on a sphere and change little under a slowly varying field.
#include "tvf/synth/surface_synthesis.h"

#include "support/test_paths.h"
#include "synth_test_support.h"
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
  SurfaceSynthesizer synth(bundle, field, make_procedural_exemplar(ProceduralExemplar::stripes, 16), o);
  synth.advance(0);
  const Neighbourhoods& nb = synth.neighbourhoods();
  const double h = synth.texel();
  for (int v = 0; v < sphere.num_vertices(); v += 97) {
    const Vec3 c = tap_position(sphere, nb.taps[static_cast<size_t>(v * 49 + 3 * 7 + 3)]);
    EXPECT_LT((c - sphere.position(v)).norm(), 1e-9);
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

}  // namespace
}  // namespace tvf
