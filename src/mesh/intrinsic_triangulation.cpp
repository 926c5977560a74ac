#include "tvf/mesh/intrinsic_triangulation.h"

#include "tvf/core/error.h"

#include <algorithm>
#include <cmath>
#include <limits>

namespace tvf {

namespace {

// Four times the area of a triangle of side lengths a, b, c (Kahan's stable Heron: sides
// sorted a ≥ b ≥ c, brackets as written). 0 for lengths that violate the triangle inequality.
double four_area(double a, double b, double c) {
  if (a < b) std::swap(a, b);
  if (b < c) std::swap(b, c);
  if (a < b) std::swap(a, b);
  const double p = (a + (b + c)) * (c - (a - b)) * (c + (a - b)) * (a + (b - c));
  return p > 0 ? std::sqrt(p) : 0.0;
}

// Cotangent of the 3D corner angle opposite halfedge h: the formula connection_laplacian
// and the log map used before intrinsic triangulations, kept so that an unchanged
// triangulation gives bit-identical operators.
double cot_opposite_3d(const Mesh& mesh, int h) {
  const int o = Mesh::prev(h);
  const Vec3& a = mesh.position(mesh.tail(o));
  const Vec3 u = mesh.position(mesh.head(o)) - a;
  const Vec3 w = mesh.position(mesh.tail(Mesh::prev(o))) - a;
  return u.dot(w) / u.cross(w).norm();
}

}  // namespace

IntrinsicTriangulation::IntrinsicTriangulation(const TangentBundle& bundle, IntrinsicTriangulationOptions options)
    : bundle_(&bundle) {
  const Mesh& mesh = bundle.mesh();
  nv_ = mesh.num_vertices();
  faces_ = mesh.faces();
  const auto nh = static_cast<size_t>(mesh.num_halfedges());
  twin_.resize(nh);
  input_.resize(nh);
  length_.resize(nh);
  for (size_t h = 0; h < nh; ++h) {
    const int hi = static_cast<int>(h);
    twin_[h] = mesh.twin(hi);
    input_[h] = hi;
    length_[h] = mesh.edge_length(hi);
  }

  // 1. Mollification: the least δ with l_i + l_j − l_k ≥ ε in every triangle.
  const double eps = options.mollify_factor * mesh.mean_edge_length();
  for (int f = 0; f < num_faces(); ++f) {
    for (int c = 0; c < 3; ++c) {
      const int h = 3 * f + c;
      const double slack = length(next(h)) + length(prev(h)) - length(h);
      delta_ = std::max(delta_, eps - slack);
    }
  }
  cot_.resize(nh);
  if (delta_ > 0) {
    for (double& l : length_) l += delta_;
    for (int f = 0; f < num_faces(); ++f) set_face_cotangents(f);
  } else {
    delta_ = 0;
    for (size_t h = 0; h < nh; ++h) cot_[h] = cot_opposite_3d(mesh, static_cast<int>(h));
  }
  min_input_weight_ = std::numeric_limits<double>::infinity();
  for (int h = 0; h < num_halfedges(); ++h) min_input_weight_ = std::min(min_input_weight_, raw_weight(h));

  // Signposts: every halfedge's angle at its tail, counter-clockwise from the first
  // outgoing input halfedge (the same sums TangentBundle makes, from the same angles
  // when nothing was mollified).
  phi_.assign(nh, 0.0);
  angle_sum_.assign(static_cast<size_t>(nv_), 0.0);
  for (int v = 0; v < nv_; ++v) {
    double acc = 0;
    for (int h : mesh.outgoing(v)) {
      phi_[static_cast<size_t>(h)] = acc;
      acc += delta_ > 0 ? corner_angle(h) : mesh.corner_angle(h);
    }
    angle_sum_[static_cast<size_t>(v)] = acc;
  }

  // 2. Flip interior edges until every one is locally Delaunay. Each flip lowers the
  // Dirichlet energy of the piecewise-linear functions, so this ends (Bobenko & Springborn
  // 2007); the cap only guards against rounding cycling between two near-ties.
  std::vector<int> stack;
  std::vector<char> queued(nh, 0);
  auto push = [&](int h) {
    const int t = twin(h);
    if (t < 0 || queued[static_cast<size_t>(h)]) return;
    queued[static_cast<size_t>(h)] = queued[static_cast<size_t>(t)] = 1;
    stack.push_back(h);
  };
  for (int h = 0; h < num_halfedges(); ++h)
    if (twin(h) > h) push(h);
  const long long max_flips = 100LL * static_cast<long long>(nh) + 1000;
  while (!stack.empty()) {
    const int h = stack.back();
    stack.pop_back();
    queued[static_cast<size_t>(h)] = 0;
    if (const int t = twin(h); t >= 0) queued[static_cast<size_t>(t)] = 0;
    if (twin(h) < 0 || raw_weight(h) >= -options.delaunay_tolerance) continue;
    const int f0 = face_of(h), f1 = face_of(twin(h));
    if (!flip(h)) continue;
    if (++flips_ > max_flips)
      throw Error(fmt::format("{}: the intrinsic Delaunay flips did not end after {} flips (a mesh with "
                              "degenerate triangles that mollification could not repair)",
                              mesh.source(), flips_ - 1));
    for (int f : {f0, f1})
      for (int c = 0; c < 3; ++c) queued[static_cast<size_t>(3 * f + c)] = 0;
    for (int f : {f0, f1})
      for (int c = 0; c < 2; ++c) push(3 * f + c);  // the quad's four outer edges
  }

  // Weights still negative beyond the tolerance (boundary edges with an obtuse opposite
  // angle; an interior edge only if it could not be flipped). Those within it (cocircular
  // neighbours: −1e-17) are set to 0 as well, but not counted.
  for (int h = 0; h < num_halfedges(); ++h)
    if ((twin(h) < 0 || twin(h) > h) && raw_weight(h) < -options.delaunay_tolerance) ++clamped_;

  // Transports: the bundle's for input edges (exactly 1 on planar domains), from the
  // two ends' directions for flipped ones; twins get the conjugate.
  transport_.assign(nh, cplx(1, 0));
  for (int h = 0; h < num_halfedges(); ++h) {
    const int t = twin(h);
    if (t >= 0 && t < h) {
      transport_[static_cast<size_t>(h)] = std::conj(transport_[static_cast<size_t>(t)]);
      continue;
    }
    if (bundle.is_flat()) continue;
    if (input_[static_cast<size_t>(h)] >= 0) {
      transport_[static_cast<size_t>(h)] = bundle.transport(input_[static_cast<size_t>(h)]);
      continue;
    }
    TVF_CHECK(t >= 0, "flipped halfedge {} has no twin", h);
    transport_[static_cast<size_t>(h)] = normalized(-direction(t) * std::conj(direction(h)));
  }
}

double IntrinsicTriangulation::corner_angle(int h) const {
  const double a = length(next(h)), b = length(h), c = length(prev(h));
  return std::atan2(four_area(a, b, c), b * b + c * c - a * a);
}

double IntrinsicTriangulation::face_area(int f) const {
  return 0.25 * four_area(length(3 * f), length(3 * f + 1), length(3 * f + 2));
}

void IntrinsicTriangulation::set_face_cotangents(int f) {
  for (int c = 0; c < 3; ++c) {
    const int h = 3 * f + c;
    const double a = length(h), b = length(next(h)), d = length(prev(h));
    cot_[static_cast<size_t>(h)] = (b * b + d * d - a * a) / four_area(a, b, d);
  }
}

double IntrinsicTriangulation::raw_weight(int h) const {
  double w = 0.5 * cot_[static_cast<size_t>(h)];
  if (const int t = twin(h); t >= 0) w += 0.5 * cot_[static_cast<size_t>(t)];
  return w;
}

double IntrinsicTriangulation::edge_weight(int h) const { return std::max(raw_weight(h), 0.0); }

std::array<Vec3, 3> IntrinsicTriangulation::layout(int f) const {
  const int h0 = 3 * f;
  const double a0 = corner_angle(h0), l2 = length(prev(h0));
  return {Vec3::Zero(), Vec3(length(h0), 0, 0), Vec3(l2 * std::cos(a0), l2 * std::sin(a0), 0)};
}

cplx IntrinsicTriangulation::direction(int h) const {
  if (const int in = input_[static_cast<size_t>(h)]; in >= 0) return bundle_->halfedge_direction(in);
  const Mesh& mesh = bundle_->mesh();
  const int v = tail(h);
  if (bundle_->is_flat()) {
    // In the plane an intrinsic edge is the straight segment between its ends.
    const Vec3 d = mesh.position(head(h)) - mesh.position(v);
    return unit_direction(d.x(), d.y());
  }
  const double s = mesh.is_boundary_vertex(v) ? 1.0 : 2 * kPi / angle_sum_[static_cast<size_t>(v)];
  return bundle_->halfedge_direction(mesh.outgoing(v)[0]) * std::polar(1.0, s * phi_[static_cast<size_t>(h)]);
}

bool IntrinsicTriangulation::flip(int h) {
  // Before: f0 = (a, b, c) with h = a→b, f1 = (b, a, d) with t = b→a.
  // After:  f0 = (c, a, d), f1 = (d, b, c); the new edge joins c and d.
  const int t = twin(h);
  const int f0 = face_of(h), f1 = face_of(t);
  if (f0 == f1) return false;
  const int h1 = next(h), h2 = prev(h), t1 = next(t), t2 = prev(t);
  const int outer[4] = {twin(h1), twin(h2), twin(t1), twin(t2)};
  for (int x : outer)
    if (x >= 0 && (face_of(x) == f0 || face_of(x) == f1)) return false;  // a vertex of degree 1
  const double alpha_a = corner_angle(h), beta_a = corner_angle(t1);
  const double alpha_b = corner_angle(h1), beta_b = corner_angle(t);
  if (!(alpha_a + beta_a < kPi) || !(alpha_b + beta_b < kPi)) return false;  // not convex

  const int a = tail(h), b = head(h), c = tail(h2), d = tail(t2);
  // The quad unfolded: a at the origin, b on the x axis, c above, d below.
  const double lac = length(h2), lad = length(t1);
  const double lcd = std::hypot(lac * std::cos(alpha_a) - lad * std::cos(beta_a),
                                lac * std::sin(alpha_a) + lad * std::sin(beta_a));
  struct Kept {
    double length, phi;
    int input, twin;
  };
  auto keep = [&](int g) {
    return Kept{length_[static_cast<size_t>(g)], phi_[static_cast<size_t>(g)], input_[static_cast<size_t>(g)], twin(g)};
  };
  const Kept k_ca = keep(h2), k_ad = keep(t1), k_db = keep(t2), k_bc = keep(h1);
  faces_[static_cast<size_t>(f0)] = {c, a, d};
  faces_[static_cast<size_t>(f1)] = {d, b, c};
  const int A0 = 3 * f0, A1 = A0 + 1, A2 = A0 + 2;  // c→a, a→d, d→c
  const int B0 = 3 * f1, B1 = B0 + 1, B2 = B0 + 2;  // d→b, b→c, c→d
  auto put = [&](int g, const Kept& k) {
    length_[static_cast<size_t>(g)] = k.length;
    phi_[static_cast<size_t>(g)] = k.phi;
    input_[static_cast<size_t>(g)] = k.input;
    twin_[static_cast<size_t>(g)] = k.twin;
    if (k.twin >= 0) twin_[static_cast<size_t>(k.twin)] = g;
  };
  put(A0, k_ca);
  put(A1, k_ad);
  put(B0, k_db);
  put(B1, k_bc);
  for (int g : {A2, B2}) {
    length_[static_cast<size_t>(g)] = lcd;
    input_[static_cast<size_t>(g)] = -1;
  }
  twin_[static_cast<size_t>(A2)] = B2;
  twin_[static_cast<size_t>(B2)] = A2;
  set_face_cotangents(f0);
  set_face_cotangents(f1);

  // Signposts of the new edge: counter-clockwise at c, c→d follows c→a by the angle of
  // f0 at c; at d, d→c follows d→b by the angle of f1 at d.
  const Mesh& mesh = bundle_->mesh();
  auto wrap = [&](int v, double angle) {
    if (mesh.is_boundary_vertex(v)) return angle;
    const double sum = angle_sum_[static_cast<size_t>(v)];
    angle = std::fmod(angle, sum);
    return angle < 0 ? angle + sum : angle;
  };
  phi_[static_cast<size_t>(B2)] = wrap(c, phi_[static_cast<size_t>(A0)] + corner_angle(A0));
  phi_[static_cast<size_t>(A2)] = wrap(d, phi_[static_cast<size_t>(B0)] + corner_angle(B0));
  return true;
}

}  // namespace tvf
