// Planar synthesis: frames keep the exemplar's statistics, stripes follow the field,
// frames of a steady flow move with it and change little otherwise.
#include "tvf/synth/planar_synthesis.h"

#include "support/test_paths.h"
#include "synth_test_support.h"
#include "tvf/mesh/grid.h"

#include <gtest/gtest.h>

#include <algorithm>
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

// The 90th-percentile speed of a field over all its values, as the synthesizer measures it
// (its pixels-per-frame scale).
double p90_speed(const Field& field) {
  std::vector<double> speeds;
  for (const cplx& z : field.data()) speeds.push_back(std::abs(z));
  auto mid = speeds.begin() + static_cast<long>(0.9 * static_cast<double>(speeds.size() - 1));
  std::nth_element(speeds.begin(), mid, speeds.end());
  return *mid;
}

// Mean structure-tensor coherence (0: isotropic, 1: lines) of 16×16 blocks of a picture
// whose centres lie within `radius` pixels of the centre, and the mean squared gradient
// there (smaller when elements grow).
void shape_statistics(const PlanarSynthesizer& synth, double radius, double& coherence, double& energy) {
  const auto l = test::luminance(synth.texture(), 3);
  const int w = synth.width(), h = synth.height();
  coherence = 0;
  energy = 0;
  int n = 0;
  for (int y0 = 0; y0 + 16 <= h; y0 += 8)
    for (int x0 = 0; x0 + 16 <= w; x0 += 8) {
      if (std::hypot(x0 + 8 - 0.5 * w, y0 + 8 - 0.5 * h) > radius) continue;
      double c = 0;
      test::stripe_angle(l, w, x0, y0, x0 + 16, y0 + 16, c);
      coherence += c;
      ++n;
    }
  for (int y = 1; y + 1 < h; ++y)
    for (int x = 1; x + 1 < w; ++x) {
      if (std::hypot(x - 0.5 * w, y - 0.5 * h) > radius) continue;
      const double gx = 0.5 * (l[static_cast<size_t>(y * w + x + 1)] - l[static_cast<size_t>(y * w + x - 1)]);
      const double gy = 0.5 * (l[static_cast<size_t>((y + 1) * w + x)] - l[static_cast<size_t>((y - 1) * w + x)]);
      energy += gx * gx + gy * gy;
    }
  coherence /= std::max(1, n);
}

// A translation does not deform the carried texture; a shear does, without changing its
// area, and the tracked distortion (σ1/σ2 of the advection map's Jacobian) grows without
// renewal and stays bounded with it.
TEST(PlanarSynthesis, DeformationOfTheCarriedTextureIsTrackedAndRenewed) {
  const Mesh grid = make_grid(GridSpec{9, 9, {-1, -1}, {1, 1}});
  const TangentBundle bundle(grid);
  const Exemplar e = make_procedural_exemplar(ProceduralExemplar::pebbles, 32, 4);
  SynthesisOptions o = small_options(64);
  o.pixels_per_frame = 3;
  auto run = [&](auto velocity, double max_distortion, std::vector<SynthesisFrameReport>& reports) {
    const Field field = test::field_from(grid, TimeSampling{0, 1, 31}, velocity);
    SynthesisOptions p = o;
    p.max_distortion = max_distortion;
    PlanarSynthesizer synth(bundle, field, e, p);
    synth.advance(0);
    for (int k = 1; k <= 30; ++k) reports.push_back(synth.advance(k / 30.0));
  };
  std::vector<SynthesisFrameReport> uniform, shear_kept, shear_renewed, source;
  run([](const Vec3&, double) { return cplx(1, 0); }, 1.6, uniform);
  run([](const Vec3& p, double) { return cplx(p.y(), 0); }, 0, shear_kept);
  run([](const Vec3& p, double) { return cplx(p.y(), 0); }, 1.6, shear_renewed);
  run([](const Vec3& p, double) { return cplx(p.x(), p.y()); }, 1.6, source);
  for (const auto& r : uniform) EXPECT_LT(r.distortion, 1.01);
  // 30 frames of shear of 3 pixels per frame at |y| = 1 across 32 pixels: γ ≈ 2.8,
  // σ1 ≈ 3.2 where nothing is renewed.
  EXPECT_GT(shear_kept.back().distortion, 2.5);
  for (const auto& r : shear_kept) EXPECT_EQ(r.reseeded, 0.0);
  double renewed = 0;
  for (const auto& r : shear_renewed) {
    EXPECT_LT(r.distortion, 2.2);
    renewed += r.reseeded;
  }
  EXPECT_GT(renewed, 0.2);
  double spread = 0;
  for (const auto& r : source) spread += r.reseeded;
  EXPECT_GT(spread, 0.2);
}

// Pebbles carried round a vortex whose speed falls off with the radius (differential
// rotation: shear that keeps area) keep their shape: with renewal the blocks stay near the
// first frame's isotropy and gradient energy (size); without it they are drawn into rings.
TEST(PlanarSynthesis, PebblesKeepTheirShapeAndSizeInAVortex) {
  const Mesh grid = make_grid(GridSpec{17, 17, {-1, -1}, {1, 1}});
  const TangentBundle bundle(grid);
  const Exemplar e = make_procedural_exemplar(ProceduralExemplar::pebbles, 48, 4);
  const Field field = test::field_from(grid, TimeSampling{0, 1, 31}, [](const Vec3& p, double) {
    return cplx(-p.y(), p.x()) / (0.05 + p.squaredNorm());
  });
  SynthesisOptions o = small_options(80);
  o.pixels_per_frame = 2;
  double first_coherence = 0, first_energy = 0;
  auto run = [&](double max_distortion, double& coherence, double& energy) {
    SynthesisOptions p = o;
    p.max_distortion = max_distortion;
    PlanarSynthesizer synth(bundle, field, e, p);
    synth.advance(0);
    shape_statistics(synth, 32, first_coherence, first_energy);
    for (int k = 1; k <= 30; ++k) synth.advance(k / 30.0);
    shape_statistics(synth, 32, coherence, energy);
  };
  double kept_coherence = 0, kept_energy = 0, renewed_coherence = 0, renewed_energy = 0;
  run(0, kept_coherence, kept_energy);
  run(1.6, renewed_coherence, renewed_energy);
  // Measured: coherence 0.32 on the first frame, 0.71 after 30 frames without renewal,
  // 0.45 with it; gradient energy 20.3, 15.6 and 17.9.
  EXPECT_LT(renewed_coherence, kept_coherence - 0.15) << renewed_coherence << " vs " << kept_coherence;
  EXPECT_LT(renewed_coherence, first_coherence + 0.2) << renewed_coherence << " vs first " << first_coherence;
  EXPECT_GT(renewed_energy, 0.8 * first_energy) << renewed_energy << " vs first " << first_energy;
  EXPECT_GT(renewed_energy, kept_energy) << renewed_energy << " vs " << kept_energy;
}

// Renewal fades in: under a shear, the change of each 16×16 block from the previous frame
// carried by the flow stays small in every frame (a cell replaced at once would jump).
TEST(PlanarSynthesis, RenewedTextureFadesInWithoutPopping) {
  const Mesh grid = make_grid(GridSpec{9, 9, {-1, -1}, {1, 1}});
  const TangentBundle bundle(grid);
  const Exemplar e = make_procedural_exemplar(ProceduralExemplar::pebbles, 48, 4);
  const TimeSampling ts{0, 1, 25};
  const Field field = test::field_from(grid, ts, [](const Vec3& p, double) { return cplx(p.y(), 0); });
  SynthesisOptions o = small_options(80);
  o.pixels_per_frame = 2;
  // Pixels per unit of y per frame: the synthesizer's speed scale.
  const double shift_per_y = o.pixels_per_frame / p90_speed(field);
  auto worst_block_change = [&](int renew_frames, double& renewed) {
    SynthesisOptions p = o;
    p.renew_frames = renew_frames;
    PlanarSynthesizer synth(bundle, field, e, p);
    synth.advance(0);
    const int w = synth.width(), h = synth.height();
    std::vector<float> previous = synth.texture();
    double worst = 0;
    renewed = 0;
    for (int k = 1; k < ts.frames; ++k) {
      renewed += synth.advance(ts.time(k)).reseeded;
      const auto& now = synth.texture();
      for (int y0 = 8; y0 + 16 <= h - 8; y0 += 16)
        for (int x0 = 16; x0 + 16 <= w - 16; x0 += 16) {
          double change = 0;
          for (int j = y0; j < y0 + 16; ++j) {
            const double y = 1 - (j + 0.5) / (0.5 * h);
            const double src = -shift_per_y * y;  // this row came from src pixels to the left
            for (int i = x0; i < x0 + 16; ++i) {
              const double xs = i + src;
              const int i0 = static_cast<int>(std::floor(xs));
              const double f = xs - i0;
              for (int c = 0; c < 3; ++c) {
                const double before = (1 - f) * previous[(static_cast<size_t>(j * w + i0)) * 3 + static_cast<size_t>(c)] +
                                      f * previous[(static_cast<size_t>(j * w + i0 + 1)) * 3 + static_cast<size_t>(c)];
                change += std::abs(now[(static_cast<size_t>(j * w + i)) * 3 + static_cast<size_t>(c)] - before);
              }
            }
          }
          worst = std::max(worst, change / (16 * 16 * 3));
        }
      previous = now;
    }
    return worst;
  };
  double renewed_faded = 0, renewed_at_once = 0;
  const double faded = worst_block_change(8, renewed_faded);
  const double at_once = worst_block_change(1, renewed_at_once);
  EXPECT_GT(renewed_faded, 0.1);
  EXPECT_GT(renewed_at_once, 0.1);
  // Measured: 0.080 faded over 8 frames, 0.250 renewed at once, 0.199 between unrelated
  // textures.
  EXPECT_LT(faded, 0.5 * at_once) << faded << " vs " << at_once;
  // Against the difference of two unrelated textures of the exemplar (what a block that
  // is replaced at once can change by).
  PlanarSynthesizer a(bundle, field, e, o), b(bundle, field, e, [&] { auto p = o; p.seed = 99; return p; }());
  a.advance(0);
  b.advance(0);
  double unrelated = 0;
  for (size_t i = 0; i < a.texture().size(); ++i) unrelated += std::abs(a.texture()[i] - b.texture()[i]);
  unrelated /= static_cast<double>(a.texture().size());
  EXPECT_LT(faded, 0.5 * unrelated) << faded << " vs unrelated " << unrelated;
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
  EXPECT_NE(with([](auto& o) { o.max_distortion = 0.5; }).find("max_distortion"), std::string::npos);
  EXPECT_NE(with([](auto& o) { o.renew_frames = 0; }).find("renew_frames"), std::string::npos);
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
