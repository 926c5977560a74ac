#include "tvf/integrate/dye.h"

#include "tvf/core/error.h"
#include "tvf/field/point_locator.h"

#include <fmt/format.h>
#include <tbb/parallel_for.h>

#include <algorithm>
#include <cmath>
#include <utility>

namespace tvf {

namespace {

void check_time(const Field& field, double t, const char* what) {
  const TimeSampling& time = field.time();
  const double lo = std::min(time.t0, time.t1), hi = std::max(time.t0, time.t1);
  const double slack = 1e-12 * std::max(1.0, hi - lo);
  if (!std::isfinite(t) || t < lo - slack || t > hi + slack)
    throw Error(fmt::format("{} {} is outside the field's time range [{}, {}]", what, t, lo, hi));
}

}  // namespace

DyeInjector::DyeInjector(const TangentBundle& bundle, const Field& field, std::span<const Vec3> seeds, double t0,
                         const DyeOptions& options)
    : bundle_(bundle), flow_(bundle, field, options.flow), t0_(t0), t_(t0) {
  check_time(field, t0, "the dye's start time");
  const TimeSampling& time = field.time();
  const double span = std::abs(time.t1 - time.t0);
  const double frame_dt = time.frames > 1 ? span / (time.frames - 1) : 1.0;
  if (!(options.release_spacing >= 0) || !std::isfinite(options.release_spacing))
    throw Error(fmt::format("dye release spacing {} must be a positive time", options.release_spacing));
  spacing_ = options.release_spacing > 0 ? options.release_spacing : 0.25 * frame_dt;
  if (!(spacing_ > 0)) spacing_ = 1.0;
  if (span / spacing_ > kMaxReleases)
    throw Error(fmt::format("dye release spacing {:g} would release {:.3g} particles per seed over the field's "
                            "time range [{}, {}], more than {:g}: give a larger spacing",
                            spacing_, span / spacing_, std::min(time.t0, time.t1), std::max(time.t0, time.t1),
                            kMaxReleases));
  if (!(options.max_seed_distance >= 0) || !std::isfinite(options.max_seed_distance))
    throw Error(fmt::format("dye seed distance {} must be a positive length", options.max_seed_distance));

  const Mesh& mesh = bundle.mesh();
  if (mesh.num_faces() == 0) throw_input_error(mesh.source(), "", "the domain has no faces");
  const PointLocator locator(mesh);
  for (const Vec3& x : seeds) seeds_.push_back(locate_seed(bundle, locator, x, "dye seed", options.max_seed_distance));
  for (const auto& [a, b] : options.timelines) {
    TimelineOptions o;
    o.t0 = t0;
    o.max_seed_distance = options.max_seed_distance;  // the ends are placed as seeds are
    lines_.emplace_back(flow_, a, b, o);
  }
  dye_.resize(seeds_.size());
  records_.resize(lines_.size());
  advance(t0);
  records_.assign(lines_.size(), {});  // the records count the caller's advances (its pictures)
}

Vec3 DyeInjector::seed_position(size_t s) const { return surface_position(bundle_.mesh(), seeds_[s]); }

void DyeInjector::advance(double t) {
  check_time(flow_.field(), t, "dye time");
  if (t < t_) throw Error(fmt::format("dye goes forward in time only: {} is before its time {}", t, t_));
  // Releases t0 + kΔ for k up to ⌊(t − t0)/Δ + 1e-9⌋, as trace_streakline counts them; one a
  // hair after t waits at the seed (trace_streakline clamps it to t) and is carried from its
  // own release time by the next advance.
  const long last = static_cast<long>(std::floor((t - t0_) / spacing_ + 1e-9));
  const Mesh& mesh = bundle_.mesh();
  for (; next_ <= last; ++next_) {
    const double r = t0_ + spacing_ * static_cast<double>(next_);
    for (size_t s = 0; s < seeds_.size(); ++s)
      dye_[s].push_back({seeds_[s], surface_position(mesh, seeds_[s]), r, r, false});
  }
  t_ = t;
  std::vector<Particle*> moving;
  for (auto& line : dye_)
    for (Particle& p : line)
      if (!p.left && p.time < t) moving.push_back(&p);
  tbb::parallel_for(tbb::blocked_range<size_t>(0, moving.size(), 16), [&](const tbb::blocked_range<size_t>& range) {
    for (size_t i = range.begin(); i != range.end(); ++i) {
      Particle& p = *moving[i];
      const FlowMapResult m = flow_.advect(p.where, p.time, t);
      p.where = m.where;
      p.position = surface_position(mesh, m.where);
      p.time = t;
      p.left = m.left;
    }
  });
  for (size_t l = 0; l < lines_.size(); ++l) {
    lines_[l].advance(t);
    const Streakline& line = lines_[l].line();
    TimelineRecord& r = records_[l];
    ++r.times;
    if (line.unresolved == 0) continue;
    if (r.unresolved++ == 0) r.first_unresolved = t;
    if (line.largest_gap > r.largest_gap || r.unresolved == 1) {
      r.worst_time = t;
      r.largest_gap = line.largest_gap;
      r.resolution = line.resolution;
      r.unresolved_by = line.unresolved_by;
    }
  }
}

Streakline DyeInjector::streakline(size_t s) const {
  const std::vector<Particle>& line = dye_.at(s);
  Streakline out;
  out.t = t_;
  out.released = static_cast<int>(line.size());
  bool gap = false;
  for (const Particle& p : line) {
    if (p.left) {
      ++out.left;
      gap = !out.points.empty();
      continue;
    }
    out.points.push_back({p.position, p.where, std::min(p.release, t_), gap});
    gap = false;
  }
  // The particle released at t itself, still at the seed, when t is not a release time.
  const double last = line.empty() ? -INFINITY : line.back().release;
  if (last < t_ - 1e-12 * std::max(1.0, std::abs(t_))) {
    ++out.released;
    out.points.push_back({seed_position(s), seeds_[s], t_, gap});
  }
  return out;
}

long DyeInjector::released() const {
  long n = 0;
  for (size_t s = 0; s < dye_.size(); ++s) n += streakline(s).released;
  return n;
}

long DyeInjector::alive() const {
  long n = 0;
  for (size_t s = 0; s < dye_.size(); ++s) n += static_cast<long>(streakline(s).points.size());
  return n;
}

std::string unresolved_note(const TimelineRecord& r, const std::string& name, int max_points) {
  if (r.unresolved == 0) return {};
  const std::string why =
      r.unresolved_by == Streakline::Refinement::out_of_particles
          ? fmt::format("it needs more than {} particles there", max_points)
          : std::string("the flow tears it apart there (particles that started 1e-12 apart along it end further apart)");
  return fmt::format("{} is not resolved at {} of {} pictures, from t = {:g}: at t = {:g} neighbours are up to {:.3g} "
                     "apart (more than {:.3g}); {}, so there it is drawn as straight chords, or broken where they are "
                     "far apart in the picture",
                     name, r.unresolved, r.times, r.first_unresolved, r.worst_time, r.largest_gap, r.resolution, why);
}

}  // namespace tvf
