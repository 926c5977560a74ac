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
// surface, evenly spaced: a discrete geodesic, in the edge path's homotopy class.
#include "tvf/field/point_locator.h"
#include "tvf/mesh/tangent_bundle.h"

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

private:
  const TangentBundle& bundle_;
  const PointLocator& locator_;
};

}  // namespace tvf
