#pragma once
// Flow maps of a time-varying field (beyond the paper, its §10): where the particle at p
// at time t0 is at time t1, the solution of dx/dt = V(x, t) by RK4 in t with the field
// interpolated linearly in time between frames and barycentrically in space
// (field_sampler.h). Used by the Lagrangian descriptors: FTLE (ftle.h), streaklines and
// timelines (streakline.h).
//
// Unlike a pathline (pathline.h) a flow map does not stop at singularities (particles
// keep moving towards a sink or around a centre) and keeps no trail. The interval
// [t0, t1] is split at the frame times (where the field's time derivative jumps) and each
// piece is walked in equal RK4 steps of at most `dt`, and of at most the time the field's
// fastest point takes to cross kReachEdges mean edge lengths (a step that crosses many
// faces samples the piecewise-linear field too coarsely, and a fast field over a long time
// range would wrap the walk round the mesh; one step for every particle, not one per
// particle's own speed, keeps the flow map smooth from particle to particle, which FTLE
// differentiates). A field whose speed would need over kMaxSteps such steps across its
// time range is refused, as is a given `dt` that would. Every stage walks along the
// surface (surface_walk.h), so planar domains and surfaces share one integrator. A step
// that meets the domain's boundary slides along it when the remaining displacement is
// tangential there (rounding); one whose displacement points out of the domain leaves it:
// the particle is then reported as gone (FlowMapResult::left).
//
// On a planar regular grid (one made by make_grid, grid.h) the same steps run on the grid
// directly: the point is located by dividing by the spacing instead of walking, and the
// walls are the box's sides (src/integrate/grid_flow.h). The results agree with the walk
// to rounding (the tests check 1e-8) at a small fraction of the cost: this is what lets
// the designer update FTLE while designing. FlowMapOptions::walk forces the walk.
#include "tvf/field/field.h"
#include "tvf/field/field_sampler.h"
#include "tvf/mesh/tangent_bundle.h"

#include <memory>
#include <span>
#include <vector>

namespace tvf {

namespace detail {
class GridFlow;
}

struct FlowMapOptions {
  double dt = 0.0;  // largest RK4 time step; 0: half the frame spacing
  bool walk = false;  // walk the surface even on a planar grid (the tests compare both paths)
};

struct FlowMapResult {
  SurfacePoint where;     // the particle at t1 (or where it left the domain)
  bool left = false;      // it left the domain before t1
  double t_left = 0.0;    // the start of the RK4 step in which it left (t1 when it did not)
};

class FlowMap {
public:
  // The farthest one RK4 step moves at the field's fastest point, in mean edge lengths
  // (designed fields sampled at their frames move far less: the designer's 65² double
  // gyre, half a frame a step, about 1.7 cells), and the most steps across the field's whole
  // time range (see above).
  static constexpr double kReachEdges = 4;
  static constexpr double kMaxSteps = 1e6;
  // Throws tvf::Error on a non-positive dt or one that takes over kMaxSteps steps across the
  // field's time range, a field that does not fit the mesh, or one too fast for its time
  // range (over kMaxSteps steps of kReachEdges mean edge lengths).
  FlowMap(const TangentBundle& bundle, const Field& field, const FlowMapOptions& options = {});

  // The particle at p at time t0, carried to t1 (t1 < t0: backwards in time). t0 and t1
  // must lie in the field's time range (tvf::Error otherwise).
  FlowMapResult advect(const SurfacePoint& p, double t0, double t1) const;
  // Many particles, in parallel (TBB).
  std::vector<FlowMapResult> advect(std::span<const SurfacePoint> points, double t0, double t1) const;

  const TangentBundle& bundle() const { return bundle_; }
  const Field& field() const { return field_; }
  double dt() const { return dt_; }
  // Whether the planar-grid fast path is in use.
  bool on_grid() const { return grid_ != nullptr; }

private:
  void check_time(double t) const;
  std::vector<double> knots(double t0, double t1) const;
  FlowMapResult advect_through(const SurfacePoint& p, const std::vector<double>& knots) const;
  const TangentBundle& bundle_;
  const Field& field_;
  FieldSampler sampler_;
  double dt_ = 0.0;
  std::shared_ptr<const detail::GridFlow> grid_;  // planar grids: the fast path
};

}  // namespace tvf
