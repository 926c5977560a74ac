#include "tvf/field/point_locator.h"

#include "tvf/core/error.h"

#include <CGAL/AABB_traits.h>
#include <CGAL/AABB_tree.h>
#include <CGAL/AABB_triangle_primitive.h>
#include <CGAL/Simple_cartesian.h>
#include <nanoflann.hpp>

#include <algorithm>
#include <cstdint>
#include <vector>

namespace tvf {

namespace {
using Kernel = CGAL::Simple_cartesian<double>;
using Triangles = std::vector<Kernel::Triangle_3>;
using Primitive = CGAL::AABB_triangle_primitive<Kernel, Triangles::const_iterator>;
using Tree = CGAL::AABB_tree<CGAL::AABB_traits<Kernel, Primitive>>;

Kernel::Point_3 point(const Vec3& p) { return {p.x(), p.y(), p.z()}; }

// The faces' centroids as nanoflann's dataset.
struct Centroids {
  std::vector<Vec3> points;
  size_t kdtree_get_point_count() const { return points.size(); }
  double kdtree_get_pt(size_t i, size_t dim) const { return points[i][static_cast<int>(dim)]; }
  template <class Box>
  bool kdtree_get_bbox(Box&) const { return false; }
};
using CentroidTree =
    nanoflann::KDTreeSingleIndexAdaptor<nanoflann::L2_Simple_Adaptor<double, Centroids>, Centroids, 3, std::uint32_t>;
}  // namespace

// The AABB tree alone (CGAL's build splits at the median: depth O(log |F|)), without
// CGAL's distance accelerator: that kd-tree is built on one corner of each triangle, and
// on a fan whose triangles all start at the centre vertex those are one point repeated,
// which made its build recurse once per triangle (and overflow the stack at 60,000). The
// first guess of each query comes from a kd-tree over the centroids instead (distinct
// points; nanoflann splits at the median as well).
struct PointLocator::Impl {
  Triangles triangles;
  Tree tree;
  Centroids centroids;
  std::unique_ptr<CentroidTree> hints;
};

PointLocator::PointLocator(const Mesh& mesh) : mesh_(mesh), impl_(std::make_unique<Impl>()) {
  TVF_CHECK(mesh.num_faces() > 0, "a point locator needs a mesh with faces");
  auto& t = impl_->triangles;
  t.reserve(static_cast<size_t>(mesh.num_faces()));
  for (int f = 0; f < mesh.num_faces(); ++f) {
    const Face& face = mesh.face(f);
    t.emplace_back(point(mesh.position(face[0])), point(mesh.position(face[1])), point(mesh.position(face[2])));
  }
  impl_->tree.insert(t.begin(), t.end());
  // Build both trees now: later queries then only read them (thread-safe).
  impl_->tree.do_not_accelerate_distance_queries();
  impl_->tree.build();
  auto& c = impl_->centroids.points;
  c.reserve(t.size());
  for (int f = 0; f < mesh.num_faces(); ++f) {
    const Face& face = mesh.face(f);
    c.push_back((mesh.position(face[0]) + mesh.position(face[1]) + mesh.position(face[2])) / 3.0);
  }
  impl_->hints = std::make_unique<CentroidTree>(3, impl_->centroids, nanoflann::KDTreeSingleIndexAdaptorParams(8));
  impl_->hints->buildIndex();
}

PointLocator::~PointLocator() = default;

SurfacePoint PointLocator::closest(const Vec3& x) const {
  std::uint32_t nearest = 0;
  double distance2 = 0;
  nanoflann::KNNResultSet<double, std::uint32_t> result(1);
  result.init(&nearest, &distance2);
  const double query[3] = {x.x(), x.y(), x.z()};
  impl_->hints->findNeighbors(result, query, nanoflann::SearchParams());
  const auto hint_face = impl_->triangles.begin() + nearest;
  const Tree::Point_and_primitive_id hint(point(impl_->centroids.points[nearest]), hint_face);
  const auto [p, id] = impl_->tree.closest_point_and_primitive(point(x), hint);
  SurfacePoint out;
  out.face = static_cast<int>(id - impl_->triangles.begin());
  // Barycentric coordinates of the closest point (it lies in the triangle).
  const Face& f = mesh_.face(out.face);
  const Vec3 a = mesh_.position(f[0]), b = mesh_.position(f[1]), c = mesh_.position(f[2]);
  const Vec3 q(p.x(), p.y(), p.z());
  const Vec3 v0 = b - a, v1 = c - a, v2 = q - a;
  const double d00 = v0.dot(v0), d01 = v0.dot(v1), d11 = v1.dot(v1), d20 = v2.dot(v0), d21 = v2.dot(v1);
  const double den = d00 * d11 - d01 * d01;
  double v = den > 0 ? (d11 * d20 - d01 * d21) / den : 0.0;
  double w = den > 0 ? (d00 * d21 - d01 * d20) / den : 0.0;
  v = std::clamp(v, 0.0, 1.0);
  w = std::clamp(w, 0.0, 1.0 - v);
  out.bary = Vec3(1.0 - v - w, v, w);
  return out;
}

}  // namespace tvf
