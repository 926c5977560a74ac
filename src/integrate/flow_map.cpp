#include "tvf/integrate/flow_map.h"

#include "tvf/core/error.h"
#include "tvf/integrate/surface_walk.h"

#include "grid_flow.h"

#include <fmt/format.h>
#include <tbb/parallel_for.h>

#include <algorithm>
#include <cmath>

namespace tvf {

namespace {

struct Move {
  SurfacePoint end;
  cplx transport{1.0, 0.0};  // start face frame → end face frame
  bool left = false;         // the displacement points out of the domain at the boundary
};

double dot(cplx a, cplx b) { return a.real() * b.real() + a.imag() * b.imag(); }

// Moves p by d (in p.face's frame) along the surface. At a boundary edge the rest of the
// displacement slides along the edge when its outward part is rounding (under 1e-6 of
// |d|); otherwise the particle has left the domain.
Move move(const TangentBundle& bundle, const SurfacePoint& p, cplx d) {
  const Mesh& mesh = bundle.mesh();
  Move m{p};
  cplx rem = d;
  const double tol = 1e-6 * std::abs(d);
  for (int pass = 0; pass < 8 && std::abs(rem) > 0.0; ++pass) {
    const SurfaceWalk w = walk_surface(bundle, m.end, rem);
    m.end = w.end;
    m.transport = w.transport * m.transport;
    if (!w.hit_boundary) return m;
    rem = (1.0 - w.travelled) * rem * w.transport;  // what is left, in the end face's frame
    const int f = m.end.face;
    int c = 0;  // the corner opposite the boundary edge (its coordinate is 0)
    for (int k = 1; k < 3; ++k)
      if (m.end.bary[k] < m.end.bary[c]) c = k;
    const Face& tri = mesh.face(f);
    const Vec3& a = mesh.position(tri[static_cast<size_t>((c + 1) % 3)]);
    const Vec3& b = mesh.position(tri[static_cast<size_t>((c + 2) % 3)]);
    const Vec3& o = mesh.position(tri[static_cast<size_t>(c)]);
    cplx along = bundle.world_to_face(f, b - a);
    along /= std::abs(along);
    cplx inward = bundle.world_to_face(f, o - a);
    inward -= along * dot(along, inward);
    inward /= std::abs(inward);
    if (dot(rem, inward) < -tol) {
      m.left = true;
      return m;
    }
    rem = along * dot(along, rem);
    // Off the edge by a hair, so that the slide does not stop on it again at once.
    m.end.bary[c] += 1e-9;
    m.end.bary /= m.end.bary.sum();
  }
  return m;
}

}  // namespace

FlowMap::FlowMap(const TangentBundle& bundle, const Field& field, const FlowMapOptions& options)
    : bundle_(bundle), field_(field), sampler_(bundle, field) {
  TVF_CHECK(field.num_vertices() == bundle.mesh().num_vertices(), "field of {} vertices on a mesh of {}",
            field.num_vertices(), bundle.mesh().num_vertices());
  if (!(options.dt >= 0) || !std::isfinite(options.dt))
    throw Error(fmt::format("flow map time step {} must be positive (or 0 for half the frame spacing)", options.dt));
  const TimeSampling& time = field.time();
  const double span = std::abs(time.t1 - time.t0);
  const double frame_dt = time.frames > 1 ? span / (time.frames - 1) : span;
  dt_ = options.dt > 0 ? options.dt : 0.5 * frame_dt;
  if (!(dt_ > 0)) dt_ = 1.0;
  // A step given so small that a particle carried across the time range would take more
  // than kMaxSteps of them (1e-12 over [0, 20]: 2e13, days of RK4 for a command that seems
  // hung). The default, half the frame spacing, is two steps per frame.
  if (options.dt > 0 && span / dt_ > kMaxSteps)
    throw Error(fmt::format("flow map time step {:g} would take {:.3g} RK4 steps over the field's time range of {:g}, "
                            "more than {:g}: give a step of at least {:.3g}",
                            dt_, span / dt_, span, kMaxSteps, span / kMaxSteps));
  // At most kReachEdges mean edge lengths per step at the field's largest speed.
  double vmax = 0;
  for (const cplx& z : field.data()) vmax = std::max(vmax, std::abs(z));
  const double reach = kReachEdges * bundle.mesh().mean_edge_length();
  if (vmax > 0 && reach > 0 && vmax * dt_ > reach) {
    dt_ = reach / vmax;
    if (span / dt_ > kMaxSteps)
      throw Error(fmt::format("the field's speed {:.3g} would take {:.3g} steps of {:g} mean edge lengths ({:.3g}) over "
                              "its time range of {:.3g}: it is too fast for its time range; scale it down",
                              vmax, span / dt_, kReachEdges, reach, span));
  }
  if (!options.walk)
    if (const auto g = detail::detect_grid(bundle)) grid_ = std::make_shared<const detail::GridFlow>(*g, field);
}

void FlowMap::check_time(double t) const {
  const TimeSampling& time = field_.time();
  const double lo = std::min(time.t0, time.t1), hi = std::max(time.t0, time.t1);
  const double slack = 1e-12 * std::max(1.0, hi - lo);
  if (!std::isfinite(t) || t < lo - slack || t > hi + slack)
    throw Error(fmt::format("time {} is outside the field's time range [{}, {}]", t, lo, hi));
}

std::vector<double> FlowMap::knots(double t0, double t1) const {
  // t0, the frame times strictly between, t1 (in the direction of travel).
  const TimeSampling& time = field_.time();
  const double lo = std::min(t0, t1), hi = std::max(t0, t1);
  std::vector<double> inner;
  for (int j = 0; j < time.frames; ++j) {
    const double tj = time.time(j);
    if (tj > lo && tj < hi) inner.push_back(tj);
  }
  std::sort(inner.begin(), inner.end());
  if (t1 < t0) std::reverse(inner.begin(), inner.end());
  std::vector<double> out{t0};
  out.insert(out.end(), inner.begin(), inner.end());
  out.push_back(t1);
  return out;
}

FlowMapResult FlowMap::advect(const SurfacePoint& start, double t0, double t1) const {
  check_time(t0);
  check_time(t1);
  return advect_through(start, knots(t0, t1));
}

FlowMapResult FlowMap::advect_through(const SurfacePoint& start, const std::vector<double>& knots) const {
  FlowMapResult out;
  out.where = start;
  out.t_left = knots.back();
  if (knots.front() == knots.back()) return out;
  if (grid_) {
    const Vec3 x = surface_position(bundle_.mesh(), start);
    Vec2 p(x.x(), x.y());
    out.left = grid_->advect(p, knots, dt_, out.t_left);
    out.where = grid_->to_surface(p);
    return out;
  }
  // Particles are kept strictly inside their faces (moved towards the centroid by 1e-10 of
  // the face): a walk that starts on a vertex or an edge has no well-defined first face and
  // can circle the vertex. The shift is far below the integration error.
  auto inside = [](SurfacePoint q) {
    constexpr double kShift = 1e-10;
    q.bary = (1.0 - kShift) * q.bary + Vec3::Constant(kShift / 3.0);
    return q;
  };
  SurfacePoint p = inside(start);
  for (size_t s = 0; s + 1 < knots.size(); ++s) {
    const double a = knots[s], b = knots[s + 1];
    const long n = std::max(1L, static_cast<long>(std::ceil(std::abs(b - a) / dt_ - 1e-9)));
    const double h = (b - a) / static_cast<double>(n);
    for (long k = 0; k < n; ++k) {
      const double t = a + h * static_cast<double>(k);
      const cplx k1 = sampler_.in_face(p, t);
      auto stage = [&](cplx kv, double frac) {
        const Move m = move(bundle_, p, frac * h * kv);
        return sampler_.in_face(m.end, t + frac * h) / m.transport;
      };
      const cplx k2 = stage(k1, 0.5);
      const cplx k3 = stage(k2, 0.5);
      const cplx k4 = stage(k3, 1.0);
      const Move m = move(bundle_, p, h * (k1 + 2.0 * k2 + 2.0 * k3 + k4) / 6.0);
      p = inside(m.end);
      if (m.left) {
        out.where = p;
        out.left = true;
        out.t_left = t;
        return out;
      }
    }
  }
  out.where = p;
  return out;
}

std::vector<FlowMapResult> FlowMap::advect(std::span<const SurfacePoint> points, double t0, double t1) const {
  check_time(t0);
  check_time(t1);
  const std::vector<double> k = knots(t0, t1);
  std::vector<FlowMapResult> out(points.size());
  tbb::parallel_for(tbb::blocked_range<size_t>(0, points.size(), 16), [&](const tbb::blocked_range<size_t>& r) {
    for (size_t i = r.begin(); i != r.end(); ++i) out[i] = advect_through(points[i], k);
  });
  return out;
}

}  // namespace tvf
