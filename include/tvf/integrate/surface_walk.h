#pragma once
// Moving a point along a triangle mesh by a tangent displacement (DESIGN §8): the
// straight line of the face's plane, continued across each edge it meets into the
// neighbouring face, unfolded about the shared edge (a geodesic of the piecewise-flat
// surface). The remaining displacement is carried into each new face's frame by
// TangentBundle::face_to_face, so the walk on a planar domain is a straight segment and on
// a surface it never leaves the surface. Integrators (streamline.h, pathline.h) take
// their RK4 stages with it.
#include "tvf/field/field_sampler.h"
#include "tvf/mesh/tangent_bundle.h"

#include <functional>
#include <span>

namespace tvf {

struct SurfaceWalk {
  SurfacePoint end;             // where the walk stopped
  cplx transport{1.0, 0.0};     // unit complex: a vector in the start face's frame times
                                // this is the same vector in end.face's frame
  bool hit_boundary = false;    // stopped on a boundary edge before the whole displacement
  bool stopped = false;         // stopped on entering a face that `stop_in` named
  double travelled = 1.0;       // fraction of |displacement| walked (1 unless stopped)
};

// Walks from `start` by `displacement` (in the frame of start.face: a·face_e1 + b·face_e2).
// A walk that reaches a boundary edge stops on it (hit_boundary); one that enters a face f
// with stop_in(f) true stops where it enters (stopped).
SurfaceWalk walk_surface(const TangentBundle& bundle, const SurfacePoint& start, cplx displacement,
                         const std::function<bool(int)>& stop_in = {});

// The vector of the vertex values `values` (each in its vertex basis) at p, in the frame of
// p.face: corner vectors transported into the face frame, interpolated barycentrically.
cplx interpolate_in_face(const TangentBundle& bundle, std::span<const cplx> values, const SurfacePoint& p);

}  // namespace tvf
