// Planar synthesis: frames keep the exemplar's statistics, stripes follow the field,
// frames of a steady flow move with it and change little otherwise.
#include "tvf/synth/planar_synthesis.h"

#include "support/test_paths.h"
#include "synth_test_support.h"
#include "tvf/mesh/grid.h"

#include <gtest/gtest.h>

#include <numbers>

namespace tvf {
namespace {


SynthesisOptions small_options(int size) {
  SynthesisOptions o;
  o.size = size;
  o.levels = 2;
  o.frame_levels = 1;
  o.iterations_first = 4;
  o.iterations = 2;
  return o;
}

TEST(PlanarSynthesis, FramesKeepTheExemplarsStatistics) {
  const Mesh grid = make_grid(GridSpec{17, 17, {-1, -1}, {1, 1}});
  const TangentBundle bundle(grid);
  const Field field = test::field_from(grid, TimeSampling{0, 1, 3}, [](const Vec3& p, double) { return cplx(-p.y(), p.x()); });
  const Exemplar e = make_procedural_exemplar(ProceduralExemplar::pebbles, 48, 4);
  PlanarSynthesizer synth(bundle, field, e, small_options(96));
  const SynthesisFrameReport& r = synth.advance(0);
  const auto he = test::histogram(e.pixels, 3, 16);
  const auto hs = test::histogram(synth.texture(), 3, 16);
  // Baseline: a flat picture of the exemplar's mean colour, the best a texture-free
  // answer can do, is far off; the synthesized picture is close.
  std::vector<float> flat(synth.texture().size());
  for (size_t i = 0; i < flat.size(); ++i) flat[i] = 0.5f;
  const double synthesized = test::histogram_distance(he, hs, 3);
  const double baseline = test::histogram_distance(he, test::histogram(flat, 3, 16), 3);
  EXPECT_LT(synthesized, 0.35) << synthesized;
  EXPECT_LT(synthesized, 0.3 * baseline);
  // Nearest-patch distance: at most half of that of the exemplar's own pixels shuffled
  // (same histogram, no structure), measured with the same index.
  ExemplarIndexOptions io;
  const ExemplarIndex index(e, io);
  std::vector<float> shuffled;
  random_exemplar_pixels(e, synth.width() * synth.height(), 9, shuffled);
  std::vector<float> q(static_cast<size_t>(index.dimension()));
  double shuffled_distance = 0;
  int n = 0;
  for (int j = 3; j + 3 < synth.height(); j += 5)
    for (int i = 3; i + 3 < synth.width(); i += 5, ++n) {
      for (int row = 0; row < 7; ++row)
        for (int c = 0; c < 7; ++c)
          for (int k = 0; k < 3; ++k)
            q[static_cast<size_t>((row * 7 + c) * 3 + k)] =
                shuffled[(static_cast<size_t>(j + row - 3) * static_cast<size_t>(synth.width()) + static_cast<size_t>(i + c - 3)) * 3 + static_cast<size_t>(k)];
      float d2 = 0;
      index.nearest(q.data(), d2);
      shuffled_distance += d2 / index.dimension();
    }
  shuffled_distance = std::sqrt(shuffled_distance / n);
  EXPECT_LT(r.patch_distance, 0.5 * shuffled_distance) << r.patch_distance << " vs " << shuffled_distance;
  EXPECT_EQ(r.uncovered, 0.0);
}

// Mean stripe-direction error (radians) of the synthesized texture against the field's
// direction, over blocks of the picture.
double stripe_error(const PlanarSynthesizer& synth, int block) {
  const auto l = test::luminance(synth.texture(), 3);
  double total = 0;
  int n = 0;
  for (int y0 = block / 2; y0 + block <= synth.height(); y0 += block)
    for (int x0 = block / 2; x0 + block <= synth.width(); x0 += block) {
      double coherence = 0;
      const double a = test::stripe_angle(l, synth.width(), x0, y0, x0 + block, y0 + block, coherence);
      const auto d = synth.direction(x0 + block / 2, y0 + block / 2);
      if (d[0] == 0 && d[1] == 0) continue;
      total += test::line_angle_difference(a, std::atan2(d[1], d[0]));
      ++n;
    }
  return total / std::max(1, n);
}

TEST(PlanarSynthesis, StripesFollowAUniformField) {
  const Mesh grid = make_grid(GridSpec{9, 9, {-1, -1}, {1, 1}});
  const TangentBundle bundle(grid);
  const Exemplar e = make_procedural_exemplar(ProceduralExemplar::stripes, 48, 2);
  for (double angle : {0.5, 2.0}) {
    const Field field = test::field_from(grid, TimeSampling{0, 1, 2},
                                         [&](const Vec3&, double) { return std::polar(1.0, angle); });
    PlanarSynthesizer synth(bundle, field, e, small_options(96));
    synth.advance(0);
    double coherence = 0;
    const auto l = test::luminance(synth.texture(), 3);
    const double a = test::stripe_angle(l, synth.width(), 0, 0, synth.width(), synth.height(), coherence);
    // Image y is down: the field's angle θ appears as −θ.
    EXPECT_LT(test::line_angle_difference(a, -angle), 0.15) << "field angle " << angle << ", stripes " << a;
    EXPECT_GT(coherence, 0.4);
  }
}

TEST(PlanarSynthesis, StripesFollowACircularField) {
  const Mesh grid = make_grid(GridSpec{17, 17, {-1, -1}, {1, 1}});
  const TangentBundle bundle(grid);
  const Field field = test::field_from(grid, TimeSampling{0, 1, 2}, [](const Vec3& p, double) { return cplx(-p.y(), p.x()); });
  const Exemplar e = make_procedural_exemplar(ProceduralExemplar::stripes, 48, 2);
  PlanarSynthesizer synth(bundle, field, e, small_options(128));
  synth.advance(0);
  const double error = stripe_error(synth, 32);
  EXPECT_LT(error, 0.25) << error;  // a random orientation averages π/4 ≈ 0.785
}

TEST(PlanarSynthesis, FramesMoveWithASteadyFlowAndChangeLittle) {
  const Mesh grid = make_grid(GridSpec{9, 9, {-1, -1}, {1, 1}});
  const TangentBundle bundle(grid);
  const Field field = test::field_from(grid, TimeSampling{0, 1, 11}, [](const Vec3&, double) { return cplx(1, 0); });
  const Exemplar e = make_procedural_exemplar(ProceduralExemplar::pebbles, 48, 4);
  SynthesisOptions o = small_options(96);
  o.pixels_per_frame = 2;  // the texture moves 2 pixels right per frame
  PlanarSynthesizer synth(bundle, field, e, o);
  synth.advance(0);
  std::vector<float> previous = synth.texture();
  const int w = synth.width(), h = synth.height();
  double moved = 0, unrelated = 0;
  PlanarSynthesizer other(bundle, field, e, [&] { auto p = o; p.seed = 99; return p; }());
  other.advance(0);
  for (int k = 1; k <= 3; ++k) {
    synth.advance(0.1 * k);
    const auto& now = synth.texture();
    double s = 0, u = 0;
    int n = 0;
    for (int j = 8; j < h - 8; ++j)
      for (int i = 10; i < w - 8; ++i, ++n)
        for (int c = 0; c < 3; ++c) {
          s += std::abs(now[(static_cast<size_t>(j * w + i)) * 3 + static_cast<size_t>(c)] -
                        previous[(static_cast<size_t>(j * w + i - 2)) * 3 + static_cast<size_t>(c)]);
          u += std::abs(now[(static_cast<size_t>(j * w + i)) * 3 + static_cast<size_t>(c)] -
                        other.texture()[(static_cast<size_t>(j * w + i)) * 3 + static_cast<size_t>(c)]);
        }
    moved = std::max(moved, s / (3.0 * n));
    unrelated += u / (3.0 * n) / 3;
    previous = now;
  }
  // Frame to frame (shifted by the flow), far less change than between two unrelated
  // textures of the same exemplar.
  EXPECT_LT(moved, 0.25 * unrelated) << moved << " vs " << unrelated;
}

// A translation does not stretch the carried texture: nothing is re-seeded. A source
// spreads it: pixels near the source are re-seeded once their area has about doubled.
TEST(PlanarSynthesis, StretchedTextureIsReseededOnlyWhereTheFlowSpreadsIt) {
  const Mesh grid = make_grid(GridSpec{9, 9, {-1, -1}, {1, 1}});
  const TangentBundle bundle(grid);
  const Exemplar e = make_procedural_exemplar(ProceduralExemplar::pebbles, 32, 4);
  SynthesisOptions o = small_options(64);
  o.pixels_per_frame = 3;
  auto run = [&](auto velocity, std::vector<double>& reseeded) {
    const Field field = test::field_from(grid, TimeSampling{0, 1, 11}, velocity);
    PlanarSynthesizer synth(bundle, field, e, o);
    synth.advance(0);
    for (int k = 1; k <= 10; ++k) reseeded.push_back(synth.advance(0.1 * k).reseeded);
    return synth.texture();
  };
  std::vector<double> uniform, source;
  run([](const Vec3&, double) { return cplx(1, 0); }, uniform);
  run([](const Vec3& p, double) { return cplx(p.x(), p.y()); }, source);
  for (double r : uniform) EXPECT_EQ(r, 0.0);
  double total = 0;
  for (double r : source) total += r;
  EXPECT_GT(total, 0.0);
}

TEST(PlanarSynthesis, BadOptionsNameTheOption) {
  const Mesh grid = make_grid(GridSpec{5, 5, {-1, -1}, {1, 1}});
  const TangentBundle bundle(grid);
  const Field field = test::field_from(grid, TimeSampling{0, 1, 2}, [](const Vec3&, double) { return cplx(1, 0); });
  const Exemplar e = make_procedural_exemplar(ProceduralExemplar::stripes, 32);
  auto with = [&](auto change) {
    SynthesisOptions o = small_options(64);
    change(o);
    return test::error_of([&] { PlanarSynthesizer s(bundle, field, e, o); });
  };
  EXPECT_NE(with([](auto& o) { o.neighbourhood = 4; }).find("neighbourhood"), std::string::npos);
  EXPECT_NE(with([](auto& o) { o.temporal_weight = std::nan(""); }).find("temporal_weight"), std::string::npos);
  EXPECT_NE(with([](auto& o) { o.levels = 4; }).find("too small for 4 levels"), std::string::npos);
  EXPECT_NE(with([](auto& o) { o.frame_levels = 3; }).find("frame_levels"), std::string::npos);
}

TEST(PlanarSynthesis, HillshadeIsLitFromTheNorthWest) {
  // A ramp rising to the east: slopes facing west (towards the light) are brighter than
  // a ramp rising to the west.
  std::vector<float> east(32 * 32), west(32 * 32);
  for (int j = 0; j < 32; ++j)
    for (int i = 0; i < 32; ++i) {
      east[static_cast<size_t>(j * 32 + i)] = 0.5f + 0.01f * static_cast<float>(i - 16);
      west[static_cast<size_t>(j * 32 + i)] = 0.5f - 0.01f * static_cast<float>(i - 16);
    }
  const Image a = hillshade(east, 32, 32, 20), b = hillshade(west, 32, 32, 20);
  EXPECT_GT((a.at(16, 16) >> 8) & 0xFF, (b.at(16, 16) >> 8) & 0xFF);
}

}  // namespace
}  // namespace tvf
