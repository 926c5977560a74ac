#pragma once
// Streamlines of one frame (DESIGN §8): RK4 on the unit direction field (arc-length
// parametrisation), both ways from the seed, on planar domains and on triangle-mesh
// surfaces alike. The position is carried as a face and barycentric coordinates; each RK4
// stage walks along the surface (surface_walk.h) and the stage's vector is carried back
// into the step's starting face frame by the walk's transport, so the curve never leaves
// the surface. A direction stops at the domain's boundary, where the field vanishes
// (|V| below stop_speed relative to the frame's largest |V|), on entering a face of
// non-zero index (a singularity, analysis/singularities.h), after max_length, when a
// caller's `accept` test refuses a point, or when the curve closes on itself.
#include "tvf/field/field.h"
#include "tvf/field/field_sampler.h"
#include "tvf/mesh/tangent_bundle.h"

#include <functional>
#include <span>
#include <vector>

namespace tvf {

// Why one direction of an integral curve ended.
enum class StopReason {
  none,         // the curve did not go this way (the seed itself stopped it)
  length,       // max_length (or the step limit) reached
  boundary,     // reached the domain's boundary
  singularity,  // |V| below the stop speed, or entered a face of non-zero index
  closed,       // came back to its seed (a closed orbit)
  rejected,     // the caller's accept() refused the next point
  time_range,   // pathlines: reached the end of the time range
};
const char* to_string(StopReason r);

struct StreamlineOptions {
  double step = 0.0;        // arc length per RK4 step; 0: half the mean edge length
  double max_length = 0.0;  // per direction; 0: the domain's bounding-box diagonal
  double stop_speed = 1e-9; // stop where |V| < stop_speed · (largest |V| of the frame)
  // The frame's largest |V| (max_speed(values)) when the caller has it, so that many short
  // lines on one frame do not each scan every vertex for it; negative: found from the values.
  double max_speed = -1.0;
  bool stop_at_singular_faces = true;  // stop on entering a face of non-zero index
  bool both_directions = true;         // false: forward only
  // With both_directions false: trace against the flow only; the points after the seed
  // (and stop_forward) are then that way's, in the order traced.
  bool backward_only = false;
  bool stop_when_closed = true;        // stop when the curve comes back to its seed
  // Called with each new point (world position); returning false ends that direction
  // (StopReason::rejected) without keeping the point. Used by evenly spaced placement.
  std::function<bool(const Vec3&)> accept;
};

struct Streamline {
  std::vector<Vec3> points;            // world positions, ordered along the flow
  std::vector<SurfacePoint> where;     // the same points on the mesh
  std::vector<double> speeds;          // |V| at each point
  size_t seed = 0;                     // index of the seed in points
  StopReason stop_backward = StopReason::none;  // at points.front()
  StopReason stop_forward = StopReason::none;   // at points.back()
  double length() const;
};

// The largest |V| of one frame's vertex values (what StreamlineOptions::max_speed takes).
double max_speed(std::span<const cplx> values);

// `values`: one frame, |V| vectors each in its vertex basis. The seed is snapped to the
// closest point of the surface; on a planar domain a seed outside the domain is an error
// (tvf::Error).
Streamline trace_streamline(const TangentBundle& bundle, std::span<const cplx> values,
                            const Vec3& seed, const StreamlineOptions& options = {});
Streamline trace_streamline(const TangentBundle& bundle, std::span<const cplx> values,
                            const SurfacePoint& seed, const StreamlineOptions& options = {});
// The field's values at time t (linear between frames; DESIGN §3).
std::vector<cplx> values_at(const Field& field, double t);

}  // namespace tvf
