#pragma once
// Going back from a log-map chart to the surface (the exponential map at the chart's point
// p), for moving things on a surface in local coordinates: a bifurcation's neighbourhood
// (edit/field_editor.h) and a representative streamline (the deform generator).
//
// The chart (log_map.h) gives every vertex its log coordinates log_p(x_v); a point inside
// a face has the barycentric combination of its corners' coordinates. The inverse maps a
// chart point w back by point location in that log-coordinate triangulation: the face
// whose image holds w, with w's barycentric coordinates in the image. Only faces whose
// corners all lie within `radius` of p and whose image keeps the face's orientation are
// used, so a fold of the chart (near the cut locus, where geodesics from p meet) is never
// inverted; a point outside them has no inverse (std::nullopt). On a planar domain the
// chart is x − p and the inverse is exact translation.
//
// Vectors: a vector z in the chart's frame (the frame at p, carried by parallel transport)
// is z·chart.frame[v] at a vertex v, and z·frame_in_face(q) in the frame of face q.face.
#include "tvf/field/field_sampler.h"
#include "tvf/mesh/log_map.h"
#include "tvf/mesh/tangent_bundle.h"

#include <optional>
#include <vector>

namespace tvf {

class ChartInverse {
public:
  // `bundle` and `chart` must outlive the object. radius: world units (geodesic distance
  // from p); faces with a corner farther out are not inverted.
  ChartInverse(const TangentBundle& bundle, const LocalChart& chart, double radius);

  // The surface point whose log coordinates are w, or nullopt outside the inverted faces.
  std::optional<SurfacePoint> locate(cplx w) const;
  // Log coordinates of a surface point (barycentric combination of its corners').
  cplx coords(const SurfacePoint& q) const;
  // The chart frame's first axis at q, as a unit complex number in the frame of face q.face:
  // a chart vector z is z·frame_in_face(q) there.
  cplx frame_in_face(const SurfacePoint& q) const;

  double radius() const { return radius_; }

private:
  const TangentBundle& bundle_;
  const LocalChart& chart_;
  double radius_;
  cplx lo_{0, 0};
  double cell_ = 1;
  int n_ = 1;  // buckets per side
  std::vector<std::vector<int>> buckets_;
};

}  // namespace tvf
