#include "tvf/integrate/ftle.h"

#include "tvf/core/error.h"

#include "grid_flow.h"

#include <tbb/parallel_for.h>

#include <algorithm>
#include <cmath>
#include <limits>

namespace tvf {

const char* to_string(HorizonPolicy p) {
  switch (p) {
    case HorizonPolicy::clamp: return "clamp";
    case HorizonPolicy::nan: return "nan";
  }
  return "?";
}

namespace {

constexpr float kNaN = std::numeric_limits<float>::quiet_NaN();

// Vertex v as a point of one of its faces.
SurfacePoint vertex_point(const Mesh& mesh, int v) {
  const int h = mesh.outgoing(v).front();
  SurfacePoint p;
  p.face = Mesh::face_of(h);
  p.bary = Vec3::Zero();
  p.bary[h % 3] = 1.0;
  return p;
}

// The one-ring neighbours of v (heads of its outgoing halfedges, and on the boundary the
// last neighbour, reached through the previous halfedge of the last face).
void one_ring(const Mesh& mesh, int v, std::vector<int>& out) {
  out.clear();
  for (const int h : mesh.outgoing(v)) {
    out.push_back(mesh.head(h));
    out.push_back(mesh.tail(Mesh::prev(h)));
  }
  std::sort(out.begin(), out.end());
  out.erase(std::unique(out.begin(), out.end()), out.end());
}

}  // namespace

std::vector<float> ftle_from_flow_map(const TangentBundle& bundle, const std::vector<FlowMapResult>& mapped,
                                      double span) {
  const Mesh& mesh = bundle.mesh();
  TVF_CHECK(mapped.size() == static_cast<size_t>(mesh.num_vertices()), "{} mapped points for {} vertices",
            mapped.size(), mesh.num_vertices());
  std::vector<float> out(mapped.size(), kNaN);
  if (!(span > 0)) return out;
  std::vector<Vec3> end(mapped.size());
  for (size_t v = 0; v < mapped.size(); ++v)
    if (!mapped[v].left) end[v] = surface_position(mesh, mapped[v].where);
  tbb::parallel_for(tbb::blocked_range<int>(0, mesh.num_vertices(), 256), [&](const tbb::blocked_range<int>& r) {
    std::vector<int> ring;
    for (int v = r.begin(); v != r.end(); ++v) {
      const FlowMapResult& m = mapped[static_cast<size_t>(v)];
      if (m.left) continue;
      one_ring(mesh, v, ring);
      const Vec3& e1 = bundle.vertex_e1(v);
      const Vec3& e2 = bundle.vertex_e2(v);
      const int f = m.where.face;
      const Vec3& g1 = bundle.face_e1(f);
      const Vec3& g2 = bundle.face_e2(f);
      Eigen::Matrix2d xx = Eigen::Matrix2d::Zero(), yx = Eigen::Matrix2d::Zero();
      int used = 0;
      for (const int u : ring) {
        if (mapped[static_cast<size_t>(u)].left) continue;
        const Vec3 dx = mesh.position(u) - mesh.position(v);
        const Vec3 dy = end[static_cast<size_t>(u)] - end[static_cast<size_t>(v)];
        const Eigen::Vector2d x(dx.dot(e1), dx.dot(e2));
        const Eigen::Vector2d y(dy.dot(g1), dy.dot(g2));
        xx += x * x.transpose();
        yx += y * x.transpose();
        ++used;
      }
      const double scale = xx.trace();
      if (used < 2 || !(xx.determinant() > 1e-10 * scale * scale)) continue;
      const Eigen::Matrix2d F = yx * xx.inverse();
      // Largest singular value: the square root of FᵀF's larger eigenvalue.
      const Eigen::Matrix2d C = F.transpose() * F;
      const double half_trace = 0.5 * (C(0, 0) + C(1, 1));
      const double d = 0.5 * (C(0, 0) - C(1, 1));
      const double lambda = half_trace + std::sqrt(d * d + C(0, 1) * C(0, 1));
      if (!(lambda > 0)) continue;
      out[static_cast<size_t>(v)] = static_cast<float>(0.5 * std::log(lambda) / span);
    }
  });
  return out;
}

namespace {

// A horizon so short that the flow map moves no particle by a millionth of an edge: the
// fit's φ(u) − φ(v) is then the rounding of the positions (relative error ~1e-16 of the
// coordinates over an edge), not the flow's stretch, and σ comes out 0 or noise (the double
// gyre at T = 1e-300: 0 everywhere; the limit T → 0 is the largest eigenvalue of ∇V's
// symmetric part, ~1 there). At a millionth of an edge the rounding is ~1e-5 of the
// stretch on a 100-edge domain. A field that is zero everywhere moves nothing at any
// horizon, and its σ = 0 is faithful.
void check_horizon(const Mesh& mesh, const Field& field, double horizon) {
  if (!(horizon > 0) || !std::isfinite(horizon))
    throw Error(fmt::format("FTLE horizon {} must be a positive time", horizon));
  double speed = 0.0;
  for (const cplx& v : field.data()) speed = std::max(speed, std::abs(v));
  const double resolved = 1e-6 * mesh.mean_edge_length();
  if (speed > 0 && std::isfinite(speed) && speed * horizon < resolved)
    throw Error(fmt::format("FTLE horizon {:.3g} carries no particle further than {:.3g} (the field's largest "
                            "speed {:.3g} times the horizon), under a millionth of the mean edge length {:.3g}: "
                            "the flow map's stretch is lost to rounding; give a horizon of at least {:.3g}",
                            horizon, speed * horizon, speed, mesh.mean_edge_length(), resolved / speed));
  // t ± T must differ from t as a double, or every window is empty (NaN).
  const TimeSampling& time = field.time();
  const double latest = std::max(std::abs(time.t0), std::abs(time.t1));
  if ((latest + horizon) - latest < 0.5 * horizon)
    throw Error(fmt::format("FTLE horizon {:.3g} is below the resolution of the field's times (up to {:.3g}): "
                            "t + T rounds to t; give a longer horizon",
                            horizon, latest));
}

// One time, one direction, with the flow map and the vertices' start points made once.
FtleSlice slice(const TangentBundle& bundle, const FlowMap& flow, std::span<const SurfacePoint> starts, double t0,
                double horizon, int dir, HorizonPolicy policy) {
  const TimeSampling& time = flow.field().time();
  const double lo = std::min(time.t0, time.t1), hi = std::max(time.t0, time.t1);
  FtleSlice s;
  double t1 = t0 + dir * horizon;
  s.cut = t1 > hi + 1e-12 * (hi - lo) || t1 < lo - 1e-12 * (hi - lo);
  if (s.cut) t1 = std::clamp(t1, lo, hi);
  if ((s.cut && policy == HorizonPolicy::nan) || t1 == t0) {
    s.values.assign(starts.size(), kNaN);
    return s;
  }
  const std::vector<FlowMapResult> mapped = flow.advect(starts, t0, t1);
  for (const auto& m : mapped) s.left += m.left;
  s.span = std::abs(t1 - t0);
  s.values = ftle_from_flow_map(bundle, mapped, s.span);
  return s;
}

std::vector<SurfacePoint> vertex_starts(const Mesh& mesh) {
  std::vector<SurfacePoint> starts(static_cast<size_t>(mesh.num_vertices()));
  for (int v = 0; v < mesh.num_vertices(); ++v) starts[static_cast<size_t>(v)] = vertex_point(mesh, v);
  return starts;
}

// compute_ftle with FtleOptions::compose on a planar grid.
void compose_series(const TangentBundle& bundle, const Field& field, const FlowMap& flow,
                    const detail::GridLayout& layout, const FtleOptions& options, const std::vector<int>& frames,
                    FtleResult& r) {
  const detail::GridFlow grid(layout, field);
  const TimeSampling& time = field.time();
  const int n = field.frames(), nv = r.vertices;
  const double lo = std::min(time.t0, time.t1), hi = std::max(time.t0, time.t1);
  const double eps = 1e-9 * std::max(1e-300, (hi - lo) / std::max(1, n - 1));
  auto start = [&](int v) {
    const Vec3& x = bundle.mesh().position(v);
    return Vec2(x.x(), x.y());
  };
  // One-step maps of every frame interval k (t_k → t_{k+1} forward, back for backward),
  // at every vertex: where it goes, and whether it left.
  struct Step {
    std::vector<Vec2> to;
    std::vector<char> left;
  };
  auto steps = [&](int dir) {
    Step m;
    if (n < 2) return m;
    const size_t size = static_cast<size_t>(n - 1) * static_cast<size_t>(nv);
    m.to.resize(size);
    m.left.resize(size);
    tbb::parallel_for(tbb::blocked_range<size_t>(0, size, 256), [&](const tbb::blocked_range<size_t>& rr) {
      for (size_t i = rr.begin(); i != rr.end(); ++i) {
        const int k = static_cast<int>(i / static_cast<size_t>(nv)), v = static_cast<int>(i % static_cast<size_t>(nv));
        Vec2 p = start(v);
        double t_left = 0.0;
        const std::vector<double> knots = dir > 0 ? std::vector<double>{time.time(k), time.time(k + 1)}
                                                  : std::vector<double>{time.time(k + 1), time.time(k)};
        m.left[i] = grid.advect(p, knots, flow.dt(), t_left);
        m.to[i] = p;
      }
    });
    return m;
  };
  // The one-step map of interval k at p (barycentric in p's triangle); false: it left.
  auto apply = [&](const Step& m, int k, Vec2& p) {
    std::array<int, 3> c{};
    Vec3 w;
    grid.corners(p, c, w);
    Vec2 q = Vec2::Zero();
    const size_t base = static_cast<size_t>(k) * static_cast<size_t>(nv);
    for (int a = 0; a < 3; ++a) {
      const size_t i = base + static_cast<size_t>(c[static_cast<size_t>(a)]);
      if (w[a] > 1e-12 && m.left[i]) return false;
      q += w[a] * m.to[i];
    }
    p = q;
    return true;
  };
  const int total = static_cast<int>(frames.size()) * (options.forward + options.backward);
  int done = 0;
  for (const int dir : {1, -1}) {
    if ((dir > 0 && !options.forward) || (dir < 0 && !options.backward)) continue;
    const Step m = steps(dir);
    std::vector<float>& values = dir > 0 ? r.forward : r.backward;
    std::vector<double>& spans = dir > 0 ? r.forward_span : r.backward_span;
    int& cut = dir > 0 ? r.forward_cut : r.backward_cut;
    long& left = dir > 0 ? r.forward_left : r.backward_left;
    values.assign(static_cast<size_t>(n) * static_cast<size_t>(nv), kNaN);
    spans.assign(static_cast<size_t>(n), 0.0);
    for (const int j : frames) {
      const double t0 = time.time(j);
      double t1 = t0 + dir * options.horizon;
      const bool outside = t1 > hi + 1e-12 * (hi - lo) || t1 < lo - 1e-12 * (hi - lo);
      cut += outside;
      if (outside) t1 = std::clamp(t1, lo, hi);
      if (!(outside && options.beyond_range == HorizonPolicy::nan) && t1 != t0) {
        std::vector<FlowMapResult> mapped(static_cast<size_t>(nv));
        tbb::parallel_for(tbb::blocked_range<int>(0, nv, 64), [&](const tbb::blocked_range<int>& rr) {
          for (int v = rr.begin(); v != rr.end(); ++v) {
            FlowMapResult& out = mapped[static_cast<size_t>(v)];
            Vec2 p = start(v);
            int k = j;  // the frame the particle is at
            bool gone = false;
            if (dir > 0)
              while (!gone && k + 1 < n && time.time(k + 1) <= t1 + eps) gone = !apply(m, k++, p);
            else
              while (!gone && k > 0 && time.time(k - 1) >= t1 - eps) gone = !apply(m, --k, p);
            double t_left = t1;
            if (!gone && std::abs(t1 - time.time(k)) > eps) gone = grid.advect(p, {time.time(k), t1}, flow.dt(), t_left);
            out.where = grid.to_surface(p);
            out.left = gone;
            out.t_left = t_left;
          }
        });
        for (const auto& x : mapped) left += x.left;
        const double span = std::abs(t1 - t0);
        spans[static_cast<size_t>(j)] = span;
        const std::vector<float> sigma = ftle_from_flow_map(bundle, mapped, span);
        std::copy(sigma.begin(), sigma.end(), values.begin() + static_cast<long>(j) * nv);
      }
      ++done;
      if (options.progress) options.progress(done, total);
    }
  }
}

}  // namespace

FtleSlice compute_ftle_at(const TangentBundle& bundle, const Field& field, double t, double horizon, int direction,
                          HorizonPolicy policy, const FlowMapOptions& flow_options) {
  check_horizon(bundle.mesh(), field, horizon);
  if (direction != 1 && direction != -1)
    throw Error(fmt::format("FTLE direction {} must be +1 (forward) or -1 (backward)", direction));
  const TimeSampling& time = field.time();
  const double lo = std::min(time.t0, time.t1), hi = std::max(time.t0, time.t1);
  if (!std::isfinite(t) || t < lo || t > hi)
    throw Error(fmt::format("FTLE time {} is outside the field's time range [{}, {}]", t, lo, hi));
  const FlowMap flow(bundle, field, flow_options);
  return slice(bundle, flow, vertex_starts(bundle.mesh()), t, horizon, direction, policy);
}

FtleResult compute_ftle(const TangentBundle& bundle, const Field& field, const FtleOptions& options) {
  const Mesh& mesh = bundle.mesh();
  check_horizon(mesh, field, options.horizon);
  const int n = field.frames();
  std::vector<int> frames = options.frames;
  if (frames.empty())
    for (int j = 0; j < n; ++j) frames.push_back(j);
  for (const int j : frames)
    if (j < 0 || j >= n) throw Error(fmt::format("FTLE frame {} is outside the field's frames 0–{}", j, n - 1));
  const FlowMap flow(bundle, field, options.flow);

  FtleResult r;
  r.frames = n;
  r.vertices = mesh.num_vertices();
  r.horizon = options.horizon;
  const size_t size = static_cast<size_t>(n) * static_cast<size_t>(r.vertices);
  if (options.compose && flow.on_grid()) {
    compose_series(bundle, field, flow, *detail::detect_grid(bundle), options, frames, r);
    return r;
  }
  const std::vector<SurfacePoint> starts = vertex_starts(mesh);

  const TimeSampling& time = field.time();
  const int total = static_cast<int>(frames.size()) * (options.forward + options.backward);
  int done = 0;
  for (const int dir : {1, -1}) {
    if ((dir > 0 && !options.forward) || (dir < 0 && !options.backward)) continue;
    std::vector<float>& values = dir > 0 ? r.forward : r.backward;
    std::vector<double>& spans = dir > 0 ? r.forward_span : r.backward_span;
    int& cut = dir > 0 ? r.forward_cut : r.backward_cut;
    long& left = dir > 0 ? r.forward_left : r.backward_left;
    values.assign(size, kNaN);
    spans.assign(static_cast<size_t>(n), 0.0);
    for (const int j : frames) {
      const FtleSlice s = slice(bundle, flow, starts, time.time(j), options.horizon, dir, options.beyond_range);
      cut += s.cut;
      left += s.left;
      spans[static_cast<size_t>(j)] = s.span;
      std::copy(s.values.begin(), s.values.end(), values.begin() + static_cast<long>(j) * r.vertices);
      ++done;
      if (options.progress) options.progress(done, total);
    }
  }
  return r;
}

}  // namespace tvf
