#pragma once
// Pathlines of a time-varying field (DESIGN §8): solutions of dx/dt = V(x, t), t the
// design time, by RK4 in t with the field interpolated linearly in time between frames
// and barycentrically in space (field_sampler.h). As for streamlines the position is a
// face and barycentric coordinates and every stage walks along the surface
// (surface_walk.h), so planar domains and surfaces share one integrator. A pathline ends
// at the end of its time range, at the boundary, at a singularity (|V| below stop_speed
// relative to the field's largest |V|, or entering a face of non-zero index at the nearest
// frame), or after max_length of travel.
#include "tvf/field/field.h"
#include "tvf/integrate/streamline.h"

namespace tvf {

struct PathlineOptions {
  // The most RK4 steps one pathline takes (every step's point is kept: about 80 MB).
  static constexpr double kMaxSteps = 1e6;
  double t_start = 0.0;       // release time
  double t_end = 1.0;         // end time; t_end < t_start integrates backwards in time
  double dt = 0.0;            // time step; 0: a quarter of the frame spacing
  double max_length = 0.0;    // 0: no limit
  double stop_speed = 1e-9;   // relative to the largest |V| of the field
  bool stop_at_singular_faces = true;
};

struct Pathline {
  std::vector<Vec3> points;         // world positions, in order of time
  std::vector<SurfacePoint> where;  // the same points on the mesh
  std::vector<double> times;        // t of each point
  StopReason stop = StopReason::none;
  double length() const;
};

// The seed is snapped to the closest point of the surface; a seed outside a planar
// domain, a time outside the field's range, a negative or non-finite dt, or one that would
// take over kMaxSteps steps from t_start to t_end is an error (tvf::Error).
Pathline trace_pathline(const TangentBundle& bundle, const Field& field, const Vec3& seed,
                        const PathlineOptions& options = {});
Pathline trace_pathline(const TangentBundle& bundle, const Field& field, const SurfacePoint& seed,
                        const PathlineOptions& options = {});

}  // namespace tvf
