#include "tvf/mesh/mesh.h"

#include "tvf/core/error.h"
#include "tvf/mesh/mesh_validate.h"

#include <algorithm>
#include <cmath>
#include <unordered_map>

namespace tvf {

namespace {
std::uint64_t edge_key(int a, int b) {
  const auto lo = static_cast<std::uint64_t>(std::min(a, b));
  const auto hi = static_cast<std::uint64_t>(std::max(a, b));
  return (lo << 32) | hi;
}
}  // namespace

Mesh::Mesh(std::vector<Vec3> positions, std::vector<Face> faces, std::string source)
    : positions_(std::move(positions)), faces_(std::move(faces)), source_(std::move(source)) {
  validate_triangle_soup(positions_, faces_, source_);
  build_connectivity();
}

void Mesh::build_connectivity() {
  const int nh = num_halfedges();
  const auto nv = positions_.size();
  twin_.assign(static_cast<size_t>(nh), -1);
  halfedge_edge_.assign(static_cast<size_t>(nh), -1);
  edge_vertices_.clear();

  // Pair halfedges through an edge map; validation guarantees at most two per edge with
  // opposite orientation.
  std::unordered_map<std::uint64_t, int> first;
  first.reserve(static_cast<size_t>(nh));
  for (int h = 0; h < nh; ++h) {
    const auto key = edge_key(tail(h), head(h));
    auto [it, inserted] = first.try_emplace(key, h);
    if (inserted) {
      halfedge_edge_[static_cast<size_t>(h)] = static_cast<int>(edge_vertices_.size());
      edge_vertices_.push_back({std::min(tail(h), head(h)), std::max(tail(h), head(h))});
    } else {
      const int o = it->second;
      TVF_CHECK(twin_[static_cast<size_t>(o)] < 0, "edge {}-{} has more than two faces", tail(h),
                head(h));
      twin_[static_cast<size_t>(o)] = h;
      twin_[static_cast<size_t>(h)] = o;
      halfedge_edge_[static_cast<size_t>(h)] = halfedge_edge_[static_cast<size_t>(o)];
    }
  }
  num_boundary_edges_ = static_cast<int>(std::count(twin_.begin(), twin_.end(), -1));

  // Any outgoing halfedge per vertex; for boundary vertices the one with no face on its
  // clockwise side, i.e. whose prev is a boundary halfedge... we look for the outgoing
  // halfedge h with twin(prev(h)) unused as a start below.
  std::vector<int> any_out(nv, -1);
  boundary_vertex_.assign(nv, 0);
  for (int h = 0; h < nh; ++h) {
    any_out[static_cast<size_t>(tail(h))] = h;
    if (twin(h) < 0) {
      boundary_vertex_[static_cast<size_t>(tail(h))] = 1;
      boundary_vertex_[static_cast<size_t>(head(h))] = 1;
    }
  }

  outgoing_offset_.assign(nv + 1, 0);
  outgoing_.clear();
  outgoing_.reserve(static_cast<size_t>(nh));
  for (size_t v = 0; v < nv; ++v) {
    outgoing_offset_[v] = static_cast<int>(outgoing_.size());
    int start = any_out[v];
    TVF_CHECK(start >= 0, "vertex {} has no face", v);
    // Rotating clockwise from h: twin(h) then next. Walk clockwise to the boundary start.
    if (boundary_vertex_[v]) {
      int h = start;
      for (;;) {
        const int t = twin(h);
        if (t < 0) break;
        h = next(t);
        TVF_CHECK(h != start, "boundary vertex {} has a closed fan", v);
      }
      start = h;
    }
    // Counter-clockwise: h -> twin(prev(h)).
    int h = start;
    do {
      outgoing_.push_back(h);
      const int t = twin(prev(h));
      if (t < 0) break;
      h = t;
    } while (h != start);
  }
  outgoing_offset_[nv] = static_cast<int>(outgoing_.size());
  TVF_CHECK(outgoing_.size() == static_cast<size_t>(nh), "vertex fans cover {} of {} halfedges",
            outgoing_.size(), nh);

  planar_xy_ = std::all_of(positions_.begin(), positions_.end(),
                           [](const Vec3& p) { return p.z() == 0.0; });
}

Vec3 Mesh::face_normal(int f) const {
  const Face& t = face(f);
  const Vec3 n = (position(t[1]) - position(t[0])).cross(position(t[2]) - position(t[0]));
  return n.normalized();
}

double Mesh::face_area(int f) const {
  const Face& t = face(f);
  return 0.5 * (position(t[1]) - position(t[0])).cross(position(t[2]) - position(t[0])).norm();
}

double Mesh::corner_angle(int h) const {
  const Vec3& a = position(tail(h));
  const Vec3 u = position(head(h)) - a;
  const Vec3 w = position(tail(prev(h))) - a;
  // atan2 of |u×w| and u·w is accurate for all angles, unlike acos.
  return std::atan2(u.cross(w).norm(), u.dot(w));
}

double Mesh::mean_edge_length() const {
  double sum = 0;
  for (const auto& e : edge_vertices_) sum += (position(e[1]) - position(e[0])).norm();
  return edge_vertices_.empty() ? 0.0 : sum / static_cast<double>(edge_vertices_.size());
}

Vec3 Mesh::bbox_min() const {
  Vec3 m = Vec3::Constant(std::numeric_limits<double>::infinity());
  for (const auto& p : positions_) m = m.cwiseMin(p);
  return m;
}

Vec3 Mesh::bbox_max() const {
  Vec3 m = Vec3::Constant(-std::numeric_limits<double>::infinity());
  for (const auto& p : positions_) m = m.cwiseMax(p);
  return m;
}

}  // namespace tvf
