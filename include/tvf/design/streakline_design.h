#pragma once
// Streaklines as a design element (issue 20, the paper's §10 flow descriptors): the user
// sketches the shape a streakline has at time t, and the constrained and spacetime
// generators make the field reproduce it.
//
// The element (scene.h's StreaklineElement) is a polyline p(s), arc length s ∈ [0, L],
// seed p(0), and a release interval [from, t]. A streakline at t is the locus of the
// particles released from the seed at τ ∈ [from, t]; the sketch says nothing about the
// release rate along it, so tvf takes the one natural choice: dye advances along the
// polyline at the constant speed u = L / (t − from), so that the particle released at τ is
// at arc length u·(t − τ) at time t — the oldest one (τ = from) at the polyline's end, the
// youngest (τ = t) at the seed.
//
// What is constrained: at time t′ ∈ [from, t] the particles released so far cover the
// polyline's first u·(t′ − from) of arc length (the dye front). On that part the field is
// fixed to u times the polyline's unit tangent T (hard constraints, at the corners of the
// faces the polyline crosses, sampled every quarter edge length and averaged where
// samples meet, as key-frame streamlines are; at the polyline's corners the tangent turns
// smoothly over u·Δt + h of arc on either side, so the front never meets a jump in it);
// ahead of the front and outside [from, t]
// the solve is free. Then every released particle moves along the polyline at speed u
// for its whole life, and so sits at arc length u·(t − τ) at time t: the sketched shape.
// No smaller set of constraints does that (the field where no dye is never matters to the
// streakline), so the rest of the design keeps its freedom.
// After t the streakline is what it is; the field there is free, but letting go of the
// whole polyline at one frame would jolt it (the coherence series jumped sixfold there):
// the constraints let go from the seed end at 4u, the dye still moving along the sketch,
// so the field relaxes over (t − from)/4.
// Discretisation margins: the front is led by one frame's travel u·Δt plus two mean edge
// lengths, and the frames just before `from` and just after t (when these fall between
// frames) are constrained too, because the flow map interpolates the field linearly in
// time between frames and within faces in space.
// `attach` c ≥ 0 adds, as a regular element's attachment does, a pull −c·u·y′·n onto the
// polyline (y′ the signed offset of the constrained vertex from the sample, n the left
// normal): the polyline becomes attracting, so that a particle off it by interpolation
// error comes back instead of drifting.
#include "tvf/scene/design_space.h"
#include "tvf/scene/scene.h"

#include <limits>
#include <optional>
#include <span>
#include <string>
#include <utility>
#include <vector>

namespace tvf {

// How far a traced streakline (tvf streaklines; integrate/streakline.h) lies from the
// sketch, both ways, in world units: every traced point's distance to the sketched
// polyline, and the sketch's (sampled at 12 points per segment and its end) distance to the
// traced polyline (consecutive points joined). Hausdorff is the largest of all those, mean
// their average. Both are blind to order: a sketch that folds back along itself is near a
// dye that only went out. The Fréchet distance is not: the largest gap between the two
// curves walked together from the seed (the traced one is oldest first, as
// trace_streakline gives it, so it is walked from its end), each forward only, resampled
// at a 2000th of the longer length (so within that of the continuous distance). An empty
// or one-point traced curve is infinitely far.
struct StreaklineMatch {
  double hausdorff = 0;
  double mean = 0;
  double frechet = 0;
};
StreaklineMatch compare_streakline(std::span<const Vec3> sketch, std::span<const Vec3> traced);

// Where a sketch comes closest to itself between two parts of it that are not one
// stretch of curve: the polyline sampled every quarter of `h` (at most 4000 samples), and
// of the sample pairs further apart along it than max(8h, 8d), d their distance (so a
// corner sharper than 14° counts, a wider one does not), the closest. distance is +∞
// when no pair is that far apart along it. On a closed sketch (last point on the first)
// distances along it are taken round the loop, the shorter way: the closing point is not
// an approach.
struct SketchSelfApproach {
  double distance = std::numeric_limits<double>::infinity();
  double along = 0;  // their distance along the sketch
  Vec3 a = Vec3::Zero(), b = Vec3::Zero();
};
SketchSelfApproach sketch_self_approach(std::span<const Vec3> points, double h);

// How close, in mean edge lengths, two such parts of a sketch may come for the traced dye
// to follow it (measured by the Fréchet distance on a U whose two sides are d apart, at
// 33², 65² and 129², 31 frames): with `attach` > 0 it is followed from 1 edge length at
// every grid (at 0.75: 10, 18 and 33 edge lengths off); without, dye that strays by the
// linear interpolation is carried onto the other side from further away, up to 3 edge
// lengths at 129² (at 1 edge: 4.7, 9.2 and 28 off; at 3 on 129²: 5.7). generate() warns.
inline constexpr double kSketchApartEdges = 1.0;
inline constexpr double kSketchApartEdgesUnattached = 4.0;

// Where a sketch on a surface crosses or folds back onto itself (planar sketches are refused
// by the scene reader, exactly): at t each released particle is at one point, so two parts
// of the sketch at one point would be two particles there at once. The sketch's chords are
// cut into pieces of at most a quarter edge length whose ends are snapped onto the surface
// (a long chord runs through the inside); two pieces that are not neighbours, come within
// half an edge length of each other and face the same way (not the two sides of a thin
// part) are projected onto the plane normal to the surface between them and tested there,
// as the reader tests planar segments; two neighbours fold back when, in the plane normal
// to both their faces, the second turns back along the first. Returns the indices of the
// two sketch points whose segments meet, or nothing. A closed sketch (last point on the
// seed) is not a crossing.
std::optional<std::pair<size_t, size_t>> surface_sketch_crossing(const DesignSpace& space,
                                                                 std::span<const Vec3> points);
// Refuses (tvf::Error located at "elements[i].points", one sentence) the first streakline
// element of `scene` whose sketch meets itself on `space`'s surface; nothing on planar
// domains (the reader has tested them). The sentence names `label` (empty: scene.label()),
// as the reader's name the label it was given. check_scene_on_domain (generate.h) calls it.
void check_surface_sketches(const DesignSpace& space, const Scene& scene, const std::string& label = "");

class StreaklineConstraints {
public:
  // Every streakline element of scene.elements, prepared on the domain (world points
  // snapped to the surface on meshes).
  StreaklineConstraints(const DesignSpace& space, const Scene& scene);

  bool empty() const { return lines_.empty(); }
  size_t size() const { return lines_.size(); }
  // The dye's speed u = L / (t − from) of the k-th streakline (world units per unit time).
  double speed(size_t k) const { return lines_[k].speed; }
  // Its length L (world units, along the polyline's chords).
  double length(size_t k) const { return lines_[k].length; }

  // Adds the constraints of time `t` (one frame: |V| entries each): fixed[v] = 1 and
  // values[v] += the streaklines' value (averaged over the samples that reach v) at every
  // vertex a dye front covers, in v's tangent basis. A vertex not yet fixed starts from 0.
  void constrain(double t, std::span<char> fixed, std::span<cplx> values) const;

private:
  struct Sample {
    double s = 0;      // arc length of the sample along the polyline
    int corners[3]{};  // the face holding it
    cplx value[3]{};   // the constraint at each corner, in that corner's basis
  };
  struct Line {
    double from = 0, t = 1, speed = 0, length = 0;
    std::vector<Sample> samples;  // increasing s
  };
  std::vector<Line> lines_;
  int vertices_ = 0;
  double frame_dt_ = 0;  // the scene's frame spacing
  double lead_ = 0;      // 2 mean edge lengths
};

}  // namespace tvf
