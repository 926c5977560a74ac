#pragma once
// Dye injection (smoke in the flow; the paper's §10 flow descriptors, issue 20): the
// streaklines of streakline.h kept up to date while an animation runs. Dye is released
// continuously at each seed from a start time t0, one particle every `release_spacing`
// (release times t0, t0 + Δ, t0 + 2Δ, …), and every particle is carried by the flow map
// (flow_map.h: RK4 on the surface or the grid, steps split at the field's frame times).
// advance(t) carries the particles already released from the current time to t and
// releases the ones due in (current time, t], each carried from its own release time to
// t: the cost of a frame is one frame of RK4 per particle alive, where re-tracing the
// streakline from scratch costs every particle's whole history.
//
// At every time t, streakline(s) is trace_streakline(bundle, field, seed, {t0, t, Δ,
// flow}): the same release times, the same order (oldest first, then the particle at the
// seed released at t itself when t is not a release time), the same particles dropped
// (those that left the domain, with gap_before on the next one). The positions agree to
// rounding when the times advanced to are the field's frame times (the flow map splits its
// steps there anyway) and to the integration error otherwise (tests/integrate/dye_test).
//
// Seeds (and timelines' ends): on a planar domain a seed's x and y must lie in the domain
// (z is ignored); on a surface a seed is moved to its closest point of the surface, and
// refused when that is farther than max_seed_distance.
#include "tvf/field/field.h"
#include "tvf/integrate/flow_map.h"
#include "tvf/integrate/streakline.h"
#include "tvf/mesh/tangent_bundle.h"

#include <array>
#include <limits>
#include <span>
#include <string>
#include <vector>

namespace tvf {

struct DyeOptions {
  double release_spacing = 0.0;    // time between releases; 0: a quarter of the field's frame
                                   // spacing (trace_streakline's default)
  double max_seed_distance = 0.0;  // surfaces: how far (world units) a seed may be from the
                                   // surface; 0: three mean edge lengths (timelines' ends too)
  // Material lines drawn at t0 beside the dye: each segment (its ends placed as seeds are)
  // is a MaterialLine (streakline.h) advanced with the dye: its particles are carried from
  // picture to picture, and those added where it stretches from t0.
  std::vector<std::array<Vec3, 2>> timelines;
  FlowMapOptions flow;
};

// How a timeline fared over the advances so far. A renderer draws the line at every picture,
// and a chord drawn at some pictures is worth saying even when the last one is resolved:
// the renderers return these and the CLI warns from them.
struct TimelineRecord {
  int times = 0;       // advances the line was measured after (the pictures drawn)
  int unresolved = 0;  // of which it was not resolved (Streakline::unresolved > 0)
  double first_unresolved = std::numeric_limits<double>::quiet_NaN();  // the first such time
  // The worst of those (the largest gap): its time, its gap, the resolution asked and what
  // stopped the refinement there.
  double worst_time = std::numeric_limits<double>::quiet_NaN();
  double largest_gap = 0.0;
  double resolution = 0.0;
  Streakline::Refinement unresolved_by = Streakline::Refinement::resolved;
};

// One sentence for a timeline a renderer drew unresolved at some pictures (which, at how many,
// from when, how far apart and why), naming it `name` (the CLI's "--timeline X0,Y0,X1,Y1",
// Python's "timelines[0]"); empty when it was resolved at every picture. `max_points`: the
// particle budget it had.
std::string unresolved_note(const TimelineRecord& record, const std::string& name, int max_points);

class DyeInjector {
public:
  // Dye released from each seed from time t0 on (the first particles are released at once).
  // Throws tvf::Error, one sentence naming the value, on a seed outside a planar domain or
  // too far from a surface, t0 outside the field's time range, a non-positive release
  // spacing, or one that would release more than a million particles per seed over the
  // field's time range.
  DyeInjector(const TangentBundle& bundle, const Field& field, std::span<const Vec3> seeds, double t0,
              const DyeOptions& options = {});

  // Carries the dye from time() to t and releases what is due up to t. t ≥ time(), in the
  // field's time range (tvf::Error otherwise).
  void advance(double t);

  double time() const { return t_; }
  double start() const { return t0_; }
  double release_spacing() const { return spacing_; }
  size_t num_seeds() const { return seeds_.size(); }
  // A seed's place on the mesh and its world position there.
  const SurfacePoint& seed(size_t s) const { return seeds_[s]; }
  Vec3 seed_position(size_t s) const;
  // The dye of seed s at time(), as trace_streakline gives it.
  Streakline streakline(size_t s) const;
  // The timelines (DyeOptions::timelines) at time(): trace_timeline(bundle, field, a, b,
  // {start(), time()}) along the curve, refined where neighbours part (MaterialLine).
  size_t num_timelines() const { return lines_.size(); }
  const Streakline& timeline(size_t l) const { return lines_[l].line(); }
  // Each timeline's record over the advances so far (one per timeline, in order).
  const std::vector<TimelineRecord>& timeline_records() const { return records_; }
  // Particles released so far over all seeds (at the seed at time() included), and of
  // those the ones still in the domain.
  long released() const;
  long alive() const;

private:
  struct Particle {
    SurfacePoint where;
    Vec3 position;
    double release = 0;  // its release time (t0 + kΔ)
    double time = 0;     // the time its place is for
    bool left = false;
  };
  const TangentBundle& bundle_;
  FlowMap flow_;
  double t0_ = 0, t_ = 0, spacing_ = 0;
  long next_ = 0;  // the next release index k (time t0 + kΔ), the same for every seed
  std::vector<SurfacePoint> seeds_;
  std::vector<MaterialLine> lines_;  // the timelines
  std::vector<TimelineRecord> records_;  // and how they fared
  std::vector<std::vector<Particle>> dye_;  // per seed, by release
};

}  // namespace tvf
