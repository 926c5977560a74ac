#include "tvf/design/hermite_path.h"

#include "tvf/core/error.h"

#include <algorithm>
#include <cmath>

namespace tvf {

HermitePath::HermitePath(std::vector<PathPoint> points) : points_(std::move(points)) {
  TVF_CHECK(!points_.empty(), "a path needs at least one point");
  const size_t n = points_.size();
  tangents_.assign(n, Vec3::Zero());
  if (n < 2) return;
  for (size_t i = 0; i < n; ++i) {
    const size_t a = i == 0 ? 0 : i - 1;
    const size_t b = i + 1 == n ? n - 1 : i + 1;
    const double dt = points_[b].t - points_[a].t;
    TVF_CHECK(dt > 0, "path times must increase (points {} and {})", a, b);
    tangents_[i] = (points_[b].position - points_[a].position) / dt;
  }
}

int HermitePath::segment(double t) const {
  // Last point with t_i <= t, limited to the last segment's start.
  const auto it = std::upper_bound(points_.begin(), points_.end(), t,
                                   [](double x, const PathPoint& p) { return x < p.t; });
  const auto i = static_cast<int>(it - points_.begin()) - 1;
  return std::clamp(i, 0, static_cast<int>(points_.size()) - 2);
}

Vec3 HermitePath::position(double t) const {
  if (points_.size() == 1) return points_[0].position;
  t = std::clamp(t, t_begin(), t_end());
  const auto i = static_cast<size_t>(segment(t));
  const PathPoint& a = points_[i];
  const PathPoint& b = points_[i + 1];
  const double h = b.t - a.t;
  const double s = (t - a.t) / h;
  const double s2 = s * s, s3 = s2 * s;
  const double h00 = 2 * s3 - 3 * s2 + 1, h10 = s3 - 2 * s2 + s;
  const double h01 = -2 * s3 + 3 * s2, h11 = s3 - s2;
  return h00 * a.position + h10 * h * tangents_[i] + h01 * b.position + h11 * h * tangents_[i + 1];
}

Vec3 HermitePath::velocity(double t) const {
  if (points_.size() == 1) return Vec3::Zero();
  t = std::clamp(t, t_begin(), t_end());
  const auto i = static_cast<size_t>(segment(t));
  const PathPoint& a = points_[i];
  const PathPoint& b = points_[i + 1];
  const double h = b.t - a.t;
  const double s = (t - a.t) / h;
  const double s2 = s * s;
  const double d00 = 6 * s2 - 6 * s, d10 = 3 * s2 - 4 * s + 1;
  const double d01 = -6 * s2 + 6 * s, d11 = 3 * s2 - 2 * s;
  return (d00 * a.position + d01 * b.position) / h + d10 * tangents_[i] + d11 * tangents_[i + 1];
}

TransformKey interpolate_transform(const std::vector<TransformKey>& keys, double t) {
  if (keys.empty()) return TransformKey{t, 1, 1, 0};
  if (t <= keys.front().t) return keys.front();
  if (t >= keys.back().t) return keys.back();
  const auto it = std::upper_bound(keys.begin(), keys.end(), t,
                                   [](double x, const TransformKey& k) { return x < k.t; });
  const TransformKey& b = *it;
  const TransformKey& a = *(it - 1);
  const double w = (t - a.t) / (b.t - a.t);
  return {t, (1 - w) * a.sx + w * b.sx, (1 - w) * a.sy + w * b.sy,
          (1 - w) * a.theta + w * b.theta};
}

Mat2 transform_matrix(const TransformKey& k) {
  const double c = std::cos(k.theta), s = std::sin(k.theta);
  Mat2 r;
  r << c, -s, s, c;
  return Eigen::DiagonalMatrix<double, 2>(k.sx, k.sy) * r;
}

}  // namespace tvf
