#pragma once
// Streaklines and timelines (the paper's §10 flow descriptors; DESIGN §12, "Streaklines"):
//  - a streakline at time t1 is where the dye released continuously from a seed over
//    [t0, t1] is at t1: particles released every `release_spacing` (release times
//    t0, t0 + Δ, …, and t1 itself, the particle at the seed) carried by the flow map
//    (flow_map.h) to t1, with releases added between neighbours that drift apart. Ordered
//    by release time, oldest first, so consecutive points are neighbours along the streak.
//  - a timeline at time t1 is a material line: the points of a curve at t0 (a segment
//    between two points, straight in the plane; on a surface the shortest path over it
//    between them) carried to t1, refined where neighbours drift apart.
// Particles that leave the domain before t1 are dropped and counted. In a steady field a
// streakline is the streamline through the seed (the tests check both closed forms).
#include "tvf/field/field.h"
#include "tvf/integrate/flow_map.h"
#include "tvf/mesh/tangent_bundle.h"

#include <memory>
#include <vector>

namespace tvf {

class PointLocator;

// The most particles one streakline releases (and a dye seed over the field's time range,
// dye.h): a spacing that would release more is refused, not allocated (a million carried
// particles take about 100 MB and minutes of RK4 on 2 cores).
inline constexpr double kMaxReleases = 1e6;

struct StreaklineOptions {
  double t0 = 0.0;               // first release
  double t1 = 1.0;               // the streakline's time; t0 ≤ t1
  double release_spacing = 0.0;  // time between releases; 0: a quarter of the frame spacing
  // Where neighbours are further apart at t1 than max_gap (world distance; 0: the mean edge
  // length), a particle released halfway between them is added, at most max_added in all:
  // dye released continuously is one curve, but release times close together can end far
  // apart (the double gyre's stretching). Infinity: the regular releases only (the dye
  // renderers' particles, dye.h). A neighbour that left the domain counts where it left,
  // so the curve runs on to the boundary; two that left far apart are halved with what
  // additions are left over, to find what stayed between them.
  double max_gap = 0.0;
  long max_added = 20000;
  // Surfaces: how far (world units) the seed may be from the surface (it is moved to its
  // closest point); farther is refused. 0: three mean edge lengths (as the dye renderers).
  double max_seed_distance = 0.0;
  FlowMapOptions flow;
};

struct StreakPoint {
  Vec3 position;           // world position at t1
  SurfacePoint where;      // the same on the mesh
  double release = 0.0;    // when it was released (streaklines) or its parameter along
                           // the initial curve in [0, 1] (timelines)
  bool gap_before = false; // a particle between this point and the previous one left the
                           // domain: the curve is broken here
};

struct Streakline {
  double t = 0.0;                  // t1
  std::vector<StreakPoint> points; // oldest release first (timelines: by parameter)
  int released = 0;                // particles released
  int left = 0;                    // of which left the domain before t1
  // How well the points resolve the curve: between neighbours the curve is drawn as a
  // straight chord, faithful only where they are close. resolution: the distance
  // neighbours should keep (the options' max_gap; the mean edge length where that is 0, or
  // infinite for a streakline);
  // largest_gap: the largest distance at t1 between neighbours not broken by a particle
  // that left; unresolved: how many such neighbours are further apart than resolution.
  double resolution = 0.0;
  double largest_gap = 0.0;
  int unresolved = 0;
  // What stopped the refinement short of resolution (unresolved > 0): the particles ran out
  // (max_points, max_added), or neighbours 1e-12 apart in parameter are still too far apart
  // at t1 (the flow map tears the curve there).
  enum class Refinement { resolved, out_of_particles, torn };
  Refinement unresolved_by = Refinement::resolved;
};

// Where a seed (or a line's end) `x` lies on the domain: on a planar domain the face under
// its x and y (z is ignored), refused outside the domain; on a surface its closest point,
// refused when that is farther than max_distance (0: three mean edge lengths): a point that
// far off lands wherever the nearest part of the surface happens to be. Non-finite
// coordinates are refused. Errors name the point as `what` ("streakline seed").
SurfacePoint locate_seed(const TangentBundle& bundle, const PointLocator& locator, const Vec3& x, const char* what,
                         double max_distance = 0.0);

// unresolved_by as the JSON answers and Python's dicts give it (DESIGN §12 keys): null when
// resolved, "particles" (out of particles) or "torn".
const char* refinement_name(Streakline::Refinement r);

// Throws tvf::Error on t0 > t1, times outside the field's range, a non-positive release
// spacing or one that would release more than kMaxReleases particles over [t0, t1], a
// negative or NaN max_gap, or a seed off the domain (locate_seed); all name the value.
Streakline trace_streakline(const TangentBundle& bundle, const Field& field, const Vec3& seed,
                            const StreaklineOptions& options);

struct TimelineOptions {
  double t0 = 0.0;         // when the line is drawn
  double t1 = 1.0;         // when it is shown (t1 < t0: backwards)
  int count = 100;         // particles on the initial segment (at least 2)
  double max_gap = 0.0;    // world distance between neighbours at t1 above which a midpoint
                           // is added (and carried); 0: a mean edge length. At most
                           // max_points in all. Particles that left: as for streaklines.
  int max_points = 20000;
  // Surfaces: how far the line's ends may be from the surface (StreaklineOptions).
  double max_seed_distance = 0.0;
  FlowMapOptions flow;
};

// The segment from a to b at t0, carried to t1; release = the parameter along it (its
// arclength over the whole). On a surface the ends are moved to their closest points and
// the line is the shortest path over the surface between them (SurfacePaths,
// surface_path.h: the chord between them runs through the inside, and its closest points
// jump across hollows). The line is filled in at t0 to a mean edge length and refined at t1
// where the flow parts neighbours (MaterialLine with one advance).
// Throws tvf::Error on times outside the field's range, a count below 2 or above
// max_points, a negative or NaN max_gap, both ends at one point of the domain (on a
// surface: once moved onto it), ends on separate pieces of a surface (no path over it
// joins them), or (planar domains) an end outside the domain.
Streakline trace_timeline(const TangentBundle& bundle, const Field& field, const Vec3& a, const Vec3& b,
                          const TimelineOptions& options);

// A timeline kept up to date while time goes on (the renderers' timelines, dye.h): advance(t)
// carries its particles from time() to t and then adds particles where neighbours are more
// than max_gap apart, each carried from t0 (the parts that stretch are refined as they
// stretch). Particles an advance added are dropped again where the line draws together
// (coarsen), so a long clip holds about what its time needs, not every particle it ever
// needed. Across a clip each particle is carried once, where tracing the timeline afresh
// at every picture carries every particle from t0 each time. line() agrees with
// trace_timeline(bundle, field, a, b, {t0, time()}) along the curve: positions of one
// parameter agree to rounding when the times advanced to are the field's frame times (the
// flow map splits its steps there) and to the integration error otherwise; it may hold
// more particles (those added at earlier times and not yet drawn together).
class MaterialLine {
public:
  // The segment at options.t0 (options.t1 and options.flow are not used: `flow` carries it),
  // filled in there until neighbours are within a mean edge length (or max_gap if larger;
  // line() is measured against that until the first advance, which refines to max_gap).
  // Throws as trace_timeline.
  MaterialLine(const FlowMap& flow, const Vec3& a, const Vec3& b, const TimelineOptions& options);

  // Carries the line from time() to t (t < time(): backwards) and refines it at t. t must lie
  // in the field's time range (tvf::Error otherwise).
  void advance(double t);

  double time() const { return t_; }
  double start() const { return t0_; }
  // The line at time(), ordered by parameter, broken where particles left the domain.
  const Streakline& line() const { return line_; }

  // A particle: its parameter s along the segment, where it starts (on the mesh and in
  // space) and where it is at time().
  struct Particle {
    double s = 0.0;
    SurfacePoint start;
    Vec3 x0 = Vec3::Zero();
    FlowMapResult m;
    Vec3 x = Vec3::Zero();
    bool added = false;  // by an advance's refinement: coarsen() may drop it again
  };

private:
  // A surface timeline's path: at most this many segments (about an edge length each).
  static constexpr int kPathSegments = 256;
  Particle start_at(double s) const;
  void refine(double gap, bool mark_added);
  void coarsen(double gap);
  FlowMap flow_;
  std::shared_ptr<const PointLocator> locator_;
  double t0_ = 0.0, t_ = 0.0, max_gap_ = 0.0;
  int max_points_ = 0;
  std::vector<Vec3> path_;     // the line at t0: the segment, or the path over the surface
  std::vector<SurfacePoint> path_starts_;  // on a surface: the path's segments as walks over it
  std::vector<cplx> path_steps_;           // (SurfacePaths::Route)
  std::vector<double> along_;  // each path point's arclength over the whole (0 … 1)
  std::vector<Particle> particles_;
  Streakline line_;
};

}  // namespace tvf
