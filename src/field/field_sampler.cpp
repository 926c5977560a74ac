#include "tvf/field/field_sampler.h"

#include "tvf/core/error.h"

#include <fmt/format.h>

#include <algorithm>
#include <cmath>
#include <limits>

namespace tvf {

cplx FieldSampler::at_vertex(int v, double t) const {
  int j = 0;
  double w = 0.0;
  field_.time().locate(t, j, w);
  if (w == 0.0) return field_.at(j, v);
  if (w == 1.0) return field_.at(j + 1, v);
  return (1.0 - w) * field_.at(j, v) + w * field_.at(j + 1, v);
}

cplx FieldSampler::in_face(const SurfacePoint& p, double t) const {
  const Mesh& mesh = bundle_.mesh();
  TVF_DCHECK(p.face >= 0 && p.face < mesh.num_faces(), "face {} of {}", p.face, mesh.num_faces());
  int j = 0;
  double w = 0.0;
  field_.time().locate(t, j, w);
  const Face& face = mesh.face(p.face);
  cplx sum(0.0, 0.0);
  for (int c = 0; c < 3; ++c) {
    const int v = face[static_cast<size_t>(c)];
    cplx z = field_.at(j, v);
    if (w != 0.0) z = w == 1.0 ? field_.at(j + 1, v) : (1.0 - w) * z + w * field_.at(j + 1, v);
    sum += p.bary[c] * (bundle_.corner_to_face(3 * p.face + c) * z);
  }
  return sum;
}

Vec3 FieldSampler::world(const SurfacePoint& p, double t) const {
  return bundle_.face_to_world(p.face, in_face(p, t));
}

namespace {

// Closest point of triangle (a, b, c) to p, with its barycentric coordinates (Voronoi
// regions of the vertices, then the edges, then the interior; Ericson, Real-Time
// Collision Detection §5.1.5).
Vec3 closest_in_triangle(const Vec3& p, const Vec3& a, const Vec3& b, const Vec3& c) {
  const Vec3 ab = b - a;
  const Vec3 ac = c - a;
  const Vec3 ap = p - a;
  const double d1 = ab.dot(ap);
  const double d2 = ac.dot(ap);
  if (d1 <= 0 && d2 <= 0) return {1, 0, 0};

  const Vec3 bp = p - b;
  const double d3 = ab.dot(bp);
  const double d4 = ac.dot(bp);
  if (d3 >= 0 && d4 <= d3) return {0, 1, 0};

  const double vc = d1 * d4 - d3 * d2;
  if (vc <= 0 && d1 >= 0 && d3 <= 0) {
    const double v = d1 / (d1 - d3);
    return {1 - v, v, 0};
  }

  const Vec3 cp = p - c;
  const double d5 = ab.dot(cp);
  const double d6 = ac.dot(cp);
  if (d6 >= 0 && d5 <= d6) return {0, 0, 1};

  const double vb = d5 * d2 - d1 * d6;
  if (vb <= 0 && d2 >= 0 && d6 <= 0) {
    const double w = d2 / (d2 - d6);
    return {1 - w, 0, w};
  }

  const double va = d3 * d6 - d5 * d4;
  if (va <= 0 && (d4 - d3) >= 0 && (d5 - d6) >= 0) {
    const double w = (d4 - d3) / ((d4 - d3) + (d5 - d6));
    return {0, 1 - w, w};
  }

  const double denom = va + vb + vc;
  if (!(denom > 0)) return {1, 0, 0};  // degenerate triangle (meshes reject these)
  const double v = vb / denom;
  const double w = vc / denom;
  return {1 - v - w, v, w};
}

}  // namespace

SurfacePoint closest_point(const Mesh& mesh, const Vec3& x) {
  SurfacePoint best;
  double best_d2 = std::numeric_limits<double>::infinity();
  double best_d = std::numeric_limits<double>::infinity();
  for (int f = 0; f < mesh.num_faces(); ++f) {
    const Face& t = mesh.face(f);
    const Vec3& a = mesh.position(t[0]);
    const Vec3& b = mesh.position(t[1]);
    const Vec3& c = mesh.position(t[2]);
    // Cull with the sphere around the centroid through the farthest corner: no point of
    // the face is closer to x than |x − centre| − radius.
    const Vec3 centre = (a + b + c) / 3.0;
    const double r2 = std::max({(a - centre).squaredNorm(), (b - centre).squaredNorm(),
                                (c - centre).squaredNorm()});
    const double dc = (x - centre).norm();
    if (dc - std::sqrt(r2) > best_d) continue;
    const Vec3 bary = closest_in_triangle(x, a, b, c);
    const double d2 = (x - (bary[0] * a + bary[1] * b + bary[2] * c)).squaredNorm();
    if (d2 < best_d2) {
      best_d2 = d2;
      best_d = std::sqrt(d2);
      best.face = f;
      best.bary = bary;
    }
  }
  return best;
}

Vec3 surface_position(const Mesh& mesh, const SurfacePoint& p) {
  const Face& t = mesh.face(p.face);
  return p.bary[0] * mesh.position(t[0]) + p.bary[1] * mesh.position(t[1]) +
         p.bary[2] * mesh.position(t[2]);
}

std::string planar_point_problem(const Mesh& mesh, const Vec3& x, const Vec3& on, const std::string& what) {
  if (!mesh.is_planar_xy()) return {};
  if (x.z() != 0)
    return fmt::format("{} ({}, {}, {}) is off the planar domain, which lies at z = 0: give z = 0 or leave it out", what,
                       x.x(), x.y(), x.z());
  if ((on - x).head<2>().norm() > 1e-9 * std::max(1.0, mesh.diameter()))
    return fmt::format("{} ({}, {}) is outside the domain", what, x.x(), x.y());
  return {};
}

}  // namespace tvf
