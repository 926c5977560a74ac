#include "tvf/analysis/singularities.h"

#include "tvf/core/error.h"

#include <Eigen/LU>

#include <algorithm>
#include <array>
#include <cmath>
#include <limits>

namespace tvf {

namespace {

constexpr double kTwoPi = 2 * kPi;

double cross(cplx a, cplx b) { return a.real() * b.imag() - a.imag() * b.real(); }
cplx times_i(cplx z) { return {-z.imag(), z.real()}; }  // exact
cplx times_minus_i(cplx z) { return {z.imag(), -z.real()}; }  // exact

// a_ij = arg(z_j · conj(r·z_i)) ∈ [−π, π] for i < j, r = transport(i→j), as the limit of
// simulation of simplicity: vertex v carries the perturbation δ_{2v} + i·δ_{2v+1} with
// δ_k = ε^(2^k). The perturbed q = Z_j · conj(r·Z_i) is a polynomial in the δ whose
// monomials, from the largest to the smallest (i < j, so 2i + 1 < 2j), are
//   1, δ_2i, δ_2i+1, δ_2j, δ_2i·δ_2j, δ_2i+1·δ_2j, δ_2j+1, δ_2i·δ_2j+1, δ_2i+1·δ_2j+1
// (exponents a < 2a < c < c+a < c+2a < 2c < 2c+a < 2c+2a with a = 2^2i, c = 2^2j ≥ 4a).
// Its argument tends to the argument of the first non-zero coefficient; when that one is a
// negative real number the limit is ±π, signed by the first later coefficient with a
// non-zero imaginary part. The coefficient of δ_2i·δ_2j is conj(r) ≠ 0, so a leading one
// always exists; and every coefficient c that can lead is followed by −i·c (or by c and
// −i·c) a few places later, one of which has a non-zero imaginary part, so the sign is
// always decided. Both faces of the edge evaluate this same function on the same
// arguments, so a zero on the edge or at a vertex goes to exactly one side.
double edge_angle(cplx zi, cplx zj, cplx r) {
  const cplx p = std::conj(r * zi);  // conj(r·z_i)
  const cplx s = zj * std::conj(r);  // z_j·conj(r)
  const cplx cr = std::conj(r);
  const std::array<cplx, 9> c = {
      zj * p,             // 1
      s,                  // δ_2i
      times_minus_i(s),   // δ_2i+1          (z_j·conj(i·r))
      p,                  // δ_2j
      cr,                 // δ_2i·δ_2j
      times_minus_i(cr),  // δ_2i+1·δ_2j     (conj(i·r))
      times_i(p),         // δ_2j+1          (i·conj(r·z_i))
      times_i(cr),        // δ_2i·δ_2j+1     (i·conj(r))
      cr,                 // δ_2i+1·δ_2j+1   (i·conj(i·r))
  };
  size_t k = 0;
  while (k < c.size() && c[k] == cplx(0, 0)) ++k;
  TVF_CHECK(k < c.size(), "edge transport {}+{}i is zero", r.real(), r.imag());
  if (c[k].imag() != 0 || c[k].real() > 0) return std::atan2(c[k].imag(), c[k].real());
  for (size_t m = k + 1; m < c.size(); ++m) {
    if (c[m].imag() != 0) return c[m].imag() > 0 ? kPi : -kPi;
  }
  // Unreachable: c[k] real negative means c[k+1] or c[k+2] (or, for k = 3, c[4] or c[5])
  // has a non-zero imaginary part.
  TVF_CHECK(false, "symbolic perturbation left edge angle undecided");
  return 0;
}

// Values scaled by 2^-exponent (exact) so that the largest component is in [0.5, 1), with
// magnitudes below 2^-460 of that flushed to exact zero: the products in edge_angle and
// in the position solve then neither overflow nor underflow, so zero tests mean what they
// say. Throws on non-finite values.
struct Scaled {
  std::vector<cplx> z;
  int exponent = 0;
};
Scaled normalized_values(const TangentBundle& bundle, std::span<const cplx> values) {
  const Mesh& mesh = bundle.mesh();
  TVF_CHECK(static_cast<int>(values.size()) == mesh.num_vertices(),
            "{} values for a mesh of {} vertices", values.size(), mesh.num_vertices());
  double largest = 0;
  for (size_t v = 0; v < values.size(); ++v) {
    const cplx z = values[v];
    if (!std::isfinite(z.real()) || !std::isfinite(z.imag()))
      throw_input_error(mesh.source(), "",
                        fmt::format("singularities: the field value at vertex {} is not finite "
                                    "({} + {}i)",
                                    v, z.real(), z.imag()));
    largest = std::max({largest, std::abs(z.real()), std::abs(z.imag())});
  }
  Scaled out{std::vector<cplx>(values.begin(), values.end()), 0};
  if (largest == 0) return out;
  std::frexp(largest, &out.exponent);
  const double tiny = std::ldexp(1.0, -460);
  for (cplx& z : out.z) {
    z = {std::ldexp(z.real(), -out.exponent), std::ldexp(z.imag(), -out.exponent)};
    if (std::abs(z.real()) < tiny && std::abs(z.imag()) < tiny) z = 0;
  }
  return out;
}

// a_h for every halfedge h: computed once per edge from its lower to its higher vertex and
// negated for the other direction, so the two faces of an edge see exactly opposite
// numbers.
std::vector<double> halfedge_angles(const TangentBundle& bundle, const std::vector<cplx>& z) {
  const Mesh& mesh = bundle.mesh();
  const int nh = mesh.num_halfedges();
  std::vector<double> a(static_cast<size_t>(nh), 0.0);
  for (int h = 0; h < nh; ++h) {
    const int i = mesh.tail(h);
    const int j = mesh.head(h);
    const auto zi = z[static_cast<size_t>(i)];
    const auto zj = z[static_cast<size_t>(j)];
    if (i < j) {
      a[static_cast<size_t>(h)] = edge_angle(zi, zj, bundle.transport(h));
    } else if (mesh.twin(h) < 0) {
      // A boundary edge seen from its higher vertex: only this face uses it.
      a[static_cast<size_t>(h)] = -edge_angle(zj, zi, std::conj(bundle.transport(h)));
    }
  }
  for (int h = 0; h < nh; ++h) {
    const int t = mesh.twin(h);
    if (t >= 0 && mesh.tail(h) > mesh.head(h))
      a[static_cast<size_t>(h)] = -a[static_cast<size_t>(t)];
  }
  return a;
}

std::vector<int> indices_of(const TangentBundle& bundle, const std::vector<cplx>& z) {
  const Mesh& mesh = bundle.mesh();
  const std::vector<double> a = halfedge_angles(bundle, z);
  std::vector<int> index(static_cast<size_t>(mesh.num_faces()), 0);
  for (int f = 0; f < mesh.num_faces(); ++f) {
    const auto h = static_cast<size_t>(3 * f);
    const double turn = a[h] + a[h + 1] + a[h + 2] + face_curvature(bundle, f);
    const double k = std::round(turn / kTwoPi);
    // Σ a + Ω_f is a multiple of 2π by construction (the product of the edge ratios is
    // the inverse holonomy); a large residual means the bundle's transports and its
    // angle sums disagree.
    TVF_CHECK(std::abs(turn - kTwoPi * k) < 1e-6,
              "face {}: edge angles {} {} {} and curvature {} do not close (residual {})", f,
              a[h], a[h + 1], a[h + 2], face_curvature(bundle, f), turn - kTwoPi * k);
    index[static_cast<size_t>(f)] = static_cast<int>(k);
  }
  return index;
}

// Barycentric coordinates of the point of the triangle (w0, w1, w2) ⊂ C closest to 0:
// the zero of the linear interpolant when 0 is inside, else the closest boundary point
// (a zero that the perturbation placed in this face but that lies on its boundary, or a
// face whose transported corners do not enclose 0 on a curved mesh).
Vec3 zero_barycentric(const std::array<cplx, 3>& w) {
  const double A0 = cross(w[1], w[2]);
  const double A1 = cross(w[2], w[0]);
  const double A2 = cross(w[0], w[1]);
  const double det = A0 + A1 + A2;
  if (det != 0 && std::isfinite(det)) {
    const Vec3 b(A0 / det, A1 / det, A2 / det);
    if (b.minCoeff() >= 0) return b;
  }
  // Closest point on the three sides.
  Vec3 best(1, 0, 0);
  double best_d = std::numeric_limits<double>::infinity();
  for (int c = 0; c < 3; ++c) {
    const int d = (c + 1) % 3;
    const cplx e = w[static_cast<size_t>(d)] - w[static_cast<size_t>(c)];
    const double ee = std::norm(e);
    double s = 0;
    if (ee > 0) s = std::clamp(-(std::conj(e) * w[static_cast<size_t>(c)]).real() / ee, 0.0, 1.0);
    const double dist = std::abs(w[static_cast<size_t>(c)] + s * e);
    if (dist < best_d) {
      best_d = dist;
      best = Vec3::Zero();
      best[c] = 1 - s;
      best[d] = s;
    }
  }
  return best;
}

// The type of a face of index `index` with Jacobian J (scaled to order 1 by the caller).
SingularityType type_for(const Mat2& J, int index) {
  if (index < 0) return SingularityType::saddle;
  const SingularityType t = classify_jacobian(J);
  if (t != SingularityType::saddle) return t;
  // Index +1 but det J < 0: the zero sits on the face's boundary or J is nearly singular;
  // trust the index and pick the node its trace implies.
  return J.trace() >= 0 ? SingularityType::source : SingularityType::sink;
}

}  // namespace

const char* to_string(SingularityType t) {
  switch (t) {
    case SingularityType::source: return "source";
    case SingularityType::sink: return "sink";
    case SingularityType::saddle: return "saddle";
    case SingularityType::center: return "center";
    case SingularityType::repelling_focus: return "repelling_focus";
    case SingularityType::attracting_focus: return "attracting_focus";
  }
  return "unknown";
}

SingularityType classify_jacobian(const Mat2& jacobian) {
  // The type does not depend on the scale of J: bring its largest entry to [0.5, 1)
  // (exactly) so that the determinant and the discriminant neither underflow nor overflow.
  Mat2 J = jacobian;
  const double largest = J.cwiseAbs().maxCoeff();
  if (largest > 0 && std::isfinite(largest)) {
    int e = 0;
    std::frexp(largest, &e);
    J = J.unaryExpr([e](double x) { return std::ldexp(x, -e); });
  }
  const double det = J.determinant();
  if (det < 0) return SingularityType::saddle;
  const double half_trace = 0.5 * J.trace();
  const double disc = half_trace * half_trace - det;  // (λ1 − λ2)² / 4
  if (disc < 0) {
    const double im = std::sqrt(-disc);
    if (std::abs(half_trace) <= kCenterTolerance * im) return SingularityType::center;
    if (im > kRealTolerance * std::abs(half_trace))
      return half_trace > 0 ? SingularityType::repelling_focus
                            : SingularityType::attracting_focus;
  }
  return half_trace >= 0 ? SingularityType::source : SingularityType::sink;
}

double face_curvature(const TangentBundle& bundle, int face) {
  const Mesh& mesh = bundle.mesh();
  // The rescaled angle excess Σ s_v·α − π is the real number; the stored transports give
  // it modulo 2π to rounding. Take the latter, lifted next to the former, so that the
  // index computation closes to rounding even where the two could differ (a flat star
  // that winds around its vertex more than once keeps unscaled angles in the bundle).
  double excess = -kPi;
  cplx holonomy(1, 0);
  for (int c = 0; c < 3; ++c) {
    const int h = 3 * face + c;
    const int v = mesh.tail(h);
    const double scale = mesh.is_boundary_vertex(v) ? 1.0 : kTwoPi / bundle.angle_sum(v);
    excess += scale * mesh.corner_angle(h);
    holonomy *= bundle.transport(h);
  }
  const double turn = std::arg(holonomy);
  return turn + kTwoPi * std::round((excess - turn) / kTwoPi);
}

std::vector<int> face_indices(const TangentBundle& bundle, std::span<const cplx> values) {
  return indices_of(bundle, normalized_values(bundle, values).z);
}

std::vector<Singularity> find_singularities(const TangentBundle& bundle,
                                            std::span<const cplx> values) {
  const Mesh& mesh = bundle.mesh();
  const Scaled scaled = normalized_values(bundle, values);
  const std::vector<cplx>& z = scaled.z;
  const std::vector<int> index = indices_of(bundle, z);
  std::vector<Singularity> out;
  for (int f = 0; f < mesh.num_faces(); ++f) {
    const int k = index[static_cast<size_t>(f)];
    if (k == 0) continue;
    const Face& t = mesh.face(f);
    std::array<cplx, 3> w;
    for (int c = 0; c < 3; ++c) {
      const auto cc = static_cast<size_t>(c);
      w[cc] = bundle.corner_to_face(3 * f + c) * z[static_cast<size_t>(t[cc])];
    }
    Singularity s;
    s.index = k;
    s.where.face = f;
    s.where.bary = zero_barycentric(w);
    s.position = Vec3::Zero();
    for (int c = 0; c < 3; ++c)
      s.position += s.where.bary[c] * mesh.position(t[static_cast<size_t>(c)]);

    // Jacobian in the face frame: w(y) = w0 + J·y with y the face coordinates relative to
    // corner 0, so J·[y1 y2] = [w1 − w0, w2 − w0].
    const Vec3& x0 = mesh.position(t[0]);
    Mat2 Y, W;
    for (int c = 1; c < 3; ++c) {
      const Vec3 d = mesh.position(t[static_cast<size_t>(c)]) - x0;
      Y.col(c - 1) = Vec2(d.dot(bundle.face_e1(f)), d.dot(bundle.face_e2(f)));
      W.col(c - 1) = to_vec2(w[static_cast<size_t>(c)] - w[0]);
    }
    const Mat2 J = W * Y.inverse();  // for the scaled values
    s.type = type_for(J, k);
    s.jacobian = J.unaryExpr([e = scaled.exponent](double x) { return std::ldexp(x, e); });
    out.push_back(s);
  }
  return out;
}

std::vector<Singularity> find_singularities(const TangentBundle& bundle, const Field& field,
                                            int frame) {
  TVF_CHECK(frame >= 0 && frame < field.frames(), "frame {} outside [0, {})", frame,
            field.frames());
  TVF_CHECK(field.num_vertices() == bundle.mesh().num_vertices(),
            "field of {} vertices on a mesh of {}", field.num_vertices(),
            bundle.mesh().num_vertices());
  auto out = find_singularities(bundle, field.frame(frame));
  const double t = field.time().time(frame);
  for (Singularity& s : out) {
    s.frame = frame;
    s.t = t;
  }
  return out;
}

}  // namespace tvf
