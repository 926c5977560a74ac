#include "tvf/analysis/singularities.h"

#include "analysis/index_predicates.h"

#include "tvf/core/error.h"

#include <Eigen/LU>

#include <algorithm>
#include <array>
#include <cmath>
#include <limits>

namespace tvf {

using namespace detail;

namespace {




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

// `curvature`: Ω_f of every face (face_curvatures), or empty: computed here.
std::vector<int> indices_of(const TangentBundle& bundle, const std::vector<cplx>& z,
                            std::span<const double> curvature = {}) {
  const Mesh& mesh = bundle.mesh();
  const std::vector<double> a = halfedge_angles(bundle, z);
  std::vector<int> index(static_cast<size_t>(mesh.num_faces()), 0);
  for (int f = 0; f < mesh.num_faces(); ++f) {
    const auto h = static_cast<size_t>(3 * f);
    const double omega =
        curvature.empty() ? face_curvature(bundle, f) : curvature[static_cast<size_t>(f)];
    const double turn = a[h] + a[h + 1] + a[h + 2] + omega;
    const double k = std::round(turn / kTwoPi);
    // Σ a + Ω_f is a multiple of 2π by construction (the product of the edge ratios is
    // the inverse holonomy); a large residual means the bundle's transports and its
    // angle sums disagree.
    TVF_CHECK(std::abs(turn - kTwoPi * k) < 1e-6,
              "face {}: edge angles {} {} {} and curvature {} do not close (residual {})", f,
              a[h], a[h + 1], a[h + 2], omega, turn - kTwoPi * k);
    index[static_cast<size_t>(f)] = static_cast<int>(k);
  }
  return index;
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

std::vector<double> face_curvatures(const TangentBundle& bundle) {
  std::vector<double> out(static_cast<size_t>(bundle.mesh().num_faces()));
  for (int f = 0; f < bundle.mesh().num_faces(); ++f)
    out[static_cast<size_t>(f)] = face_curvature(bundle, f);
  return out;
}

// w(y) = w0 + J·y with y the face coordinates relative to corner 0, so J·[y1 y2] = [w1 − w0, w2 − w0].
Mat2 face_linear_jacobian(const TangentBundle& bundle, int f, const std::array<cplx, 3>& w) {
  const Mesh& mesh = bundle.mesh();
  const Face& t = mesh.face(f);
  const Vec3& x0 = mesh.position(t[0]);
  Mat2 Y, W;
  for (int c = 1; c < 3; ++c) {
    const Vec3 d = mesh.position(t[static_cast<size_t>(c)]) - x0;
    Y.col(c - 1) = Vec2(d.dot(bundle.face_e1(f)), d.dot(bundle.face_e2(f)));
    W.col(c - 1) = to_vec2(w[static_cast<size_t>(c)] - w[0]);
  }
  return W * Y.inverse();
}

Mat2 face_jacobian(const TangentBundle& bundle, std::span<const cplx> values, int face) {
  const Face& t = bundle.mesh().face(face);
  std::array<cplx, 3> w;
  for (int c = 0; c < 3; ++c)
    w[static_cast<size_t>(c)] = bundle.corner_to_face(3 * face + c) * values[static_cast<size_t>(t[static_cast<size_t>(c)])];
  return face_linear_jacobian(bundle, face, w);
}

std::vector<Singularity> find_singularities(const TangentBundle& bundle,
                                            std::span<const cplx> values) {
  return find_singularities(bundle, values, {});
}

std::vector<Singularity> find_singularities(const TangentBundle& bundle,
                                            std::span<const cplx> values,
                                            std::span<const double> curvature) {
  const Mesh& mesh = bundle.mesh();
  TVF_CHECK(curvature.empty() || static_cast<int>(curvature.size()) == mesh.num_faces(),
            "{} face curvatures for a mesh of {} faces", curvature.size(), mesh.num_faces());
  const Scaled scaled = normalized_values(bundle, values);
  const std::vector<cplx>& z = scaled.z;
  const std::vector<int> index = indices_of(bundle, z, curvature);
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

    const Mat2 J = face_linear_jacobian(bundle, f, w);  // for the scaled values
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
