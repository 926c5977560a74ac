#pragma once
// The shortest path over a surface between two of its points, as a polyline on the surface
// (a discrete geodesic): the key-frame guide's paths between singularities
// (design/keyframe_topology.cpp) and the timelines drawn between two points of a surface
// (streakline.h). The shortest path along the mesh's edges (Dijkstra from the corners of
// p's face to those of q's) is resampled at about an edge length apart (at most
// `max_segments` segments), then straightened on the surface: Gauss–Seidel sweeps move each
// inner point towards the middle of its two neighbours by that displacement's part in its
// face's plane (over-relaxed; walk_surface, so a point never leaves the surface whatever the
// chord between its neighbours runs through), until no point moves more than 1e-6 edge
// lengths. Its fixed points are polylines whose turn at every point is normal to the
// surface, evenly spaced: a discrete geodesic, in the edge path's homotopy class. A chord
// may cut across a part thinner than it; `route` (below) keeps every segment on the surface.
#include "tvf/field/point_locator.h"
#include "tvf/mesh/tangent_bundle.h"

#include <optional>
#include <vector>

namespace tvf {

class SurfacePaths {
public:
  // `locator` must be the mesh's and outlive this.
  SurfacePaths(const TangentBundle& bundle, const PointLocator& locator);

  // The path from p to q (points on the surface; the first point is p and the last q, as
  // given): empty when no edge path joins them (another connected component); {p, q} when
  // they are one point; otherwise its points, which may all be one point when the
  // straightening shrinks the path to nothing.
  std::vector<Vec3> between(const Vec3& p, const Vec3& q, int max_segments = 96) const;

  // The shortest path as a walk over the surface: walking steps[k] (in the frame of
  // starts[k].face, walk_surface) from starts[k], which is points[k], ends at points[k + 1],
  // so a fraction of each step places the path's points in between continuously, which a
  // chord's closest surface point does not where the chord cuts across a fold or a thin
  // part (it jumps to the other side). Straightened over the surface itself (each point
  // moved towards the middle of the walks to its neighbours, only where both stay walks),
  // so it goes round the rim of a thin part where `between` cuts through it (CGAL's
  // camel's tail). About max_segments segments; empty when no path joins p and q.
  struct Route {
    std::vector<Vec3> points;
    std::vector<SurfacePoint> starts;
    std::vector<cplx> steps;
  };
  Route route(const Vec3& p, const Vec3& q, int max_segments = 96) const;

private:
  std::optional<std::vector<int>> edge_route(const SurfacePoint& sp, const Vec3& p, const SurfacePoint& sq,
                                             const Vec3& q) const;
  std::optional<cplx> shoot(const SurfacePoint& from, const Vec3& to, double tol) const;

  const TangentBundle& bundle_;
  const PointLocator& locator_;
};

}  // namespace tvf
