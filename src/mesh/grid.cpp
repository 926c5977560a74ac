#include "tvf/mesh/grid.h"

#include "tvf/core/error.h"
#include "tvf/mesh/mesh_validate.h"

#include <algorithm>
#include <cmath>

namespace tvf {

Mesh make_grid(const GridSpec& spec, const std::string& where) {
  if (spec.nx < 2 || spec.ny < 2)
    throw_input_error(
        where, "",
        fmt::format("a grid of {} × {} vertices is too small; it needs at least 2 × 2", spec.nx,
                    spec.ny));
  const long long count = static_cast<long long>(spec.nx) * static_cast<long long>(spec.ny);
  if (count > kMaxGridVertices)
    throw_input_error(where, "",
                      fmt::format("a grid of {} × {} = {} vertices is larger than the limit of {}",
                                  spec.nx, spec.ny, count, kMaxGridVertices));
  if (!spec.min.allFinite() || !spec.max.allFinite())
    throw_input_error(where, "",
                      fmt::format("the box [{}, {}] × [{}, {}] has a non-finite corner",
                                  spec.min.x(), spec.max.x(), spec.min.y(), spec.max.y()));
  if (std::max(spec.min.cwiseAbs().maxCoeff(), spec.max.cwiseAbs().maxCoeff()) > kMaxCoordinate)
    throw_input_error(where, "",
                      fmt::format("the box [{}, {}] × [{}, {}] is too large: a corner coordinate has a magnitude "
                                  "above {:g} (larger ones overflow the squared distances and areas tvf computes)",
                                  spec.min.x(), spec.max.x(), spec.min.y(), spec.max.y(), kMaxCoordinate));
  if (!(spec.max.x() > spec.min.x()) || !(spec.max.y() > spec.min.y()))
    throw_input_error(where, "",
                      fmt::format("the box [{}, {}] × [{}, {}] is empty or inverted (max must be "
                                  "greater than min on both axes)",
                                  spec.min.x(), spec.max.x(), spec.min.y(), spec.max.y()));
  const Vec2 extent = spec.max - spec.min;
  if (!extent.allFinite())
    throw_input_error(where, "",
                      fmt::format("the box [{}, {}] × [{}, {}] is too large to represent",
                                  spec.min.x(), spec.max.x(), spec.min.y(), spec.max.y()));

  const int nx = spec.nx;
  const int ny = spec.ny;
  std::vector<Vec3> positions;
  positions.reserve(static_cast<size_t>(count));
  const double dx = static_cast<double>(nx - 1);
  const double dy = static_cast<double>(ny - 1);
  for (int iy = 0; iy < ny; ++iy) {
    const double y = spec.min.y() + (static_cast<double>(iy) / dy) * extent.y();
    for (int ix = 0; ix < nx; ++ix) {
      const double x = spec.min.x() + (static_cast<double>(ix) / dx) * extent.x();
      positions.emplace_back(x, y, 0.0);
    }
  }

  std::vector<Face> faces;
  faces.reserve(2 * static_cast<size_t>(nx - 1) * static_cast<size_t>(ny - 1));
  for (int iy = 0; iy + 1 < ny; ++iy) {
    for (int ix = 0; ix + 1 < nx; ++ix) {
      const int v00 = iy * nx + ix;
      const int v10 = v00 + 1;
      const int v01 = v00 + nx;
      const int v11 = v01 + 1;
      // Split along (ix, iy)–(ix+1, iy+1); both triangles counter-clockwise seen from +z.
      faces.push_back({v00, v10, v11});
      faces.push_back({v00, v11, v01});
    }
  }
  return Mesh(std::move(positions), std::move(faces), "grid");
}

}  // namespace tvf
