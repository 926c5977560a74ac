#pragma once
// Topology of a time-varying field (DESIGN §6, §9; paper §4, §8.2): singularity paths
// tracked through space-time and the saddle–node bifurcations where a path turns back in
// time. The result maps one to one onto the analysis JSON of DESIGN §9.
#include "tvf/analysis/singularities.h"
#include "tvf/field/field.h"
#include "tvf/mesh/tangent_bundle.h"

#include <nlohmann/json.hpp>

#include <string>
#include <vector>

namespace tvf {

// A point of a singularity path: world position and time.
struct PathSample {
  Vec3 position;
  double t = 0.0;
};

// A maximal piece of a singularity's trajectory with one type. A path begins at the
// first frame, at a creation bifurcation, or where the type changes (a transcritical
// event: the old singularity dies and a new one is born); it ends likewise.
struct SingularityPath {
  int id = 0;
  SingularityType type = SingularityType::source;
  int index = 0;           // +1 or −1
  double birth = 0.0;      // t of the first sample
  double death = 0.0;      // t of the last sample
  std::vector<PathSample> points;  // ordered in time
};

enum class BifurcationKind { creation, cancellation };
const char* to_string(BifurcationKind k);  // "creation" | "cancellation"

struct Bifurcation {
  double t = 0.0;
  Vec3 position;
  BifurcationKind kind = BifurcationKind::creation;
  std::array<int, 2> paths{-1, -1};  // ids of the two paths it joins
};

struct Topology {
  std::vector<double> times;
  std::vector<std::vector<Singularity>> singularities;  // per frame
  std::vector<SingularityPath> paths;
  std::vector<Bifurcation> bifurcations;
  std::vector<double> coherence;  // y_i of coherence.h
};

struct TopologyOptions {
  bool parallel = true;  // frames in parallel
};

Topology analyze_topology(const TangentBundle& bundle, const Field& field,
                          const TopologyOptions& options = {});

// The analysis JSON of DESIGN §9 (exact keys and type names).
nlohmann::json topology_to_json(const Topology& topology);

}  // namespace tvf
