#pragma once
// Periodic orbits (closed streamlines) of each frame, tracked through time, and the Hopf
// events where a cycle is born from or shrinks into a focus whose stability changes
// (DESIGN §12; beyond the paper, its §10). docs/analysis.md, "Periodic orbits".
//
// Method. Around every focus or center of a frame (Topology::singularities) a Poincaré
// section is laid along a ray from it, in the plane of its face (on surfaces the seeds are
// placed by walking the surface along the ray, and radius and angle are measured in that
// plane, so the section works while the orbit stays within the chart of the focus's tangent
// plane: orbits small against the curvature radius). The return map P(r) takes the point
// at distance r on the ray once around the focus by the streamline integrator
// (streamline.h: RK4 on the unit field, surface walks) until its winding angle about the
// focus reaches ±2π, and reads the distance of the crossing. D(r) = P(r) − r is sampled
// on radii from `min_radius` edge lengths up to 90 % of the distance to the nearest other
// singularity (and to the domain boundary along the ray); a sign change of D is refined by
// the Illinois variant of regula falsi. The fixed point r* is a cycle: attracting where D
// falls through zero (the map contracts), repelling where it rises. Only hyperbolic cycles
// are reported: the map that contracts onto r* (forward for an attracting cycle, backward
// for a repelling one) must contract by `min_multiplier_gap` (10 %) per turn, measured by
// differences over ±¼ edge length on both sides of r* (the edge of a center's ring of
// closed orbits, neutral inside and spiralling outside, contracts on one side only) — the
// closed orbits of a center are neutral (P ≡ id, D only
// the integrator's and the interpolation's error, which measured up to 7 % per turn around
// the moving vortex of example 02) and are not cycles. A Hopf cycle contracts by
// e^{−4π|μ|} per turn, past 10 % once |μ| > 0.0084. The orbit's points are the streamline through r*,
// traced forward for an attracting cycle and backward for a repelling one (the direction in
// which it attracts), one turn. Its period is ∮ ds/|V| along it, in the units of the
// streamline parameter of the field (dx/dτ = V), and its multiplier (the forward map's
// slope at r*) exp(∮ div V dτ) along it.
//
// Tracking. An orbit of frame j + 1 continues an orbit of frame j of the same stability
// whose center lies within `track_distance` edge lengths and whose radius differs by at
// most that distance or 30 % (nearest first); a track keeps its id.
//
// Hopf events. Along each focus/center (matched from frame to frame by nearest position
// within `track_distance` edge lengths) the trace of the face Jacobian changing sign
// between frames j and j + 1 with complex eigenvalues on both sides marks a stability
// change at t* (linear in the trace); it is a Hopf event when an orbit track around that
// focus, at least two frames long, begins or ends within `hopf_frames` frames of t* (one
// frame early allowed: the focus's face Jacobian and the cycle's streamlines read the
// piecewise-linear field differently near t*), and the focus changes stability for real:
// on each side, while the trace keeps its sign, within `hopf_frames` frames or past them
// while r = |Re λ / Im λ| still grows, its largest r is at least that of a hyperbolic
// focus (e^{2πr} − 1 ≥ min_multiplier_gap) and the two sides' sum more than the center
// band's width 2·kCenterTolerance (not a center whose trace wavers about zero beside a
// cycle of the nonlinear part).
// Supercritical when the cycle is
// attracting (it surrounds the repelling focus), subcritical when it is repelling.
#include "tvf/analysis/topology.h"
#include "tvf/field/field.h"
#include "tvf/mesh/tangent_bundle.h"

#include <nlohmann/json.hpp>

#include <string>
#include <vector>

namespace tvf {

enum class OrbitStability { attracting, repelling };
const char* to_string(OrbitStability s);  // "attracting" | "repelling"

struct PeriodicOrbit {
  int id = 0;            // track id: the same cycle at every frame it lives
  int frame = 0;
  double t = 0.0;
  Vec3 center = Vec3::Zero();  // the focus or center it surrounds (world)
  int singularity = -1;        // index of that singularity in Topology::singularities[frame]
  double radius = 0.0;         // mean distance of the points from the center
  double period = 0.0;         // ∮ ds/|V|, in the field's streamline parameter
  double multiplier = 0.0;     // P′(r*) of the forward map, exp(∮ div V dτ) along the orbit:
                               // < 1 attracting, > 1 repelling (+inf past e^709)
  OrbitStability stability = OrbitStability::attracting;
  std::vector<Vec3> points;    // one turn, world positions, in the direction of the flow
                               // (at most 96: every k-th point of the traced curve)
};

struct HopfEvent {
  double t = 0.0;
  Vec3 position = Vec3::Zero();
  bool supercritical = true;   // the cycle is attracting (around the repelling focus)
  int orbit = -1;              // id of the orbit track born or ended there
  std::vector<int> paths;      // singularity path ids of the focus before and after t (one
                               // id when the same path holds it on both sides)
};

struct PeriodicOrbits {
  std::vector<PeriodicOrbit> orbits;  // by frame, then by singularity
  std::vector<HopfEvent> hopf;        // sorted by t
};

struct PeriodicOrbitOptions {
  bool parallel = true;           // frames in parallel (TBB)
  double min_radius = 1.5;        // smallest radius searched, in mean edge lengths
  double max_radius = 0.5;        // largest radius searched, fraction of the bbox diagonal
  int radius_samples = 24;        // samples of D(r) along the ray (at most)
  double min_multiplier_gap = 0.1;   // contraction per turn below this: neutral, not reported
  double track_distance = 2.0;    // tracking and focus matching, in mean edge lengths
  int hopf_frames = 5;            // orbit track end to stability change, in frames
  bool include_nodes = false;     // also search around sources and sinks
  // Checked between frames: once true, find_periodic_orbits stops with AnalysisCancelled
  // (topology.h).
  const std::atomic<bool>* cancel = nullptr;
};

// Periodic orbits of every frame of `field` around the foci and centers of `topology`
// (which must be analyze_topology's result for the same field), tracked, and the Hopf
// events.
PeriodicOrbits find_periodic_orbits(const TangentBundle& bundle, const Field& field, const Topology& topology,
                                    const PeriodicOrbitOptions& options = {});

// The cycles of one frame: `values` its |V| vertex values, `singularities` its
// singularities (find_singularities). Track ids are left 0.
std::vector<PeriodicOrbit> find_frame_orbits(const TangentBundle& bundle, std::span<const cplx> values,
                                             const std::vector<Singularity>& singularities,
                                             const PeriodicOrbitOptions& options = {});

// Adds the orbits to the analysis JSON of topology_to_json (DESIGN §12): "periodic_orbits":
// [{"frame", "t", "center", "radius", "stability", "points", "id", "period",
// "multiplier"}], and appends the Hopf events to "bifurcations" after the saddle–node ones
// (whose indices stay those of Topology::bifurcations): {"t", "position", "kind": "hopf",
// "paths", "orbit", "criticality": "supercritical" | "subcritical"}.
void add_periodic_orbits_to_json(nlohmann::json& analysis, const PeriodicOrbits& orbits);

}  // namespace tvf
