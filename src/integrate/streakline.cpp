#include "tvf/integrate/streakline.h"

#include "tvf/core/error.h"
#include "tvf/field/point_locator.h"
#include "tvf/integrate/surface_path.h"
#include "tvf/integrate/surface_walk.h"

#include <tbb/parallel_for.h>

#include <algorithm>
#include <cmath>
#include <utility>
#include <vector>

namespace tvf {

namespace {

void check_range(const Field& field, double t, const char* what) {
  const TimeSampling& time = field.time();
  const double lo = std::min(time.t0, time.t1), hi = std::max(time.t0, time.t1);
  const double slack = 1e-12 * std::max(1.0, hi - lo);
  if (!std::isfinite(t) || t < lo - slack || t > hi + slack)
    throw Error(fmt::format("{} {} is outside the field's time range [{}, {}]", what, t, lo, hi));
}

}  // namespace

SurfacePoint locate_seed(const TangentBundle& bundle, const PointLocator& locator, const Vec3& x, const char* what,
                         double max_distance) {
  const Mesh& mesh = bundle.mesh();
  if (!x.allFinite()) throw Error(fmt::format("the {} must have finite coordinates", what));
  if (!(max_distance >= 0) || !std::isfinite(max_distance))
    throw Error(fmt::format("the {}'s distance {} from the surface must be a positive length", what, max_distance));
  const SurfacePoint p = locator.closest(x);
  if (p.face < 0) throw_input_error(mesh.source(), "", "the domain has no faces");
  const Vec3 on = surface_position(mesh, p);
  if (bundle.is_flat()) {
    if (const std::string problem = planar_point_problem(mesh, x, on, fmt::format("the {}", what)); !problem.empty())
      throw Error(problem);
    return p;
  }
  const double reach = max_distance > 0 ? max_distance : 3.0 * mesh.mean_edge_length();
  if (const double d = (on - x).norm(); !(d <= reach))
    throw Error(fmt::format("the {} ({}, {}, {}) is {:.3g} from the surface, farther than {:.3g}{}: give a point on or "
                            "near the surface",
                            what, x.x(), x.y(), x.z(), d, reach, max_distance > 0 ? "" : " (three edge lengths)"));
  return p;
}

namespace {

// Fills the resolution fields of a traced curve (streakline.h).
void measure_gaps(Streakline& s, double resolution) {
  s.resolution = resolution;
  for (size_t k = 1; k < s.points.size(); ++k) {
    if (s.points[k].gap_before) continue;
    const double d = (s.points[k].position - s.points[k - 1].position).norm();
    s.largest_gap = std::max(s.largest_gap, d);
    if (d > resolution) ++s.unresolved;
  }
}

// A particle of a curve: its parameter s (a release time, or the place along a timeline's
// segment), where it starts (x0 in space) and where it is at the curve's time.
using Sample = MaterialLine::Particle;

Sample starting(double s, const SurfacePoint& start, const Vec3& x0) {
  Sample out;
  out.s = s;
  out.start = start;
  out.x0 = x0;
  return out;
}

// Carries the samples' starts to the curve's time (fills m and x), in parallel.
template <class Advect>
void carry(std::vector<Sample>& samples, const Mesh& mesh, Advect&& advect) {
  tbb::parallel_for(size_t{0}, samples.size(), [&](size_t k) {
    samples[k].m = advect(samples[k]);
    samples[k].x = surface_position(mesh, samples[k].m.where);
  });
}

// Halves every interval of `line` (carried, sorted by s) whose ends are further apart than
// max_gap — mid(p, q) is the particle between them, carried by advect — until none is,
// `most` particles are carried or the interval is shorter than `finest` in s (every
// interval halved is at most half as long in s, so none is halved more than ~40 times:
// this ends). The widest
// intervals are halved first, and when a round wants more particles than are left the
// widest get them: a budget that runs out leaves the line's largest gaps halved, not one
// stretch refined to max_gap and another left coarse.
// A pair one of which left the domain is halved too, measured to where that one left (its
// x): the curve runs on inside from the other towards the boundary, and as the pair closes in
// on the particle that leaves just at t1, both ends approach its exit.
// between_left: pairs that both left are halved as well where they left more than max_gap
// apart, with what particles are left once nothing else is wide (a timeline across a
// saddle's stable separatrix whose every particle went through the walls, one to either
// side: the material between them that stays runs along the unstable one; dye released
// at a seed beside it the same). Without it the curve is broken there and what stays
// between them is not looked for.
// Returns whether it ran out of particles.
template <class Mid, class Advect>
bool refine(std::vector<Sample>& line, Mid&& mid, Advect&& advect, const Mesh& mesh, double max_gap, double finest,
            long most, bool between_left) {
  for (;;) {
    std::vector<std::pair<double, size_t>> wide;  // (gap, k): line[k] and line[k + 1] too far apart
    auto gather = [&](bool both_left) {
      for (size_t k = 0; k + 1 < line.size(); ++k) {
        const Sample& p = line[k];
        const Sample& q = line[k + 1];
        const double gap = (p.x - q.x).norm();
        if ((p.m.left && q.m.left) != both_left || !(gap > max_gap) || q.s - p.s < finest) continue;
        wide.emplace_back(gap, k);
      }
    };
    gather(false);
    if (wide.empty() && between_left) gather(true);
    if (wide.empty()) return false;
    // Widest first: only those wider than half the widest this round. Every interval wider
    // than max_gap is halved in the end either way (the particles within budget are the
    // same), but a budget that runs out leaves the line evenly resolved.
    double widest = 0;
    for (const auto& w : wide) widest = std::max(widest, w.first);
    std::erase_if(wide, [&](const auto& w) { return !(w.first > 0.5 * widest); });
    const long room = std::max(0L, most - static_cast<long>(line.size()));
    const bool out_of_particles = static_cast<long>(wide.size()) > room;
    if (out_of_particles) {
      const auto keep = wide.begin() + room;
      std::nth_element(wide.begin(), keep, wide.end(), [](const auto& x, const auto& y) { return x.first > y.first; });
      wide.erase(keep, wide.end());
      if (wide.empty()) return true;
    }
    std::vector<Sample> added;
    added.reserve(wide.size());
    for (const auto& [gap, k] : wide) added.push_back(mid(line[k], line[k + 1]));
    carry(added, mesh, advect);
    std::vector<Sample> merged;
    merged.reserve(line.size() + added.size());
    std::sort(added.begin(), added.end(), [](const Sample& x, const Sample& y) { return x.s < y.s; });
    std::merge(line.begin(), line.end(), added.begin(), added.end(), std::back_inserter(merged),
               [](const Sample& x, const Sample& y) { return x.s < y.s; });
    line = std::move(merged);
    if (out_of_particles) return true;
  }
}

// The curve of a refined line at t1, broken where particles left, with its resolution
// measured against max_gap.
Streakline curve(const std::vector<Sample>& line, double max_gap, bool out_of_particles, double t1) {
  Streakline out;
  out.t = t1;
  out.released = static_cast<int>(line.size());
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
  measure_gaps(out, max_gap);
  if (out.unresolved > 0)
    out.unresolved_by = out_of_particles ? Streakline::Refinement::out_of_particles : Streakline::Refinement::torn;
  return out;
}

}  // namespace

const char* refinement_name(Streakline::Refinement r) {
  switch (r) {
    case Streakline::Refinement::out_of_particles: return "particles";
    case Streakline::Refinement::torn: return "torn";
    case Streakline::Refinement::resolved: break;
  }
  return nullptr;
}

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
  const SurfacePoint start = locate_seed(bundle, locator, seed, "streakline seed", options.max_seed_distance);

  // Release times t0, t0 + Δ, …, and t1 (the particle still at the seed).
  const long steps = static_cast<long>(std::floor((options.t1 - options.t0) / spacing + 1e-9));
  std::vector<double> releases(static_cast<size_t>(steps) + 1);
  for (long k = 0; k <= steps; ++k) releases[static_cast<size_t>(k)] = options.t0 + spacing * static_cast<double>(k);
  if (const double last = releases[static_cast<size_t>(steps)];
      last < options.t1 - 1e-12 * std::max(1.0, std::abs(options.t1)))
    releases.push_back(options.t1);
  else
    releases[static_cast<size_t>(steps)] = std::min(last, options.t1);

  if (std::isnan(options.max_gap) || options.max_gap < 0)
    throw Error(fmt::format("the streakline's largest gap {} must be positive", options.max_gap));
  const double max_gap = options.max_gap > 0 ? options.max_gap : bundle.mesh().mean_edge_length();
  const FlowMap flow(bundle, field, options.flow);
  const Vec3 at = surface_position(bundle.mesh(), start);
  auto advect = [&](const Sample& p) { return flow.advect(p.start, p.s, options.t1); };
  std::vector<Sample> line(releases.size());
  for (size_t k = 0; k < releases.size(); ++k) line[k] = starting(releases[k], start, at);
  carry(line, bundle.mesh(), advect);
  auto mid = [&](const Sample& p, const Sample& q) { return starting(0.5 * (p.s + q.s), start, at); };
  const double finest = 1e-12 * std::max(1.0, std::abs(options.t1));
  const bool out_of_particles = refine(line, mid, advect, bundle.mesh(), max_gap, finest,
                                       static_cast<long>(releases.size()) + options.max_added, true);
  Streakline out = curve(line, max_gap, out_of_particles, options.t1);
  if (!std::isfinite(max_gap)) {  // not refined: judged by the mean edge length all the same
    out.largest_gap = 0;
    out.unresolved = 0;
    measure_gaps(out, bundle.mesh().mean_edge_length());
  }
  return out;
}

Streakline trace_timeline(const TangentBundle& bundle, const Field& field, const Vec3& a, const Vec3& b,
                          const TimelineOptions& options) {
  check_range(field, options.t0, "timeline start time");
  check_range(field, options.t1, "timeline time");
  MaterialLine line(FlowMap(bundle, field, options.flow), a, b, options);
  line.advance(options.t1);
  return line.line();
}

MaterialLine::MaterialLine(const FlowMap& flow, const Vec3& a, const Vec3& b, const TimelineOptions& options)
    : flow_(flow), t0_(options.t0), t_(options.t0), max_points_(options.max_points) {
  const TangentBundle& bundle = flow.bundle();
  check_range(flow.field(), options.t0, "timeline start time");
  if (options.count < 2) throw Error(fmt::format("a timeline needs at least 2 particles, not {}", options.count));
  if (options.count > options.max_points)
    throw Error(fmt::format("a timeline of {} particles is more than its limit of {}", options.count,
                            options.max_points));
  const Mesh& mesh = bundle.mesh();
  locator_ = std::make_shared<const PointLocator>(mesh);
  const Vec3 pa =
      surface_position(mesh, locate_seed(bundle, *locator_, a, "timeline's first point", options.max_seed_distance));
  const Vec3 pb =
      surface_position(mesh, locate_seed(bundle, *locator_, b, "timeline's last point", options.max_seed_distance));
  auto show = [&](const Vec3& x) {
    return bundle.is_flat() ? fmt::format("({}, {})", x.x(), x.y()) : fmt::format("({}, {}, {})", x.x(), x.y(), x.z());
  };
  // Both ends at one point is no line: every particle would be the same one.
  if ((pa - pb).norm() <= 1e-12 * std::max(1.0, mesh.diameter())) {
    throw Error(fmt::format("the timeline's ends {} and {} are one point of the domain: give two different points",
                            show(a), show(b)));
  }
  if (std::isnan(options.max_gap) || options.max_gap < 0)
    throw Error(fmt::format("the timeline's largest gap {} must be positive", options.max_gap));
  max_gap_ = options.max_gap > 0 ? options.max_gap : mesh.mean_edge_length();

  // The line where it is drawn: on a planar domain the segment from a to b; on a surface the
  // shortest path over it between the ends' closest points (a discrete geodesic,
  // surface_path.h), which is what a segment drawn on the surface means (the chord between
  // them runs through the inside, and its closest points jump across hollows).
  if (bundle.is_flat()) {
    path_ = {a, b};
  } else {
    SurfacePaths::Route route = SurfacePaths(bundle, *locator_).route(pa, pb, kPathSegments);
    path_ = std::move(route.points);
    path_starts_ = std::move(route.starts);
    path_steps_ = std::move(route.steps);
    if (path_.empty())
      throw Error(fmt::format("the timeline's ends {} and {} lie on separate pieces of the surface: no path over it "
                              "joins them",
                              show(a), show(b)));
  }
  along_.assign(path_.size(), 0.0);
  // Arclength: over a surface the walks' lengths, the path's own.
  for (size_t k = 1; k < path_.size(); ++k)
    along_[k] = along_[k - 1] + (path_steps_.empty() ? (path_[k] - path_[k - 1]).norm() : std::abs(path_steps_[k - 1]));
  if (!(along_.back() > 0)) {  // a path of no length (only by rounding: the ends are apart): the chord
    path_ = {pa, pb};
    path_starts_.clear(), path_steps_.clear();
    along_ = {0.0, (pb - pa).norm()};
  }
  for (double& x : along_) x /= along_.back();

  // The line's points, filled in until neighbours are within a mean edge length (or
  // max_gap, if that is larger) there: where the path's chords are longer than that, their
  // points snapped to the surface could jump. One still torn (points that land on an end)
  // is no line to carry. Refining further at t0 would spend the particles evenly along the
  // line before the flow shows where they are needed.
  for (int k = 0; k < options.count; ++k) particles_.push_back(start_at(static_cast<double>(k) / (options.count - 1)));
  for (Sample& p : particles_) {
    p.m = FlowMapResult{p.start, false, t0_};
    p.x = p.x0;
  }
  refine(std::max(max_gap_, mesh.mean_edge_length()), false);
  if (line_.unresolved_by == Streakline::Refinement::torn)
    throw Error(fmt::format("the line between the timeline's ends, snapped onto the surface, breaks apart (its "
                            "points jump up to {:.3g} across it): give ends closer together",
                            line_.largest_gap));
}

void MaterialLine::advance(double t) {
  check_range(flow_.field(), t, "timeline time");
  const double from = t_;
  auto onward = [&](const Sample& p) { return p.m.left ? p.m : flow_.advect(p.m.where, from, t); };
  carry(particles_, flow_.bundle().mesh(), onward);
  t_ = t;
  coarsen(max_gap_);
  refine(max_gap_, true);
}

// Drops particles an advance added (refine) where the line has drawn together since: a run
// of them between two kept particles p and q goes when the line's path from p through the
// run to q is within half `gap`. Every point of that path is then within a quarter gap of
// the chord p–q that replaces it (|p − x| + |x − q| ≤ gap/2 puts x within gap/4 of it), and
// refine does not add it back (the chord is within half the gap). The whole contraction of
// one advance is taken at once, however many particles it drew together (one of two
// neighbours per advance lagged a fast contraction by several pictures). The particles the
// line was made with stay (tracing afresh keeps them: trace_timeline, one advance, is
// unchanged), as do particles beside one that left the domain (the refinement at the walls
// measures to them).
void MaterialLine::coarsen(double gap) {
  if (!std::isfinite(gap) || particles_.size() < 3) return;
  std::vector<Sample> kept;
  kept.reserve(particles_.size());
  kept.push_back(particles_.front());
  double run = 0;  // the path from the last kept particle to particles_[k]
  for (size_t k = 1; k + 1 < particles_.size(); ++k) {
    const Sample& p = kept.back();
    const Sample& x = particles_[k];
    const Sample& q = particles_[k + 1];
    run += (x.x - particles_[k - 1].x).norm();
    const bool drop = x.added && !p.m.left && !x.m.left && !q.m.left && run + (q.x - x.x).norm() <= 0.5 * gap;
    if (!drop) {
      kept.push_back(x);
      run = 0;
    }
  }
  kept.push_back(particles_.back());
  particles_ = std::move(kept);
}

// The particle at parameter s of the line where it is drawn: the path's point at that
// fraction of its length. On a surface, walked that fraction of its segment's step from
// the segment's start (SurfacePaths::Route), so the line is continuous in s: the chord's
// point snapped to its closest surface point jumped across thin parts (the tip of CGAL's
// camel's tail, whose line to a hoof was refused as torn). On a planar domain the
// segment's own point.
MaterialLine::Particle MaterialLine::start_at(double s) const {
  const auto k = static_cast<size_t>(std::upper_bound(along_.begin() + 1, along_.end() - 1, s) - along_.begin()) - 1;
  const double w = along_[k + 1] > along_[k] ? std::clamp((s - along_[k]) / (along_[k + 1] - along_[k]), 0.0, 1.0) : 0.0;
  SurfacePoint at;
  if (path_starts_.empty())
    at = locator_->closest((1.0 - w) * path_[k] + w * path_[k + 1]);
  else
    at = w > 0 ? walk_surface(flow_.bundle(), path_starts_[k], w * path_steps_[k]).end : path_starts_[k];
  return starting(s, at, surface_position(flow_.bundle().mesh(), at));
}

// Adds particles where neighbours at time() are more than `gap` apart: each starts at the
// line's point halfway between theirs in parameter (start_at), carried from t0, marked
// `added` when mark_added (an advance's). Then measures the line against `gap`.
void MaterialLine::refine(double gap, bool mark_added) {
  const Mesh& mesh = flow_.bundle().mesh();
  auto mid = [&](const Sample& p, const Sample& q) {
    Sample x = start_at(0.5 * (p.s + q.s));
    x.added = mark_added;
    return x;
  };
  auto from_start = [&](const Sample& p) {
    return t_ == t0_ ? FlowMapResult{p.start, false, t0_} : flow_.advect(p.start, t0_, t_);
  };
  const bool out_of_particles = tvf::refine(particles_, mid, from_start, mesh, gap, 1e-12, max_points_, true);
  line_ = curve(particles_, gap, out_of_particles, t_);
}

}  // namespace tvf
