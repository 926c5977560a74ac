#include "analysis/index_predicates.h"

#include "tvf/core/error.h"

#include <algorithm>
#include <cmath>
#include <limits>

namespace tvf::detail {

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

}  // namespace tvf::detail
