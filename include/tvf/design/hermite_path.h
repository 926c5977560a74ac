#pragma once
// A path through control points (position, t), as a function of time: piecewise cubic
// Hermite with Catmull-Rom tangents m_i = (p_{i+1} − p_{i−1}) / (t_{i+1} − t_{i−1})
// (one-sided at the ends). Parametrising by t itself (not by a spline parameter) makes
// the velocity dP/dt exact, so a particle following a regular element's field follows
// the path in design time (DESIGN §4), and keeps t monotone where a spline through
// (x, y, t) could fold back.
#include "tvf/scene/scene.h"

#include <vector>

namespace tvf {

class HermitePath {
public:
  HermitePath() = default;
  // Points must have strictly increasing t (scene_json guarantees it); one point is a
  // path at rest.
  explicit HermitePath(std::vector<PathPoint> points);

  double t_begin() const { return points_.front().t; }
  double t_end() const { return points_.back().t; }
  bool covers(double t) const { return t >= t_begin() && t <= t_end(); }
  Vec3 position(double t) const;  // clamped to [t_begin, t_end]
  Vec3 velocity(double t) const;  // dP/dt (0 for a single point)

private:
  int segment(double t) const;
  std::vector<PathPoint> points_;
  std::vector<Vec3> tangents_;
};

// Linear interpolation of transform keys (sx, sy, θ); identity when there are none,
// constant beyond the first and last keys.
TransformKey interpolate_transform(const std::vector<TransformKey>& keys, double t);
// M = diag(sx, sy)·R(θ).
Mat2 transform_matrix(const TransformKey& k);

}  // namespace tvf
