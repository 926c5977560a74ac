#pragma once
// Geodesic distance on a mesh by the heat method (Crane, Weischedel & Wardetzky 2013):
// heat flowed for t = time_factor·h² from the sources (h the mean edge length), its unit
// gradient field reversed, and the Poisson solve whose gradient is closest to it. Built on
// the same systems as the log map (mesh/log_map.h; the scalar heat flow M + tL and the
// Neumann Laplacian L with a pin per component, cotan weights of the intrinsic Delaunay
// triangulation, so non-negative on any mesh), factored once per mesh; each query is two
// back-substitutions and two passes over the faces (geometry-central's
// HeatMethodDistanceSolver is the model). On a flat domain the distance is the straight
// line's.
#include "tvf/field/field_sampler.h"
#include "tvf/mesh/tangent_bundle.h"

#include <memory>
#include <span>
#include <vector>

namespace tvf {

struct HeatSolvers;

class HeatDistance {
public:
  explicit HeatDistance(const TangentBundle& bundle, double time_factor = 1.0);
  ~HeatDistance();
  HeatDistance(const HeatDistance&) = delete;
  HeatDistance& operator=(const HeatDistance&) = delete;

  // The distance from the nearest of `sources` at every vertex (world units; the constant
  // of the Poisson solve fitted on the vertices around the sources, where the distance is
  // the chord to O(h³)). Vertices of a component without a source get +∞. Thread-safe.
  std::vector<double> distance(std::span<const SurfacePoint> sources) const;

private:
  const TangentBundle& bundle_;
  std::unique_ptr<HeatSolvers> solvers_;  // null on flat domains
};

}  // namespace tvf
