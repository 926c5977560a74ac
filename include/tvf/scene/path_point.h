#pragma once
// A control point of a path in space-time: a world position and a design time (DESIGN
// §10: `[x, y, t]` on planar domains, `[x, y, z, t]` on surfaces).
#include "tvf/core/types.h"

namespace tvf {

struct PathPoint {
  Vec3 position = Vec3::Zero();
  double t = 0.0;
};

}  // namespace tvf
