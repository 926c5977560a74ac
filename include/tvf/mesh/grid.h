#pragma once
// Planar regular grids (DESIGN §2, §11): vertex index = iy·nx + ix, position
// min + (ix/(nx−1), iy/(ny−1))·(max − min), z = 0. Each cell is split into two
// triangles along the diagonal from (ix, iy) to (ix+1, iy+1), counter-clockwise.
#include "tvf/mesh/mesh.h"

namespace tvf {

struct GridSpec {
  int nx = 65;
  int ny = 65;
  Vec2 min{-1.0, -1.0};
  Vec2 max{1.0, 1.0};
};

// Largest grid accepted (vertices); beyond it memory for a 100-frame field would not fit.
inline constexpr long long kMaxGridVertices = 50'000'000;

// Throws tvf::Error (naming `where`) for sizes < 2, sizes over kMaxGridVertices, or
// an empty or inverted box.
Mesh make_grid(const GridSpec& spec, const std::string& where = "grid");

}  // namespace tvf
