#include "tvf/design/hermite_path.h"

#include <gtest/gtest.h>

#include <random>

namespace tvf {
namespace {

PathPoint pp(double x, double y, double t) { return {Vec3(x, y, 0), t}; }

TEST(HermitePath, InterpolatesControlPointsAtTheirTimes) {
  HermitePath path({pp(0, 0, 0), pp(1, 2, 0.3), pp(-1, 0.5, 0.7), pp(2, 2, 1)});
  EXPECT_LT((path.position(0) - Vec3(0, 0, 0)).norm(), 1e-15);
  EXPECT_LT((path.position(0.3) - Vec3(1, 2, 0)).norm(), 1e-14);
  EXPECT_LT((path.position(0.7) - Vec3(-1, 0.5, 0)).norm(), 1e-14);
  EXPECT_LT((path.position(1) - Vec3(2, 2, 0)).norm(), 1e-14);
}

TEST(HermitePath, UniformMotionIsReproducedExactly) {
  // Points on a line at constant speed: Catmull-Rom tangents equal the velocity, so the
  // path is that line at that speed everywhere.
  HermitePath path({pp(-1, 0, 0), pp(0, 0.5, 0.5), pp(1, 1, 1)});
  for (double t = 0; t <= 1; t += 0.05) {
    EXPECT_LT((path.position(t) - Vec3(-1 + 2 * t, t, 0)).norm(), 1e-14) << t;
    EXPECT_LT((path.velocity(t) - Vec3(2, 1, 0)).norm(), 1e-13) << t;
  }
}

TEST(HermitePath, VelocityIsTheTimeDerivativeOfPosition) {
  HermitePath path({pp(0, 0, 0.1), pp(1, 2, 0.3), pp(-1, 0.5, 0.45), pp(2, 2, 0.9)});
  std::mt19937 rng(7);
  std::uniform_real_distribution<double> u(0.11, 0.89);
  for (int i = 0; i < 50; ++i) {
    const double t = u(rng), h = 1e-6;
    const Vec3 fd = (path.position(t + h) - path.position(t - h)) / (2 * h);
    EXPECT_LT((path.velocity(t) - fd).norm(), 1e-6 * (1 + fd.norm())) << t;
  }
}

TEST(HermitePath, ContinuousVelocityAtControlPoints) {
  HermitePath path({pp(0, 0, 0), pp(1, 2, 0.3), pp(-1, 0.5, 0.7), pp(2, 2, 1)});
  for (double tk : {0.3, 0.7}) {
    EXPECT_LT((path.velocity(tk - 1e-12) - path.velocity(tk + 1e-12)).norm(), 1e-8);
  }
}

TEST(HermitePath, SinglePointIsAtRest) {
  HermitePath path({pp(0.3, -0.2, 0)});
  EXPECT_EQ(path.position(0.8), Vec3(0.3, -0.2, 0));
  EXPECT_EQ(path.velocity(0.8), Vec3::Zero());
}

TEST(TransformKeys, InterpolateLinearlyAndHoldBeyondTheEnds) {
  std::vector<TransformKey> keys = {{0.2, 1, 2, 0}, {0.6, 3, 1, 1}};
  const TransformKey mid = interpolate_transform(keys, 0.4);
  EXPECT_DOUBLE_EQ(mid.sx, 2);
  EXPECT_DOUBLE_EQ(mid.sy, 1.5);
  EXPECT_DOUBLE_EQ(mid.theta, 0.5);
  EXPECT_DOUBLE_EQ(interpolate_transform(keys, 0).sx, 1);
  EXPECT_DOUBLE_EQ(interpolate_transform(keys, 1).theta, 1);
  const TransformKey none = interpolate_transform({}, 0.5);
  EXPECT_EQ(transform_matrix(none), Mat2::Identity());
}

TEST(TransformKeys, MatrixIsScaleTimesRotation) {
  const Mat2 m = transform_matrix({0, 2, 3, kPi / 2});
  Mat2 expected;
  expected << 0, -2, 3, 0;
  EXPECT_LT((m - expected).norm(), 1e-15);
}

}  // namespace
}  // namespace tvf
