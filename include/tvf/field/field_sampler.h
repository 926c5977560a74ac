#pragma once
// Evaluating a field anywhere in space-time (DESIGN §2–3): inside a face the three corner
// vectors are transported into the face frame and interpolated barycentrically (Zhang et
// al. 2006); between frames the vertex values are interpolated linearly in t (Tricoche et
// al. 2001).
#include "tvf/field/field.h"
#include "tvf/mesh/tangent_bundle.h"

#include <optional>
#include <string>

namespace tvf {

// A point on the mesh: a face and barycentric coordinates of its three corners
// (mesh.face(f)[0..2]), summing to 1.
struct SurfacePoint {
  int face = -1;
  Vec3 bary{1.0 / 3, 1.0 / 3, 1.0 / 3};
};

class FieldSampler {
public:
  FieldSampler(const TangentBundle& bundle, const Field& field) : bundle_(bundle), field_(field) {}

  // Vector at (p, t) in the frame of face p.face.
  cplx in_face(const SurfacePoint& p, double t) const;
  // The same vector in world coordinates.
  Vec3 world(const SurfacePoint& p, double t) const;
  // Vertex value at time t (linear between frames), in the vertex basis.
  cplx at_vertex(int v, double t) const;

private:
  const TangentBundle& bundle_;
  const Field& field_;
};

// Point location and projection onto a mesh.
// Closest point of the mesh to x (brute force over faces with a bounding-sphere cull;
// scenes place few points, so no spatial index is kept).
SurfacePoint closest_point(const Mesh& mesh, const Vec3& x);
Vec3 surface_position(const Mesh& mesh, const SurfacePoint& p);
// What is wrong with a point a user gave (`what`: "the streamline seed") on a planar mesh
// (z = 0), `on` its closest point of the mesh: off the plane (z ≠ 0: a mistake, not a point
// to project), or outside the domain; empty where nothing is, and on surfaces.
std::string planar_point_problem(const Mesh& mesh, const Vec3& x, const Vec3& on, const std::string& what);

}  // namespace tvf
