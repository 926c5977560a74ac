#include "tvf/mesh/tangent_bundle.h"

#include "tvf/core/error.h"

#include <cmath>

namespace tvf {

void tangent_basis(const Vec3& n, Vec3& e1, Vec3& e2) {
  const Vec3 axis = std::abs(n.x()) < 0.9 ? Vec3::UnitX() : Vec3::UnitY();
  e1 = (axis - axis.dot(n) * n).normalized();
  e2 = n.cross(e1);
}

namespace {
// Direction of world vector w in the basis (e1, e2), as a unit complex number.
cplx direction_in(const Vec3& w, const Vec3& e1, const Vec3& e2) {
  return unit_direction(w.dot(e1), w.dot(e2));
}
}  // namespace

double TangentBundle::angle_defect(int v) const {
  return (mesh_->is_boundary_vertex(v) ? kPi : 2 * kPi) - angle_sum(v);
}

TangentBundle::TangentBundle(const Mesh& mesh) : mesh_(&mesh) {
  const auto nv = static_cast<size_t>(mesh.num_vertices());
  const auto nf = static_cast<size_t>(mesh.num_faces());
  const auto nh = static_cast<size_t>(mesh.num_halfedges());

  // Face frames.
  fn_.resize(nf);
  fe1_.resize(nf);
  fe2_.resize(nf);
  for (size_t f = 0; f < nf; ++f) {
    fn_[f] = mesh.face_normal(static_cast<int>(f));
    tangent_basis(fn_[f], fe1_[f], fe2_[f]);
  }

  // Vertex normals: area-weighted (the unnormalised cross products summed).
  vn_.assign(nv, Vec3::Zero());
  for (size_t f = 0; f < nf; ++f) {
    const Face& t = mesh.face(static_cast<int>(f));
    const Vec3 c = (mesh.position(t[1]) - mesh.position(t[0]))
                       .cross(mesh.position(t[2]) - mesh.position(t[0]));
    for (int k : t) vn_[static_cast<size_t>(k)] += c;
  }
  ve1_.resize(nv);
  ve2_.resize(nv);
  for (size_t v = 0; v < nv; ++v) {
    vn_[v].normalize();
    tangent_basis(vn_[v], ve1_[v], ve2_[v]);
  }

  // Halfedge directions in vertex tangent spaces.
  angle_sum_.assign(nv, 0.0);
  dir_.assign(nh, cplx(1, 0));
  std::vector<double> scale(nv, 1.0);
  std::vector<char> flat_star(nv, 0);
  for (size_t v = 0; v < nv; ++v) {
    const int vi = static_cast<int>(v);
    const auto out = mesh.outgoing(vi);
    double sum = 0;
    bool star_flat = true;
    for (int h : out) {
      sum += mesh.corner_angle(h);
      if (mesh.face_normal(Mesh::face_of(h)) != vn_[v]) star_flat = false;
    }
    angle_sum_[v] = sum;
    const bool boundary = mesh.is_boundary_vertex(vi);
    if (star_flat) {
      // All faces of the star lie in the tangent plane: the plane's own directions are
      // the intrinsic ones (their angle sum is 2π up to rounding), no rescaling.
      flat_star[v] = 1;
      for (int h : out) {
        dir_[static_cast<size_t>(h)] =
            direction_in(mesh.position(mesh.head(h)) - mesh.position(vi), ve1_[v], ve2_[v]);
      }
      continue;
    }
    scale[v] = boundary ? 1.0 : 2 * kPi / sum;
    const int h0 = out[0];
    const double a0 = std::arg(
        direction_in(mesh.position(mesh.head(h0)) - mesh.position(vi), ve1_[v], ve2_[v]));
    double acc = 0;
    for (int h : out) {
      dir_[static_cast<size_t>(h)] = std::polar(1.0, a0 + scale[v] * acc);
      acc += mesh.corner_angle(h);
    }
  }

  // Transports r_ij = −u_ji / u_ij. A boundary halfedge h = i→j has no twin: the edge
  // j→i is then the last edge of j's fan, one corner angle counter-clockwise of next(h).
  auto direction_at_head = [&](int h) -> cplx {
    const int t = mesh.twin(h);
    if (t >= 0) return dir_[static_cast<size_t>(t)];
    const int j = mesh.head(h);
    const auto vj = static_cast<size_t>(j);
    if (flat_star[vj])
      return direction_in(mesh.position(mesh.tail(h)) - mesh.position(j), ve1_[vj], ve2_[vj]);
    const int hj = Mesh::next(h);
    return dir_[static_cast<size_t>(hj)] * std::polar(1.0, scale[vj] * mesh.corner_angle(hj));
  };
  transport_.assign(nh, cplx(1, 0));
  // One value per edge, its conjugate for the twin: transport(twin(h)) is exactly
  // conj(transport(h)), so anything summed over both directions cancels exactly.
  for (size_t h = 0; h < nh; ++h) {
    const int t = mesh.twin(static_cast<int>(h));
    if (t >= 0 && static_cast<size_t>(t) < h) {
      transport_[h] = std::conj(transport_[static_cast<size_t>(t)]);
      continue;
    }
    const cplx uij = dir_[h];
    const cplx uji = direction_at_head(static_cast<int>(h));
    transport_[h] = normalized(-uji * std::conj(uij));
  }

  // Corner → face transports through the corner's bisector, and face → face by unfolding.
  corner_to_face_.assign(nh, cplx(1, 0));
  face_to_face_.assign(nh, cplx(0, 0));
  for (size_t h = 0; h < nh; ++h) {
    const int hi = static_cast<int>(h);
    const size_t f = static_cast<size_t>(Mesh::face_of(hi));
    const int v = mesh.tail(hi);
    const Vec3 edge = mesh.position(mesh.head(hi)) - mesh.position(v);
    const cplx in_face = direction_in(edge, fe1_[f], fe2_[f]);
    cplx r = in_face * std::conj(dir_[h]);
    const double s = scale[static_cast<size_t>(v)];
    if (s != 1.0) r *= std::polar(1.0, 0.5 * (1.0 - s) * mesh.corner_angle(hi));
    corner_to_face_[h] = normalized(r);
    const int t = mesh.twin(hi);
    if (t >= 0) {
      const size_t g = static_cast<size_t>(Mesh::face_of(t));
      // The shared edge lies in both planes: unfolding keeps its direction.
      const cplx in_other = direction_in(edge, fe1_[g], fe2_[g]);
      face_to_face_[h] = normalized(in_other * std::conj(in_face));
    }
  }

  flat_ = mesh.is_planar_xy();
  if (flat_) {
    for (size_t h = 0; h < nh; ++h)
      TVF_CHECK(transport_[h] == cplx(1, 0), "planar transport {} is not 1", h);
  }
}

}  // namespace tvf
