#pragma once
// Streamlines of one frame (DESIGN §8), on planar domains for now: RK4 on the unit
// direction field (arc-length parametrisation), both ways from the seed, stopping at the
// domain's boundary, where the field vanishes (a singularity), after max_length, or when
// the curve closes on itself. Surfaces (face walking with transport) come with issue 6.
#include "tvf/field/field_sampler.h"
#include "tvf/mesh/tangent_bundle.h"

#include <span>
#include <vector>

namespace tvf {

struct StreamlineOptions {
  double step = 0.0;        // arc length per RK4 step; 0: half the mean edge length
  double max_length = 0.0;  // per direction; 0: the domain's bounding-box diagonal
  double stop_speed = 1e-9; // stop where |V| < stop_speed · (largest |V| of the frame)
};

struct Streamline {
  std::vector<Vec3> points;    // ordered along the flow
  std::vector<double> speeds;  // |V| at each point
  size_t seed = 0;             // index of the seed in points
};

// Throws tvf::Error when the domain is not planar or the seed lies outside it.
Streamline trace_streamline(const TangentBundle& bundle, std::span<const cplx> values,
                            const Vec3& seed, const StreamlineOptions& options = {});

}  // namespace tvf
