#include "tvf/field/time_sampling.h"

#include <gtest/gtest.h>

#include <cmath>
#include <limits>

namespace tvf {
namespace {

TEST(TimeSampling, TimesFollowTheFrameFormula) {
  const TimeSampling ts{-0.5, 2.0, 6};
  const std::vector<double> t = ts.times();
  ASSERT_EQ(t.size(), 6u);
  for (int j = 0; j < 6; ++j) {
    EXPECT_EQ(t[static_cast<size_t>(j)], ts.time(j));
    EXPECT_DOUBLE_EQ(t[static_cast<size_t>(j)], -0.5 + 0.5 * j) << j;
  }
  EXPECT_EQ(t.front(), -0.5);
  EXPECT_EQ(t.back(), 2.0);

  const TimeSampling def;  // [0, 1], 100 frames
  const std::vector<double> d = def.times();
  ASSERT_EQ(d.size(), 100u);
  for (int j = 0; j < 100; ++j) EXPECT_DOUBLE_EQ(d[static_cast<size_t>(j)], j / 99.0);
  EXPECT_EQ(d.back(), 1.0);
}

TEST(TimeSampling, LocateAtFramesReturnsThatFrameExactly) {
  const TimeSampling ts{0.1, 0.7, 7};
  for (int j = 0; j < ts.frames; ++j) {
    int k = -1;
    double w = -1;
    ts.locate(ts.time(j), k, w);
    if (j + 1 < ts.frames) {
      EXPECT_EQ(k, j);
      EXPECT_EQ(w, 0.0);
    } else {
      EXPECT_EQ(k, j - 1);
      EXPECT_EQ(w, 1.0);
    }
  }
}

TEST(TimeSampling, LocateBetweenFramesIsLinear) {
  const TimeSampling ts{-1.0, 3.0, 9};  // frames 0.5 apart
  for (int j = 0; j + 1 < ts.frames; ++j) {
    for (double s : {0.125, 0.3, 0.5, 0.9}) {
      const double t = ts.time(j) + s * 0.5;
      int k = -1;
      double w = -1;
      ts.locate(t, k, w);
      EXPECT_EQ(k, j) << t;
      EXPECT_NEAR(w, s, 1e-14) << t;
      EXPECT_NEAR((1 - w) * ts.time(k) + w * ts.time(k + 1), t, 1e-15);
    }
  }
}

TEST(TimeSampling, LocateClampsToTheRange) {
  const TimeSampling ts{0.0, 1.0, 5};
  int k = -1;
  double w = -1;
  ts.locate(-3.0, k, w);
  EXPECT_EQ(k, 0);
  EXPECT_EQ(w, 0.0);
  ts.locate(1.0 + 1e-9, k, w);
  EXPECT_EQ(k, 3);
  EXPECT_EQ(w, 1.0);
  ts.locate(std::numeric_limits<double>::infinity(), k, w);
  EXPECT_EQ(k, 3);
  EXPECT_EQ(w, 1.0);
  ts.locate(std::nan(""), k, w);
  EXPECT_EQ(k, 0);
  EXPECT_EQ(w, 0.0);
}

TEST(TimeSampling, SingleFrame) {
  const TimeSampling ts{0.25, 0.75, 1};
  EXPECT_EQ(ts.times(), std::vector<double>{0.25});
  for (double t : {-1.0, 0.25, 0.5, 2.0}) {
    int k = -1;
    double w = -1;
    ts.locate(t, k, w);
    EXPECT_EQ(k, 0);
    EXPECT_EQ(w, 0.0);
  }
}

TEST(TimeSampling, EmptyRangeLocatesTheFirstFrame) {
  const TimeSampling ts{0.5, 0.5, 4};
  int k = -1;
  double w = -1;
  ts.locate(0.5, k, w);
  EXPECT_EQ(k, 0);
  EXPECT_EQ(w, 0.0);
}

}  // namespace
}  // namespace tvf
