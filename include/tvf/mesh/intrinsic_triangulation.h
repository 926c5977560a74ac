#pragma once
// An intrinsic Delaunay triangulation of a mesh, on the same vertex set (Sharp, Soliman &
// Crane 2019, "Navigating intrinsic triangulations"; Sharp & Crane 2020, "A Laplacian for
// nonmanifold triangle meshes"). The surface and its vertices stay those of the input
// mesh; only the edges change: an edge may become a geodesic across several input faces,
// known by its length alone. Operators built on it (connection_laplacian's cotan weights,
// the log map's heat flows) have non-negative cotan weights whatever the input's triangle
// quality, while fields stay stored on the input's vertices in TangentBundle's bases.
//
// Construction:
//  1. Intrinsic mollification: every edge length grows by the same δ ≥ 0, the least that
//     makes every triangle satisfy l_i + l_j ≥ l_k + ε, ε = mollify_factor · mean edge
//     length (δ = 0 when every triangle already does, which is almost every mesh).
//  2. Intrinsic edge flips until every interior edge is locally Delaunay (cot α + cot β ≥
//     −delaunay_tolerance, α and β the angles opposite it). Boundary edges are never
//     flipped; a boundary edge whose one opposite angle is obtuse keeps a negative cotan
//     weight, which edge_weight() clamps to 0 (counted in clamped_edges()).
//
// Halfedges are corners, as in Mesh: h = 3·f + c runs from face(f)[c] to face(f)[(c+1)%3]
// inside intrinsic face f; before any flip the intrinsic faces are the input's, index for
// index. A flip rewrites its two faces in place. Faces may repeat a vertex and two edges
// may join the same two vertices (a Δ-complex): nothing here looks edges up by vertices.
//
// Directions (the bundle's convention): each halfedge keeps its angle φ ∈ [0, Θ_v) at its
// tail v, measured counter-clockwise from v's first outgoing input halfedge in intrinsic
// corner angles (Θ_v the intrinsic angle sum; the signposts of the 2019 paper). Its
// direction in T_v is that first halfedge's TangentBundle direction turned by s_v·φ, with
// s_v = 2π/Θ_v at interior vertices and 1 on the boundary, the rescaling TangentBundle
// uses. An edge still an input edge takes TangentBundle's direction and transport exactly;
// on a planar bundle every transport is exactly 1.
#include "tvf/mesh/tangent_bundle.h"

#include <array>
#include <vector>

namespace tvf {

struct IntrinsicTriangulationOptions {
  // ε of the mollification, relative to the mean input edge length.
  double mollify_factor = 1e-6;
  // An interior edge is flipped while ½(cot α + cot β) < −delaunay_tolerance.
  double delaunay_tolerance = 1e-10;
};

class IntrinsicTriangulation {
public:
  explicit IntrinsicTriangulation(const TangentBundle& bundle, IntrinsicTriangulationOptions options = {});

  const TangentBundle& bundle() const { return *bundle_; }
  int num_vertices() const { return nv_; }
  int num_faces() const { return static_cast<int>(faces_.size()); }
  int num_halfedges() const { return 3 * num_faces(); }

  // Connectivity (Mesh's layout: h = 3·f + c).
  static int face_of(int h) { return h / 3; }
  static int next(int h) { return 3 * (h / 3) + (h % 3 + 1) % 3; }
  static int prev(int h) { return 3 * (h / 3) + (h % 3 + 2) % 3; }
  const Face& face(int f) const { return faces_[static_cast<size_t>(f)]; }
  int tail(int h) const { return faces_[static_cast<size_t>(h / 3)][static_cast<size_t>(h % 3)]; }
  int head(int h) const { return tail(next(h)); }
  int twin(int h) const { return twin_[static_cast<size_t>(h)]; }

  // Geometry, from edge lengths only (world units).
  double length(int h) const { return length_[static_cast<size_t>(h)]; }
  double corner_angle(int h) const;                  // at tail(h) in face_of(h)
  double cot_opposite(int h) const { return cot_[static_cast<size_t>(h)]; }  // angle opposite h
  double face_area(int f) const;
  // The cotan weight ½(cot α + cot β) of h's edge (½ cot α on the boundary), clamped at 0.
  double edge_weight(int h) const;
  // Corner positions of face f laid out in the plane: corner 0 at the origin, corner 1 on
  // the positive x axis, corner 2 above it (z = 0).
  std::array<Vec3, 3> layout(int f) const;

  // Connection (see above): direction of h in T_tail(h) (unit), transport T_tail → T_head.
  cplx direction(int h) const;
  cplx transport(int h) const { return transport_[static_cast<size_t>(h)]; }
  // The input halfedge h still is (same edge, same direction), or −1 for a flipped edge.
  int input_halfedge(int h) const { return input_[static_cast<size_t>(h)]; }

  // What was done (STYLE 5).
  int flips() const { return flips_; }
  double mollification() const { return delta_; }  // δ added to every edge length
  // Edges whose weight was below −delaunay_tolerance after the flips (edge_weight() gives 0):
  // boundary edges with an obtuse opposite angle. Tiny negatives within the tolerance
  // (cocircular neighbours) are set to 0 too, uncounted.
  int clamped_edges() const { return clamped_; }
  double min_input_weight() const { return min_input_weight_; }  // smallest input cotan weight
  // True when nothing changed: the triangulation, its lengths and cotangents are the
  // input's exactly (the cotangents computed from the 3D positions as before).
  bool is_input() const { return flips_ == 0 && delta_ == 0.0; }

private:
  bool flip(int h);
  double raw_weight(int h) const;
  void set_face_cotangents(int f);

  const TangentBundle* bundle_;
  int nv_ = 0;
  std::vector<Face> faces_;
  std::vector<int> twin_, input_;
  std::vector<double> length_, cot_, phi_;
  std::vector<double> angle_sum_;  // Θ_v (intrinsic)
  std::vector<cplx> transport_;
  int flips_ = 0, clamped_ = 0;
  double delta_ = 0, min_input_weight_ = 0;
};

}  // namespace tvf
