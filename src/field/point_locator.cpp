#include "tvf/field/point_locator.h"

#include "tvf/core/error.h"

#include <CGAL/AABB_traits.h>
#include <CGAL/AABB_tree.h>
#include <CGAL/AABB_triangle_primitive.h>
#include <CGAL/Simple_cartesian.h>

#include <algorithm>
#include <vector>

namespace tvf {

namespace {
using Kernel = CGAL::Simple_cartesian<double>;
using Triangles = std::vector<Kernel::Triangle_3>;
using Primitive = CGAL::AABB_triangle_primitive<Kernel, Triangles::const_iterator>;
using Tree = CGAL::AABB_tree<CGAL::AABB_traits<Kernel, Primitive>>;

Kernel::Point_3 point(const Vec3& p) { return {p.x(), p.y(), p.z()}; }
}  // namespace

struct PointLocator::Impl {
  Triangles triangles;
  Tree tree;
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
  impl_->tree.build();
  impl_->tree.accelerate_distance_queries();
}

PointLocator::~PointLocator() = default;

SurfacePoint PointLocator::closest(const Vec3& x) const {
  const auto [p, id] = impl_->tree.closest_point_and_primitive(point(x));
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
