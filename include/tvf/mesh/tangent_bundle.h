#pragma once
// The tangent bundle of a mesh (STYLE 1–3): a tangent basis per vertex and per face, and
// the discrete Levi-Civita connection as unit complex numbers.
//
// Vertex tangent spaces: normal n_i (area-weighted face normals), e1_i = the global x axis
// projected onto the tangent plane (global y where x is nearly normal), e2_i = n_i × e1_i.
// A tangent vector at i is z = a + ib meaning a·e1_i + b·e2_i.
//
// Connection (DESIGN §2): the direction of halfedge i→j in T_i is the angle of the first
// outgoing halfedge (its projection onto the plane) plus the sum of the corner angles
// swept counter-clockwise to reach i→j, the sums rescaled to 2π at interior vertices
// (boundary vertices keep their angles). transport(h) for h = i→j is the unit complex
// number r_ij = −u_ji / u_ij that carries a vector of T_i into T_j. On a vertex whose
// star is flat the directions are the plane's own (computed without trigonometry), so
// transports on planar domains are exactly 1.
//
// Face frames: n_f, e1_f (global x projected, as for vertices), e2_f. corner_to_face(h)
// carries T_{tail(h)} into the frame of face_of(h) (through the corner's bisector so that
// the rescaling is split evenly between its two edges); face_to_face(h) carries the frame
// of face_of(h) into the frame of face_of(twin(h)) by unfolding across the shared edge:
// the holonomy of face_to_face around an interior vertex equals its angle defect.
#include "tvf/mesh/mesh.h"

#include <vector>

namespace tvf {

class TangentBundle {
public:
  TangentBundle() = default;
  explicit TangentBundle(const Mesh& mesh);

  const Mesh& mesh() const { return *mesh_; }

  // Per vertex.
  const Vec3& vertex_normal(int v) const { return vn_[static_cast<size_t>(v)]; }
  const Vec3& vertex_e1(int v) const { return ve1_[static_cast<size_t>(v)]; }
  const Vec3& vertex_e2(int v) const { return ve2_[static_cast<size_t>(v)]; }
  double angle_sum(int v) const { return angle_sum_[static_cast<size_t>(v)]; }
  // 2π − angle sum for interior vertices, π − angle sum for boundary vertices.
  double angle_defect(int v) const;

  // Per halfedge h = i→j.
  cplx halfedge_direction(int h) const { return dir_[static_cast<size_t>(h)]; }  // in T_i, unit
  cplx transport(int h) const { return transport_[static_cast<size_t>(h)]; }      // T_i → T_j
  // Boundary halfedges have no transport across them: face_to_face returns 0 there.
  cplx corner_to_face(int h) const { return corner_to_face_[static_cast<size_t>(h)]; }
  cplx face_to_face(int h) const { return face_to_face_[static_cast<size_t>(h)]; }

  // Per face.
  const Vec3& face_normal(int f) const { return fn_[static_cast<size_t>(f)]; }
  const Vec3& face_e1(int f) const { return fe1_[static_cast<size_t>(f)]; }
  const Vec3& face_e2(int f) const { return fe2_[static_cast<size_t>(f)]; }

  // Conversions between world vectors and tangent coordinates (projection for from_*).
  Vec3 vertex_to_world(int v, cplx z) const {
    return z.real() * vertex_e1(v) + z.imag() * vertex_e2(v);
  }
  cplx world_to_vertex(int v, const Vec3& w) const {
    return {w.dot(vertex_e1(v)), w.dot(vertex_e2(v))};
  }
  Vec3 face_to_world(int f, cplx z) const { return z.real() * face_e1(f) + z.imag() * face_e2(f); }
  cplx world_to_face(int f, const Vec3& w) const { return {w.dot(face_e1(f)), w.dot(face_e2(f))}; }

  // True when every vertex and face frame is the global (x, y) frame and every transport
  // is 1 (planar domains in the z = 0 plane).
  bool is_flat() const { return flat_; }

private:
  const Mesh* mesh_ = nullptr;
  std::vector<Vec3> vn_, ve1_, ve2_, fn_, fe1_, fe2_;
  std::vector<double> angle_sum_;
  std::vector<cplx> dir_, transport_, corner_to_face_, face_to_face_;
  bool flat_ = false;
};

// A tangent basis (e1, e2) for the plane with unit normal n: the global x axis projected
// onto the plane, or global y when x is within ~25° of n. Exact for n = (0, 0, 1).
void tangent_basis(const Vec3& n, Vec3& e1, Vec3& e2);

}  // namespace tvf
