#pragma once
// Internal helpers of the planar applications (painterly, crowd, particles): the map
// between a planar domain's bounding box and a picture's pixels, point location, and the
// field's world vector at a point and time.
#include "tvf/core/error.h"
#include "tvf/field/field_sampler.h"
#include "tvf/field/point_locator.h"
#include "tvf/mesh/tangent_bundle.h"

#include <fmt/format.h>

#include <optional>

namespace tvf::detail {

// Domain bounding box [lo, hi] stretched onto a w × h picture (y up in the domain, down in
// the picture); pixel (i, j) covers [i, i+1] × [j, j+1].
struct PlanarView {
  Vec2 lo, hi;
  int width = 0, height = 0;
  PlanarView() = default;
  PlanarView(const Mesh& mesh, int w, int h)
      : lo(mesh.bbox_min().head<2>()), hi(mesh.bbox_max().head<2>()), width(w), height(h) {}
  // Fits the domain in `size` pixels on its long side, keeping its aspect ratio.
  static PlanarView fit(const Mesh& mesh, int size) {
    const Vec2 lo = mesh.bbox_min().head<2>(), hi = mesh.bbox_max().head<2>();
    const double ext = std::max(hi.x() - lo.x(), hi.y() - lo.y());
    return PlanarView(mesh, std::max(1, static_cast<int>(std::lround(size * (hi.x() - lo.x()) / ext))),
                      std::max(1, static_cast<int>(std::lround(size * (hi.y() - lo.y()) / ext))));
  }
  double sx() const { return width / (hi.x() - lo.x()); }
  double sy() const { return height / (hi.y() - lo.y()); }
  Vec2 to_pixel(const Vec2& x) const { return {(x.x() - lo.x()) * sx(), (hi.y() - x.y()) * sy()}; }
  Vec2 to_domain(const Vec2& p) const { return {lo.x() + p.x() / sx(), hi.y() - p.y() / sy()}; }
  // A vector of the domain in pixels.
  Vec2 vector_to_pixel(const Vec2& v) const { return {v.x() * sx(), -v.y() * sy()}; }
};

// Point location on a planar domain: the face under x, or nothing outside the domain.
class PlanarLocator {
public:
  explicit PlanarLocator(const Mesh& mesh) : mesh_(mesh), locator_(mesh), tol_(1e-9 * mesh.diameter()) {}
  std::optional<SurfacePoint> locate(const Vec2& x) const {
    const Vec3 p(x.x(), x.y(), 0.0);
    const SurfacePoint s = locator_.closest(p);
    if ((surface_position(mesh_, s) - p).norm() > tol_) return std::nullopt;
    return s;
  }

private:
  const Mesh& mesh_;
  PointLocator locator_;
  double tol_;
};

inline void require_planar(const TangentBundle& bundle, const char* what) {
  if (!bundle.is_flat())
    throw Error(fmt::format("{}: the domain is a surface; this rendering draws planar domains only", what));
}

}  // namespace tvf::detail
