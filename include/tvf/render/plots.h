#pragma once
// Pictures of an analysis that a designer reads at a glance (issue 4), drawn with Cairo
// as SVG and PNG:
//  - the coherence plot (paper Fig. 18): y_i = Σ_k ‖V_k(t_{i+1}) − V_k(t_i)‖ against t_i;
//  - the space-time view of the singularity paths (paper Fig. 8, right): an oblique view
//    of the box (u, v, t), u and v the domain's two widest axes (x and y on planar
//    domains), paths coloured by type — green source, red sink, blue saddle, magenta
//    center or focus — with the ranges of u, v and t on the box's edges, and bifurcations
//    marked: creations as filled black discs, cancellations as black rings. Paths that a
//    design check reports as extra (PlotOptions::extra_paths) are drawn dashed and thinner,
//    so the designed ones stand out. With PlotOptions::orbits, periodic orbits are drawn at
//    their times as closed curves (attracting orange, repelling teal; at most about twelve
//    frames of each track, evenly spaced, so the view stays readable) and Hopf events as
//    black diamonds.
// Files are written under temporary names and renamed when complete.
#include "tvf/analysis/topology.h"
#include "tvf/mesh/mesh.h"

#include <array>
#include <string>
#include <vector>

namespace tvf {

struct PeriodicOrbits;  // integrate/periodic_orbits.h

struct PlotOptions {
  int width = 900;
  int height = 600;
  std::string title;
  // Paths plot: ids of the paths the design did not ask for (design_check.h), drawn dashed.
  std::vector<int> extra_paths;
  // Paths plot: periodic orbits and Hopf events to draw (not owned; may be null).
  const PeriodicOrbits* orbits = nullptr;
};

// Writes `stem`.svg and `stem`.png; returns their paths.
std::vector<std::string> write_coherence_plot(const std::string& stem, const std::vector<double>& times,
                                              const std::vector<double>& coherence,
                                              const PlotOptions& options = {});
std::vector<std::string> write_paths_plot(const std::string& stem, const Mesh& mesh,
                                          const Topology& topology, const PlotOptions& options = {});

// The colour of a singularity type in the paper's convention (RGB in [0, 1]).
std::array<double, 3> type_color(SingularityType type);

}  // namespace tvf
