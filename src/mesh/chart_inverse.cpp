#include "tvf/mesh/chart_inverse.h"

#include <algorithm>
#include <cmath>
#include <limits>

namespace tvf {

namespace {
double cross(cplx a, cplx b) { return a.real() * b.imag() - a.imag() * b.real(); }
}  // namespace

ChartInverse::ChartInverse(const TangentBundle& bundle, const LocalChart& chart, double radius)
    : bundle_(bundle), chart_(chart), radius_(radius) {
  const Mesh& mesh = bundle.mesh();
  // The faces to invert: all corners within the radius, image not folded.
  std::vector<int> faces;
  cplx lo(std::numeric_limits<double>::infinity(), std::numeric_limits<double>::infinity()), hi = -lo;
  for (int f = 0; f < mesh.num_faces(); ++f) {
    const Face& c = mesh.face(f);
    const cplx a = chart.coords[static_cast<size_t>(c[0])], b = chart.coords[static_cast<size_t>(c[1])],
               d = chart.coords[static_cast<size_t>(c[2])];
    if (std::abs(a) > radius || std::abs(b) > radius || std::abs(d) > radius) continue;
    if (!(cross(b - a, d - a) > 0)) continue;  // folded or degenerate image
    faces.push_back(f);
    for (const cplx z : {a, b, d}) {
      lo = cplx(std::min(lo.real(), z.real()), std::min(lo.imag(), z.imag()));
      hi = cplx(std::max(hi.real(), z.real()), std::max(hi.imag(), z.imag()));
    }
  }
  if (faces.empty()) return;
  // Buckets of about one face each over the images' bounding box.
  lo_ = lo;
  const double side = std::max(hi.real() - lo.real(), hi.imag() - lo.imag());
  n_ = std::clamp(static_cast<int>(std::ceil(std::sqrt(static_cast<double>(faces.size())))), 1, 1024);
  cell_ = std::max(side / n_, 1e-300);
  buckets_.resize(static_cast<size_t>(n_) * static_cast<size_t>(n_));
  auto bucket = [&](double x, double low) {
    return std::clamp(static_cast<int>(std::floor((x - low) / cell_)), 0, n_ - 1);
  };
  for (int f : faces) {
    const Face& c = mesh.face(f);
    const cplx a = chart.coords[static_cast<size_t>(c[0])], b = chart.coords[static_cast<size_t>(c[1])],
               d = chart.coords[static_cast<size_t>(c[2])];
    const int x0 = bucket(std::min({a.real(), b.real(), d.real()}), lo_.real());
    const int x1 = bucket(std::max({a.real(), b.real(), d.real()}), lo_.real());
    const int y0 = bucket(std::min({a.imag(), b.imag(), d.imag()}), lo_.imag());
    const int y1 = bucket(std::max({a.imag(), b.imag(), d.imag()}), lo_.imag());
    for (int y = y0; y <= y1; ++y)
      for (int x = x0; x <= x1; ++x)
        buckets_[static_cast<size_t>(y) * static_cast<size_t>(n_) + static_cast<size_t>(x)].push_back(f);
  }
}

std::optional<SurfacePoint> ChartInverse::locate(cplx w) const {
  if (!(std::abs(w) <= radius_) || buckets_.empty()) return std::nullopt;
  if (w.real() < lo_.real() || w.imag() < lo_.imag() || w.real() > lo_.real() + n_ * cell_ ||
      w.imag() > lo_.imag() + n_ * cell_)
    return std::nullopt;
  const int x = std::clamp(static_cast<int>(std::floor((w.real() - lo_.real()) / cell_)), 0, n_ - 1);
  const int y = std::clamp(static_cast<int>(std::floor((w.imag() - lo_.imag()) / cell_)), 0, n_ - 1);
  const Mesh& mesh = bundle_.mesh();
  std::optional<SurfacePoint> best;
  double best_min = -std::numeric_limits<double>::infinity();
  for (int f : buckets_[static_cast<size_t>(y) * static_cast<size_t>(n_) + static_cast<size_t>(x)]) {
    const Face& c = mesh.face(f);
    const cplx a = chart_.coords[static_cast<size_t>(c[0])], b = chart_.coords[static_cast<size_t>(c[1])],
               d = chart_.coords[static_cast<size_t>(c[2])];
    const double area = cross(b - a, d - a);
    const double b1 = cross(w - a, d - a) / area;
    const double b2 = cross(b - a, w - a) / area;
    const double b0 = 1 - b1 - b2;
    const double m = std::min({b0, b1, b2});
    // The face that holds w most deeply (on a shared edge, the first such face).
    if (m > best_min) {
      best_min = m;
      best = SurfacePoint{f, Vec3(b0, b1, b2)};
    }
  }
  constexpr double eps = -1e-9;
  if (!best || best_min < eps) return std::nullopt;
  // Rounding: clamp slightly negative coordinates and renormalise.
  Vec3& bary = best->bary;
  bary = bary.cwiseMax(0.0);
  bary /= bary.sum();
  return best;
}

cplx ChartInverse::coords(const SurfacePoint& q) const {
  const Face& c = bundle_.mesh().face(q.face);
  return q.bary[0] * chart_.coords[static_cast<size_t>(c[0])] + q.bary[1] * chart_.coords[static_cast<size_t>(c[1])] +
         q.bary[2] * chart_.coords[static_cast<size_t>(c[2])];
}

cplx ChartInverse::frame_in_face(const SurfacePoint& q) const {
  const Face& c = bundle_.mesh().face(q.face);
  cplx sum(0, 0);
  for (int k = 0; k < 3; ++k)
    sum += q.bary[k] * bundle_.corner_to_face(3 * q.face + k) * chart_.frame[static_cast<size_t>(c[static_cast<size_t>(k)])];
  return normalized(sum);
}

}  // namespace tvf
