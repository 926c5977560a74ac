#include "tvf/integrate/streamline.h"

#include "tvf/analysis/singularities.h"
#include "tvf/core/error.h"
#include "tvf/integrate/surface_walk.h"

#include <algorithm>
#include <cmath>
#include <optional>

namespace tvf {

const char* to_string(StopReason r) {
  switch (r) {
    case StopReason::none: return "none";
    case StopReason::length: return "length";
    case StopReason::boundary: return "boundary";
    case StopReason::singularity: return "singularity";
    case StopReason::closed: return "closed";
    case StopReason::rejected: return "rejected";
    case StopReason::time_range: return "time_range";
  }
  return "none";
}

double Streamline::length() const {
  double len = 0;
  for (size_t k = 1; k < points.size(); ++k) len += (points[k] - points[k - 1]).norm();
  return len;
}

std::vector<cplx> values_at(const Field& field, double t) {
  int j = 0;
  double w = 0;
  field.time().locate(t, j, w);
  const auto a = field.frame(j);
  std::vector<cplx> out(a.begin(), a.end());
  if (w > 0) {
    const auto b = field.frame(j + 1);
    for (size_t v = 0; v < out.size(); ++v) out[v] = (1.0 - w) * a[v] + w * b[v];
  }
  return out;
}

double max_speed(std::span<const cplx> values) {
  // √ of the largest |z|² (one pass the compiler vectorises, instead of a hypot call per
  // vertex: the periodic-orbit search traces many short lines per frame, and this scan of
  // every vertex was most of each one's cost on the 20k sphere; issue 15).
  double vmax2 = 0;
  for (const cplx& z : values) vmax2 = std::max(vmax2, std::norm(z));
  return std::sqrt(vmax2);
}

Streamline trace_streamline(const TangentBundle& bundle, std::span<const cplx> values,
                            const Vec3& seed, const StreamlineOptions& options) {
  const Mesh& mesh = bundle.mesh();
  const SurfacePoint p = closest_point(mesh, seed);
  if (p.face < 0) throw_input_error(mesh.source(), "", "the domain has no faces to trace a streamline on");
  if (const std::string problem = planar_point_problem(mesh, seed, surface_position(mesh, p), "the streamline seed");
      !problem.empty())
    throw_input_error(mesh.source(), "", problem);
  return trace_streamline(bundle, values, p, options);
}

Streamline trace_streamline(const TangentBundle& bundle, std::span<const cplx> values,
                            const SurfacePoint& seed, const StreamlineOptions& options) {
  const Mesh& mesh = bundle.mesh();
  TVF_CHECK(values.size() == static_cast<size_t>(mesh.num_vertices()), "{} values for {} vertices",
            values.size(), mesh.num_vertices());
  const double vmax = options.max_speed >= 0 ? options.max_speed : max_speed(values);
  const double h = options.step > 0 ? options.step : 0.5 * mesh.mean_edge_length();
  const double max_len = options.max_length > 0 ? options.max_length : mesh.diameter();
  const double stop = options.stop_speed * vmax;
  std::vector<int> index;
  if (options.stop_at_singular_faces) index = face_indices(bundle, values);
  auto singular = [&](int f) { return !index.empty() && index[static_cast<size_t>(f)] != 0; };
  const std::function<bool(int)> singular_fn = singular;

  const Vec3 x0 = surface_position(mesh, seed);
  const cplx v0 = interpolate_in_face(bundle, values, seed);

  // The unit direction of the field's vector z (of length n = |z|) at a point, in that
  // point's face frame, or nothing at a zero.
  auto unit = [&](cplx z, double n, double sign) -> std::optional<cplx> {
    if (!(n > stop) || n == 0) return std::nullopt;
    return sign * z / n;
  };
  auto direction = [&](const SurfacePoint& p, double sign) -> std::optional<cplx> {
    const cplx z = interpolate_in_face(bundle, values, p);
    return unit(z, std::abs(z), sign);
  };

  // Each step's point, its position and speed (the field there, interpolated once: the
  // speed and the next step's first stage both read it; issue 15).
  std::vector<SurfacePoint> half[2];
  std::vector<Vec3> position[2];
  std::vector<double> speed[2];
  StopReason why[2] = {StopReason::none, StopReason::none};
  const int ndir = options.both_directions ? 2 : 1;
  const long max_steps = static_cast<long>(std::ceil(max_len / h)) + 1;
  for (int dir = 0; dir < ndir; ++dir) {
    const double sign = dir == 0 && !(options.backward_only && !options.both_directions) ? 1.0 : -1.0;
    SurfacePoint p = seed;
    Vec3 xp = x0;
    cplx zp = v0;  // the field at p
    double np = std::abs(v0);
    why[dir] = StopReason::length;
    if (singular(p.face)) {
      why[dir] = StopReason::singularity;
      continue;
    }
    double len = 0;
    for (long step = 0; step < max_steps && len < max_len; ++step) {
      // RK4 with every stage's vector carried back into p's face frame.
      const auto k1 = unit(zp, np, sign);
      if (!k1) { why[dir] = StopReason::singularity; break; }
      auto stage = [&](cplx k, double frac) -> std::optional<cplx> {
        const SurfaceWalk w = walk_surface(bundle, p, frac * h * k);
        const auto d = direction(w.end, sign);
        if (!d) return std::nullopt;
        return *d / w.transport;
      };
      const auto k2 = stage(*k1, 0.5);
      const auto k3 = k2 ? stage(*k2, 0.5) : std::nullopt;
      const auto k4 = k3 ? stage(*k3, 1.0) : std::nullopt;
      // Near a zero a stage may land on it: fall back to the Euler step there.
      const cplx d = k4 ? (*k1 + 2.0 * *k2 + 2.0 * *k3 + *k4) / 6.0 : *k1;
      // Stages that cancel out (|d| of unit vectors under ½: the direction turns by more
      // than about 120° within a step) mean a zero inside the step: a sink or a source.
      const double nd2 = std::norm(d);  // |d|² against ¼: no hypot (|d| ≤ 1, a mean of unit vectors)
      if (nd2 < 0.25) { why[dir] = StopReason::singularity; break; }
      const SurfaceWalk w = walk_surface(bundle, p, h * d, index.empty() ? std::function<bool(int)>{} : singular_fn);
      const SurfacePoint q = w.end;
      const Vec3 xq = surface_position(mesh, q);
      if (options.accept && !options.accept(xq)) { why[dir] = StopReason::rejected; break; }
      p = q;
      zp = interpolate_in_face(bundle, values, p);
      np = std::abs(zp);
      half[dir].push_back(p);
      position[dir].push_back(xq);
      speed[dir].push_back(np);
      len += h * w.travelled * std::sqrt(nd2);
      if (w.hit_boundary) { why[dir] = StopReason::boundary; break; }
      if (w.stopped || singular(p.face)) { why[dir] = StopReason::singularity; break; }
      // Closed orbit: back next to the seed after going some way round.
      // (The last segment passes within half a step of the seed.)
      const Vec3 seg = xq - xp;
      const double u = seg.squaredNorm() > 0 ? std::clamp((x0 - xp).dot(seg) / seg.squaredNorm(), 0.0, 1.0) : 0.0;
      if (options.stop_when_closed && len > 4 * h && (xp + u * seg - x0).norm() < 0.5 * h) {
        why[dir] = StopReason::closed;
        break;
      }
      xp = xq;
    }
    if (why[dir] == StopReason::closed) break;  // the other half would retrace the orbit
  }
  Streamline s;
  const size_t count = half[0].size() + half[1].size() + 1;
  s.where.reserve(count);
  s.points.reserve(count);
  s.speeds.reserve(count);
  auto push = [&](const SurfacePoint& q, const Vec3& x, double sp) {
    s.where.push_back(q);
    s.points.push_back(x);
    s.speeds.push_back(sp);
  };
  for (size_t k = half[1].size(); k-- > 0;) push(half[1][k], position[1][k], speed[1][k]);
  s.seed = s.points.size();
  push(seed, x0, std::abs(v0));
  for (size_t k = 0; k < half[0].size(); ++k) push(half[0][k], position[0][k], speed[0][k]);
  s.stop_forward = why[0];
  s.stop_backward = why[1];
  return s;
}

}  // namespace tvf
