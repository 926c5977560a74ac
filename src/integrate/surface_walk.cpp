#include "tvf/integrate/surface_walk.h"

#include "tvf/core/error.h"

#include <algorithm>
#include <array>
#include <cmath>

namespace tvf {

namespace {

// Corner positions of face f in its own frame, corner 0 at the origin.
std::array<Vec2, 3> local_corners(const TangentBundle& bundle, int f) {
  const Mesh& mesh = bundle.mesh();
  const Face& t = mesh.face(f);
  const Vec3& o = mesh.position(t[0]);
  const Vec3& e1 = bundle.face_e1(f);
  const Vec3& e2 = bundle.face_e2(f);
  std::array<Vec2, 3> p;
  for (size_t c = 0; c < 3; ++c) {
    const Vec3 d = mesh.position(t[c]) - o;
    p[c] = Vec2(d.dot(e1), d.dot(e2));
  }
  return p;
}

Vec3 barycentric(const std::array<Vec2, 3>& p, const Vec2& x) {
  const Vec2 a = p[1] - p[0], b = p[2] - p[0], d = x - p[0];
  const double det = a.x() * b.y() - a.y() * b.x();
  const double l1 = (d.x() * b.y() - d.y() * b.x()) / det;
  const double l2 = (a.x() * d.y() - a.y() * d.x()) / det;
  return {1.0 - l1 - l2, l1, l2};
}

Vec3 clamp_bary(Vec3 b) {
  b = b.cwiseMax(0.0);
  const double s = b.sum();
  return s > 0 ? Vec3(b / s) : Vec3(1.0 / 3, 1.0 / 3, 1.0 / 3);
}

}  // namespace

SurfaceWalk walk_surface(const TangentBundle& bundle, const SurfacePoint& start, cplx displacement,
                         const std::function<bool(int)>& stop_in) {
  const Mesh& mesh = bundle.mesh();
  SurfaceWalk w;
  w.end = start;
  cplx rem = displacement;
  // Whether |displacement| > 0, without the hypot call of std::abs (the walk is an RK4
  // stage's: four a streamline step; issue 15): zero unless a part is NaN-free and non-zero
  // or infinite, exactly as std::abs(displacement) > 0.
  const double re = std::abs(displacement.real()), im = std::abs(displacement.imag());
  const bool moves = std::isinf(re) || std::isinf(im) || (!std::isnan(re) && !std::isnan(im) && (re > 0 || im > 0));
  double left = 1.0;  // fraction of the displacement still to walk
  int entered = -1;   // the half-edge of the current face the walk came in through
  // Each pass crosses one edge; a walk of a few edge lengths crosses few. The cap only
  // guards against rounding ping-pong around a vertex.
  for (int pass = 0; pass < 10000; ++pass) {
    const int f = w.end.face;
    const auto p = local_corners(bundle, f);
    const Vec3& b = w.end.bary;
    const Vec2 x = b[0] * p[0] + b[1] * p[1] + b[2] * p[2];
    const Vec3 bt = barycentric(p, x + to_vec2(rem));
    if (bt.minCoeff() >= 0.0) {
      w.end.bary = clamp_bary(bt);
      return w;
    }
    // The first edge the segment leaves through: corner c whose coordinate reaches 0 first.
    int c = -1;
    double s = 2.0;
    for (int k = 0; k < 3; ++k) {
      if (bt[k] >= 0.0) continue;
      const double sk = std::max(b[k], 0.0) / (std::max(b[k], 0.0) - bt[k]);
      if (sk < s) {
        s = sk;
        c = k;
      }
    }
    TVF_CHECK(c >= 0, "walk in face {}: no exit edge", f);
    Vec3 e = b + s * (bt - b);
    e[c] = 0.0;
    e = clamp_bary(e);
    const int h = 3 * f + (c + 1) % 3;  // the edge opposite corner c
    if (h == entered && !(s > 0.0)) {
      // Out again, without a move in this face, through the edge the walk came in by: what
      // is left runs along that edge, or crosses it by less than rounding, and each face's
      // rounding would send it into the other for ever (CGAL's cow: a curve point on an
      // edge, 1e-18 left). Move along the edge in this face, up to its ends, and stop.
      const int a = (c + 1) % 3, z = (c + 2) % 3;
      const Vec2 edge = p[static_cast<size_t>(z)] - p[static_cast<size_t>(a)];
      const double along = edge.dot(to_vec2(rem)) / edge.squaredNorm();
      Vec3 on_edge = Vec3::Zero();
      on_edge[z] = std::clamp(std::max(b[z], 0.0) + along, 0.0, 1.0);
      on_edge[a] = 1.0 - on_edge[z];
      w.end.bary = on_edge;
      return w;
    }
    const int tw = mesh.twin(h);
    left *= 1.0 - s;
    if (tw < 0) {
      w.end.bary = e;
      w.hit_boundary = true;
      w.travelled = moves ? 1.0 - left : 1.0;
      return w;
    }
    const int g = Mesh::face_of(tw);
    const int k = tw % 3;  // tail(tw) = head(h) = corner (c + 2) of f
    SurfacePoint next;
    next.face = g;
    next.bary = Vec3::Zero();
    next.bary[k] = e[(c + 2) % 3];
    next.bary[(k + 1) % 3] = e[(c + 1) % 3];
    const cplx r = bundle.face_to_face(h);
    rem = r * ((1.0 - s) * rem);
    w.transport = r * w.transport;
    w.end = next;
    entered = tw;
    if (stop_in && stop_in(g)) {
      w.stopped = true;
      w.travelled = moves ? 1.0 - left : 1.0;
      return w;
    }
  }
  TVF_CHECK(false, "walk from face {} did not end", start.face);
  return w;
}

cplx interpolate_in_face(const TangentBundle& bundle, std::span<const cplx> values, const SurfacePoint& p) {
  const Face& t = bundle.mesh().face(p.face);
  cplx z(0.0, 0.0);
  for (int c = 0; c < 3; ++c)
    z += p.bary[c] * (bundle.corner_to_face(3 * p.face + c) * values[static_cast<size_t>(t[static_cast<size_t>(c)])]);
  return z;
}

}  // namespace tvf
