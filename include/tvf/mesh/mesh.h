#pragma once
// A triangle mesh: positions and connectivity, nothing else (the tangent bundle and the
// fields living on it are separate types; STYLE 1).
//
// Halfedges are corners: halfedge h = 3·f + c runs from faces[f][c] to
// faces[f][(c + 1) % 3] inside face f. twin(h) is the opposite halfedge in the
// neighbouring face, or -1 on the boundary. A Mesh is always a valid oriented
// 2-manifold (with or without boundary): the constructor checks it and throws
// tvf::Error otherwise (see mesh_validate.h for the checks and the repairs).
#include "tvf/core/types.h"

#include <array>
#include <cstdint>
#include <span>
#include <string>
#include <vector>

namespace tvf {

using Face = std::array<int, 3>;

class Mesh {
public:
  Mesh() = default;
  // Validates (mesh_validate.h) and builds connectivity. `source` names the input in
  // error messages (a file name, or "grid").
  Mesh(std::vector<Vec3> positions, std::vector<Face> faces, std::string source = "mesh");

  int num_vertices() const { return static_cast<int>(positions_.size()); }
  int num_faces() const { return static_cast<int>(faces_.size()); }
  int num_halfedges() const { return 3 * num_faces(); }
  int num_edges() const { return static_cast<int>(edge_vertices_.size()); }

  const std::vector<Vec3>& positions() const { return positions_; }
  const std::vector<Face>& faces() const { return faces_; }
  const Vec3& position(int v) const { return positions_[static_cast<size_t>(v)]; }
  const Face& face(int f) const { return faces_[static_cast<size_t>(f)]; }
  const std::string& source() const { return source_; }

  // Halfedge navigation.
  static int face_of(int h) { return h / 3; }
  static int next(int h) { return 3 * (h / 3) + (h % 3 + 1) % 3; }
  static int prev(int h) { return 3 * (h / 3) + (h % 3 + 2) % 3; }
  int tail(int h) const { return faces_[static_cast<size_t>(h / 3)][static_cast<size_t>(h % 3)]; }
  int head(int h) const { return tail(next(h)); }
  int twin(int h) const { return twin_[static_cast<size_t>(h)]; }
  int edge_of(int h) const { return halfedge_edge_[static_cast<size_t>(h)]; }
  bool is_boundary_halfedge(int h) const { return twin(h) < 0; }
  // Endpoints (i < j) of edge e.
  const std::array<int, 2>& edge(int e) const { return edge_vertices_[static_cast<size_t>(e)]; }

  // Outgoing halfedges of v in counter-clockwise order (around the face normals). For a
  // boundary vertex the list starts at the boundary halfedge that leaves v (no face on
  // its clockwise side) and ends at the one whose previous halfedge lies on the
  // boundary.
  std::span<const int> outgoing(int v) const {
    const auto b = static_cast<size_t>(outgoing_offset_[static_cast<size_t>(v)]);
    const auto e = static_cast<size_t>(outgoing_offset_[static_cast<size_t>(v) + 1]);
    return {outgoing_.data() + b, e - b};
  }
  bool is_boundary_vertex(int v) const { return boundary_vertex_[static_cast<size_t>(v)] != 0; }
  bool is_closed() const { return num_boundary_edges_ == 0; }
  int num_boundary_edges() const { return num_boundary_edges_; }
  int euler_characteristic() const { return num_vertices() - num_edges() + num_faces(); }

  // Geometry helpers (computed from positions; cheap).
  Vec3 face_normal(int f) const;  // unit
  double face_area(int f) const;
  double corner_angle(int h) const;  // interior angle at tail(h) in face_of(h)
  double edge_length(int h) const { return (position(head(h)) - position(tail(h))).norm(); }
  double mean_edge_length() const;
  Vec3 bbox_min() const;
  Vec3 bbox_max() const;
  double diameter() const { return (bbox_max() - bbox_min()).norm(); }  // bbox diagonal
  // True when every vertex has z = 0 exactly: a planar domain, whose tangent bundle is
  // the global (x, y) frame everywhere.
  bool is_planar_xy() const { return planar_xy_; }

private:
  void build_connectivity();

  std::vector<Vec3> positions_;
  std::vector<Face> faces_;
  std::string source_;
  std::vector<int> twin_;
  std::vector<int> halfedge_edge_;
  std::vector<std::array<int, 2>> edge_vertices_;
  std::vector<int> outgoing_offset_;
  std::vector<int> outgoing_;
  std::vector<std::uint8_t> boundary_vertex_;
  int num_boundary_edges_ = 0;
  bool planar_xy_ = false;
};

}  // namespace tvf
