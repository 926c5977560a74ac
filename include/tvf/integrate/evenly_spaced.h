#pragma once
// Evenly spaced streamlines (Jobard & Lefer 1997) of one frame on a planar domain, for
// pictures: starting from a seed at the domain's centre, new seeds are tried at
// `separation` on both sides of every point of the streamlines already placed, in the
// order they were placed; a streamline grows from a seed that is at least `separation`
// from every other line, and stops where it comes within test_ratio·separation of one
// (and at the usual stops of trace_streamline). A uniform grid of cells of size
// `separation` answers the distance queries.
#include "tvf/integrate/streamline.h"

namespace tvf {

struct EvenlySpacedOptions {
  double separation = 0.0;   // distance between lines; 0: 3 % of the bounding-box diagonal
  double test_ratio = 0.5;   // a line stops at test_ratio·separation from another
  double step = 0.0;         // RK4 arc-length step; 0: min(separation / 4, half an edge)
  double min_length = 0.0;   // shorter lines are dropped; 0: 2·separation
  size_t max_lines = 100000;
};

// Throws tvf::Error on a domain that is not planar.
std::vector<Streamline> evenly_spaced_streamlines(const TangentBundle& bundle, std::span<const cplx> values,
                                                  const EvenlySpacedOptions& options = {});

}  // namespace tvf
