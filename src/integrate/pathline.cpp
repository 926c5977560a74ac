#include "tvf/integrate/pathline.h"

#include "tvf/analysis/singularities.h"
#include "tvf/core/error.h"
#include "tvf/integrate/surface_walk.h"

#include <algorithm>
#include <cmath>
#include <optional>

namespace tvf {

double Pathline::length() const {
  double len = 0;
  for (size_t k = 1; k < points.size(); ++k) len += (points[k] - points[k - 1]).norm();
  return len;
}

Pathline trace_pathline(const TangentBundle& bundle, const Field& field, const Vec3& seed,
                        const PathlineOptions& options) {
  const Mesh& mesh = bundle.mesh();
  const SurfacePoint p = closest_point(mesh, seed);
  if (p.face < 0) throw_input_error(mesh.source(), "", "the domain has no faces to trace a pathline on");
  if (const std::string problem = planar_point_problem(mesh, seed, surface_position(mesh, p), "the pathline seed");
      !problem.empty())
    throw_input_error(mesh.source(), "", problem);
  return trace_pathline(bundle, field, p, options);
}

Pathline trace_pathline(const TangentBundle& bundle, const Field& field, const SurfacePoint& seed,
                        const PathlineOptions& options) {
  const Mesh& mesh = bundle.mesh();
  const TimeSampling& time = field.time();
  TVF_CHECK(field.num_vertices() == mesh.num_vertices(), "field of {} vertices on a mesh of {}",
            field.num_vertices(), mesh.num_vertices());
  const double lo = std::min(time.t0, time.t1), hi = std::max(time.t0, time.t1);
  const double slack = 1e-12 * std::max(1.0, hi - lo);
  for (const double t : {options.t_start, options.t_end})
    if (!std::isfinite(t) || t < lo - slack || t > hi + slack)
      throw Error(fmt::format("pathline time {} is outside the field's time range [{}, {}]", t, lo, hi));
  const double span = options.t_end - options.t_start;
  const double frame_dt = time.frames > 1 ? (hi - lo) / (time.frames - 1) : (hi - lo);
  if (!(options.dt >= 0) || !std::isfinite(options.dt))
    throw Error(fmt::format("pathline time step {} must be positive (or 0 for a quarter of the frame spacing)",
                            options.dt));
  double dt = options.dt > 0 ? options.dt : 0.25 * frame_dt;
  if (!(dt > 0)) dt = std::abs(span) > 0 ? std::abs(span) : 1.0;
  if (std::abs(span) / dt > PathlineOptions::kMaxSteps)
    throw Error(fmt::format("pathline time step {:g} would take {:.3g} RK4 steps from t = {} to {}, more than {:g}: "
                            "give a step of at least {:.3g}",
                            dt, std::abs(span) / dt, options.t_start, options.t_end, PathlineOptions::kMaxSteps,
                            std::abs(span) / PathlineOptions::kMaxSteps));
  const double sign = span < 0 ? -1.0 : 1.0;
  double vmax = 0;  // the whole field's largest |V|: only needed for a non-zero stop speed
  if (options.stop_speed > 0)
    for (const cplx& z : field.data()) vmax = std::max(vmax, std::abs(z));
  const double stop = options.stop_speed * vmax;

  const FieldSampler sampler(bundle, field);
  // Face indices of each frame, computed when first needed.
  std::vector<std::vector<int>> index(static_cast<size_t>(time.frames));
  auto singular = [&](int f, double t) {
    if (!options.stop_at_singular_faces) return false;
    int j = 0;
    double w = 0;
    time.locate(t, j, w);
    if (w > 0.5) ++j;
    auto& idx = index[static_cast<size_t>(j)];
    if (idx.empty()) idx = face_indices(bundle, field.frame(j));
    return idx[static_cast<size_t>(f)] != 0;
  };
  auto velocity = [&](const SurfacePoint& p, double t) -> std::optional<cplx> {
    const cplx z = sampler.in_face(p, t);
    if (!(std::abs(z) > stop)) return std::nullopt;
    return z;
  };

  Pathline out;
  auto push = [&](const SurfacePoint& q, double t) {
    out.where.push_back(q);
    out.points.push_back(surface_position(mesh, q));
    out.times.push_back(t);
  };
  SurfacePoint p = seed;
  double t = options.t_start;
  push(p, t);
  out.stop = StopReason::time_range;
  const long steps = static_cast<long>(std::ceil(std::abs(span) / dt - 1e-9));
  double len = 0;
  for (long k = 0; k < steps; ++k) {
    if (singular(p.face, t)) { out.stop = StopReason::singularity; break; }
    const double t_next = k + 1 == steps ? options.t_end : options.t_start + sign * dt * static_cast<double>(k + 1);
    const double h = t_next - t;  // signed
    const auto k1 = velocity(p, t);
    if (!k1) { out.stop = StopReason::singularity; break; }
    auto stage = [&](cplx kv, double frac) -> std::optional<cplx> {
      const SurfaceWalk w = walk_surface(bundle, p, frac * h * kv);
      const auto v = velocity(w.end, t + frac * h);
      if (!v) return std::nullopt;
      return *v / w.transport;
    };
    const auto k2 = stage(*k1, 0.5);
    const auto k3 = k2 ? stage(*k2, 0.5) : std::nullopt;
    const auto k4 = k3 ? stage(*k3, 1.0) : std::nullopt;
    const cplx v = k4 ? (*k1 + 2.0 * *k2 + 2.0 * *k3 + *k4) / 6.0 : *k1;
    const SurfaceWalk w = walk_surface(bundle, p, h * v,
                                       options.stop_at_singular_faces
                                           ? std::function<bool(int)>([&](int f) { return singular(f, t_next); })
                                           : std::function<bool(int)>{});
    p = w.end;
    t = w.hit_boundary || w.stopped ? t + w.travelled * h : t_next;
    const Vec3 prev = out.points.back();
    push(p, t);
    len += (out.points.back() - prev).norm();
    if (w.hit_boundary) { out.stop = StopReason::boundary; break; }
    if (w.stopped) { out.stop = StopReason::singularity; break; }
    if (options.max_length > 0 && len >= options.max_length) { out.stop = StopReason::length; break; }
  }
  return out;
}

}  // namespace tvf
