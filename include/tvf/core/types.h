#pragma once
// Small shared math types. A tangent vector is one complex number a + ib meaning
// a·e1 + b·e2 in some tangent basis (which basis is always stated where it is used).
#include <Eigen/Dense>

#include <complex>
#include <numbers>

namespace tvf {

using cplx = std::complex<double>;
using Vec2 = Eigen::Vector2d;
using Vec3 = Eigen::Vector3d;
using Mat2 = Eigen::Matrix2d;

inline constexpr double kPi = std::numbers::pi;

// Unit complex number in the direction of (x, y) without trigonometry, so that equal
// inputs give bit-identical outputs (planar transports must be exactly 1).
inline cplx unit_direction(double x, double y) {
  const double n = std::hypot(x, y);
  return n > 0 ? cplx(x / n, y / n) : cplx(1.0, 0.0);
}
inline cplx normalized(cplx z) { return unit_direction(z.real(), z.imag()); }

inline cplx to_complex(const Vec2& v) { return {v.x(), v.y()}; }
inline Vec2 to_vec2(cplx z) { return {z.real(), z.imag()}; }

}  // namespace tvf
