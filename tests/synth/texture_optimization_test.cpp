// The optimization core: exact matches are found, and E/M iterations lower the energy.
#include "tvf/synth/texture_optimization.h"

#include "support/test_paths.h"

#include <gtest/gtest.h>

#include <random>

namespace tvf {
namespace {

TEST(ExemplarIndex, FindsEveryExemplarNeighbourhoodExactly) {
  const Exemplar e = make_procedural_exemplar(ProceduralExemplar::pebbles, 32, 5);
  ExemplarIndexOptions o;
  o.size = 5;
  o.search_eps = 0;  // exact search in the reduced space
  const ExemplarIndex index(e, o);
  EXPECT_EQ(index.count(), 32 * 32);  // tileable: one neighbourhood per pixel
  EXPECT_EQ(index.dimension(), 5 * 5 * 3);
  EXPECT_GT(index.explained_variance(), 0.5);
  EXPECT_LE(index.explained_variance(), 1.0 + 1e-9);
  std::mt19937 rng(1);
  for (int trial = 0; trial < 50; ++trial) {
    const int m = std::uniform_int_distribution<int>(0, index.count() - 1)(rng);
    float d2 = -1;
    const int found = index.nearest(index.values(m), d2);
    EXPECT_NEAR(d2, 0.f, 1e-6f) << m << " found " << found;
  }
}

TEST(ExemplarIndex, NonTileableExemplarsKeepNeighbourhoodsInside) {
  Exemplar e = make_procedural_exemplar(ProceduralExemplar::stripes, 20);
  e.tileable = false;
  const ExemplarIndex index(e, {});
  EXPECT_EQ(index.count(), (20 - 7 + 1) * (20 - 7 + 1));
  for (int m = 0; m < index.count(); ++m) {
    const auto p = index.position(m);
    ASSERT_LE(p[0] + 7, 20);
    ASSERT_LE(p[1] + 7, 20);
  }
  Exemplar small(5, 5, 3);
  EXPECT_NE(test::error_of([&] { ExemplarIndex bad(small, {}); }).find("smaller than one 7×7"), std::string::npos);
}

// A periodic grid of axis-aligned neighbourhoods (every sample a centre, wrapping).
Neighbourhoods grid_neighbourhoods(int w, int h, int size) {
  Neighbourhoods nb;
  nb.size = size;
  const int R = size / 2;
  for (int j = 0; j < h; ++j)
    for (int i = 0; i < w; ++i)
      for (int r = 0; r < size; ++r)
        for (int c = 0; c < size; ++c) {
          Tap t;
          t.sample[0] = ((j + r - R + h) % h) * w + (i + c - R + w) % w;
          t.weight[0] = 1;
          nb.taps.push_back(t);
        }
  return nb;
}

TEST(TextureOptimization, IterationsLowerThePatchDistance) {
  const Exemplar e = make_procedural_exemplar(ProceduralExemplar::stripes, 32, 2);
  ExemplarIndexOptions io;
  io.size = 5;
  const ExemplarIndex index(e, io);
  const Neighbourhoods nb = grid_neighbourhoods(48, 48, 5);
  std::vector<float> x;
  random_exemplar_pixels(e, 48 * 48, 7, x);
  OptimizeOptions o;
  o.iterations = 1;
  std::vector<double> distance;
  for (int k = 0; k < 6; ++k) distance.push_back(optimize_texture(nb, index, x, {}, o).patch_distance);
  // The first E-step sees random pixels; the last sees a texture made of exemplar patches.
  EXPECT_LT(distance.back(), 0.5 * distance.front()) << distance.front() << " → " << distance.back();
  EXPECT_LE(distance.back(), distance[2] + 1e-3);
}

TEST(TextureOptimization, TemporalTargetPullsTowardsIt) {
  const Exemplar e = make_procedural_exemplar(ProceduralExemplar::stripes, 32, 2);
  ExemplarIndexOptions io;
  io.size = 5;
  const ExemplarIndex index(e, io);
  const Neighbourhoods nb = grid_neighbourhoods(32, 32, 5);
  std::vector<float> start;
  random_exemplar_pixels(e, 32 * 32, 3, start);
  std::vector<float> target(start.size(), 0.5f);
  auto distance_to_target = [&](double lambda) {
    std::vector<float> x = start;
    OptimizeOptions o;
    o.iterations = 2;
    o.temporal_weight = lambda;
    o.histogram_matching = false;  // the soft target alone
    optimize_texture(nb, index, x, target, o);
    double s = 0;
    for (size_t i = 0; i < x.size(); ++i) s += std::abs(x[i] - target[i]);
    return s / static_cast<double>(x.size());
  };
  const double free = distance_to_target(0), soft = distance_to_target(1), hard = distance_to_target(50);
  EXPECT_LT(soft, free);
  EXPECT_LT(hard, soft);
  EXPECT_LT(hard, 0.02);
}

}  // namespace
}  // namespace tvf
