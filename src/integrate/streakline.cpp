#include "tvf/integrate/streakline.h"

#include "tvf/core/error.h"
#include "tvf/field/point_locator.h"

#include <tbb/parallel_for.h>

#include <algorithm>
#include <cmath>

namespace tvf {

namespace {

void check_range(const Field& field, double t, const char* what) {
  const TimeSampling& time = field.time();
  const double lo = std::min(time.t0, time.t1), hi = std::max(time.t0, time.t1);
  const double slack = 1e-12 * std::max(1.0, hi - lo);
  if (!std::isfinite(t) || t < lo - slack || t > hi + slack)
    throw Error(fmt::format("{} {} is outside the field's time range [{}, {}]", what, t, lo, hi));
}

// x on the mesh; on a planar domain x must lie in it.
SurfacePoint locate(const TangentBundle& bundle, const PointLocator& locator, const Vec3& x, const char* what) {
  const Mesh& mesh = bundle.mesh();
  const SurfacePoint p = locator.closest(x);
  if (p.face < 0) throw_input_error(mesh.source(), "", "the domain has no faces");
  if (bundle.is_flat() && (surface_position(mesh, p) - x).head<2>().norm() > 1e-9 * std::max(1.0, mesh.diameter()))
    throw Error(fmt::format("the {} ({}, {}) is outside the domain", what, x.x(), x.y()));
  return p;
}

}  // namespace

Streakline trace_streakline(const TangentBundle& bundle, const Field& field, const Vec3& seed,
                            const StreaklineOptions& options) {
  check_range(field, options.t0, "streakline start time");
  check_range(field, options.t1, "streakline time");
  if (options.t0 > options.t1)
    throw Error(fmt::format("the streakline's release starts at {}, after its time {}: give t0 ≤ t1", options.t0,
                            options.t1));
  const TimeSampling& time = field.time();
  const double frame_dt = time.frames > 1 ? std::abs(time.t1 - time.t0) / (time.frames - 1) : 1.0;
  const double spacing = options.release_spacing > 0 ? options.release_spacing : 0.25 * frame_dt;
  if (!(options.release_spacing >= 0) || !std::isfinite(options.release_spacing) || !(spacing > 0))
    throw Error(fmt::format("release spacing {} must be a positive time", options.release_spacing));
  if ((options.t1 - options.t0) / spacing > kMaxReleases)
    throw Error(fmt::format("release spacing {:g} would release {:.3g} particles over [{}, {}], more than {:g}: give a "
                            "larger spacing",
                            spacing, (options.t1 - options.t0) / spacing, options.t0, options.t1, kMaxReleases));
  const PointLocator locator(bundle.mesh());
  const SurfacePoint start = locate(bundle, locator, seed, "streakline seed");

  // Release times t0, t0 + Δ, …, and t1 (the particle still at the seed).
  std::vector<double> releases;
  const long steps = static_cast<long>(std::floor((options.t1 - options.t0) / spacing + 1e-9));
  for (long k = 0; k <= steps; ++k) releases.push_back(options.t0 + spacing * static_cast<double>(k));
  if (releases.back() < options.t1 - 1e-12 * std::max(1.0, std::abs(options.t1))) releases.push_back(options.t1);
  releases.back() = std::min(releases.back(), options.t1);

  const FlowMap flow(bundle, field, options.flow);
  std::vector<FlowMapResult> mapped(releases.size());
  tbb::parallel_for(size_t{0}, releases.size(),
                    [&](size_t k) { mapped[k] = flow.advect(start, releases[k], options.t1); });
  Streakline out;
  out.t = options.t1;
  out.released = static_cast<int>(releases.size());
  bool gap = false;
  for (size_t k = 0; k < releases.size(); ++k) {
    if (mapped[k].left) {
      ++out.left;
      gap = !out.points.empty();
      continue;
    }
    out.points.push_back({surface_position(bundle.mesh(), mapped[k].where), mapped[k].where, releases[k], gap});
    gap = false;
  }
  return out;
}

Streakline trace_timeline(const TangentBundle& bundle, const Field& field, const Vec3& a, const Vec3& b,
                          const TimelineOptions& options) {
  check_range(field, options.t0, "timeline start time");
  check_range(field, options.t1, "timeline time");
  if (options.count < 2) throw Error(fmt::format("a timeline needs at least 2 particles, not {}", options.count));
  if (options.count > options.max_points)
    throw Error(fmt::format("a timeline of {} particles is more than its limit of {}", options.count,
                            options.max_points));
  const Mesh& mesh = bundle.mesh();
  const PointLocator locator(mesh);
  locate(bundle, locator, a, "timeline's first point");
  locate(bundle, locator, b, "timeline's last point");
  const double max_gap = options.max_gap > 0 ? options.max_gap : mesh.mean_edge_length();
  const FlowMap flow(bundle, field, options.flow);

  struct Sample {
    double s;
    FlowMapResult m;
    Vec3 x;
  };
  auto carry = [&](const std::vector<double>& params) {
    std::vector<Sample> out(params.size());
    tbb::parallel_for(size_t{0}, params.size(), [&](size_t k) {
      const double s = params[k];
      const SurfacePoint p = locator.closest((1.0 - s) * a + s * b);
      out[k].s = s;
      out[k].m = flow.advect(p, options.t0, options.t1);
      out[k].x = surface_position(mesh, out[k].m.where);
    });
    return out;
  };
  std::vector<double> params;
  for (int k = 0; k < options.count; ++k) params.push_back(static_cast<double>(k) / (options.count - 1));
  std::vector<Sample> line = carry(params);
  int released = options.count;
  for (int round = 0; round < 16; ++round) {
    std::vector<double> mids;
    for (size_t k = 0; k + 1 < line.size(); ++k) {
      const Sample& p = line[k];
      const Sample& q = line[k + 1];
      if (p.m.left || q.m.left || (p.x - q.x).norm() <= max_gap || q.s - p.s < 1e-12) continue;
      if (released + static_cast<int>(mids.size()) >= options.max_points) break;
      mids.push_back(0.5 * (p.s + q.s));
    }
    if (mids.empty()) break;
    released += static_cast<int>(mids.size());
    std::vector<Sample> added = carry(mids);
    std::vector<Sample> merged;
    merged.reserve(line.size() + added.size());
    std::merge(line.begin(), line.end(), added.begin(), added.end(), std::back_inserter(merged),
               [](const Sample& x, const Sample& y) { return x.s < y.s; });
    line = std::move(merged);
  }
  Streakline out;
  out.t = options.t1;
  out.released = released;
  bool gap = false;
  for (const Sample& s : line) {
    if (s.m.left) {
      ++out.left;
      gap = !out.points.empty();
      continue;
    }
    out.points.push_back({s.x, s.m.where, s.s, gap});
    gap = false;
  }
  return out;
}

}  // namespace tvf
