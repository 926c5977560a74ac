#pragma once
// Topology of a time-varying field (DESIGN §6, §9; paper §4, §8.2): singularity paths
// tracked through space-time and the saddle–node bifurcations where a path turns back in
// time. The result maps one to one onto the analysis JSON of DESIGN §9.
//
// Method (docs/analysis.md, "Singularity paths"). Space-time vertex (v, j) — vertex v at
// frame t_j — has the global order id = j·|V| + v. Every prism face × [t_j, t_{j+1}] is
// split into three tetrahedra by that order (the diagonal of a side quad of edge u < w
// always runs from (u, j) to (w, j+1), so neighbouring prisms agree), which makes the
// field piecewise linear in space-time. A space-time triangle is crossed by the zero
// curve where its index — the Knöppel index of singularities.h written for space-time
// edges: Σ of the edge turns a (against the connection; 1 along time edges) plus the
// face curvature Ω_f when the triangle spans the whole face — is non-zero. Degenerate
// values are decided by the same simulation of simplicity as singularities.h, in the
// global order above, so the crossed triangles of frame j are exactly the singularities
// find_singularities reports for frame j. Each tetrahedron's four face indices sum to 0,
// so the crossings pair up tetrahedron by tetrahedron into curves (FTK, Guo et al.).
//
// A curve is cut at the frames into segments. A segment that leaves frame j and comes
// back to it is a saddle–node bifurcation (creation at a time minimum, cancellation at a
// time maximum, at the segment's extreme point). Between bifurcations, the time range's
// ends and the domain boundary, a curve is a track of one singularity; a track is split
// into paths where its topological type (per frame, from the face's Jacobian: saddle, or
// for index +1 attracting, repelling or center) changes and the new type holds for at
// least TopologyOptions::type_change_samples consecutive frames. Node and focus of the same
// stability are one topological type (docs/analysis.md, "Type changes"); a path is named
// by the precise type that most of its frames have.
#include "tvf/analysis/singularities.h"
#include "tvf/core/error.h"
#include "tvf/field/field.h"
#include "tvf/mesh/tangent_bundle.h"

#include <nlohmann/json.hpp>

#include <array>
#include <atomic>
#include <string>
#include <vector>

namespace tvf {

// A point of a singularity path: world position and time.
struct PathSample {
  Vec3 position = Vec3::Zero();
  double t = 0.0;
};

// A maximal piece of a singularity's trajectory with one type. A path begins at the
// first frame, at a creation bifurcation, where the singularity enters through the domain
// boundary, or where the type changes (a transcritical event: the old singularity dies and
// a new one is born at the first frame of the new type, which is the last point of the
// old path and the first of the new one); it ends likewise.
struct SingularityPath {
  int id = 0;
  SingularityType type = SingularityType::source;
  int index = 0;           // +1 or −1 (the index of every frame singularity on the path)
  double birth = 0.0;      // t of the first sample
  double death = 0.0;      // t of the last sample
  // Ordered in time (non-decreasing t): the frame singularities and the crossings of the
  // space-time triangles between frames; a bifurcation's point is the first (creation)
  // or last (cancellation) sample of both paths it joins.
  std::vector<PathSample> points;
};

enum class BifurcationKind { creation, cancellation };
const char* to_string(BifurcationKind k);  // "creation" | "cancellation"

struct Bifurcation {
  double t = 0.0;
  Vec3 position = Vec3::Zero();
  BifurcationKind kind = BifurcationKind::creation;
  std::array<int, 2> paths{-1, -1};  // ids of the two paths it joins (ascending)
};

// What the tracking did, for diagnostics (never needed to read the result).
struct TopologyStats {
  long long crossings = 0;    // crossed space-time triangles
  int curves = 0;             // connected zero curves
  int hidden_curves = 0;      // curves between two frames that meet no frame (not reported)
  int type_changes = 0;       // path splits at type changes
  int suppressed_flickers = 0;  // type runs shorter than type_change_samples, absorbed
};

struct Topology {
  std::vector<double> times;
  std::vector<std::vector<Singularity>> singularities;  // per frame (find_singularities)
  // singularity_path[j][k]: id of the path holding singularities[j][k] (a singularity at
  // a type change belongs to the new path).
  std::vector<std::vector<int>> singularity_path;
  std::vector<SingularityPath> paths;       // sorted by birth; id = position
  std::vector<Bifurcation> bifurcations;    // sorted by t
  std::vector<double> coherence;  // y_i of coherence.h
  TopologyStats stats;
};

struct TopologyOptions {
  bool parallel = true;  // frames in parallel (TBB)
  // A change of type along a track starts a new path only when the new type holds for at
  // least this many consecutive frames; shorter runs (center ↔ focus flicker next to the
  // 10 % thresholds of classify_jacobian) keep the current type. 1 splits at every change.
  int type_change_samples = 2;
  // Also split where a node turns into a focus of the same stability (sink ↔
  // attracting_focus, source ↔ repelling_focus). Off by default: the two are
  // topologically equivalent, equal eigenvalues are no bifurcation, and near them the
  // per-face Jacobian of a sampled field flips between the two from face to face.
  bool node_focus_changes = false;
  // Checked between frames (and between the steps after them): once true, the analysis
  // stops with AnalysisCancelled. The designer's server sets it when a newer change makes
  // the analysed field obsolete (issue 15).
  const std::atomic<bool>* cancel = nullptr;
};

// Thrown by analyze_topology and find_periodic_orbits once their options' `cancel` is true.
class AnalysisCancelled : public Error {
public:
  AnalysisCancelled() : Error("analysis cancelled") {}
};
// Throws AnalysisCancelled when `cancel` is set and true.
inline void check_analysis_cancel(const std::atomic<bool>* cancel) {
  if (cancel && cancel->load(std::memory_order_relaxed)) throw AnalysisCancelled();
}

// Topology of `field` on the mesh of `bundle`. Throws tvf::Error when a value is not
// finite (naming the vertex), as find_singularities does.
Topology analyze_topology(const TangentBundle& bundle, const Field& field,
                          const TopologyOptions& options = {});

// The analysis JSON of DESIGN §9 (exact keys and type names):
// {"frames", "times", "singularities": [{"frame", "t", "position", "face", "index", "type",
//  "jacobian"}], "paths": [{"id", "type", "birth", "death", "points"}], "bifurcations":
//  [{"t", "position", "kind", "paths"}], "coherence"}. Positions are world [x, y, z],
// path points [x, y, z, t], Jacobians [[a, b], [c, d]] in the face frame.
nlohmann::json topology_to_json(const Topology& topology);

}  // namespace tvf
