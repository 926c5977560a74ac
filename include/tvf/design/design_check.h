#pragma once
// Does a field hold what its scene designs? (issue 4's "must show"; docs/analysis.md,
// "Design check".) check_design matches every designed feature of a scene to the
// topology of its field (analysis/topology.h) and lists what the field holds beyond them.
//
// Designed features:
// - a singular element (elements[k]): a singularity of its index on its path p(t) at every
//   frame of its life span [first, last path point's t];
// - a bifurcation element: a found bifurcation of its kind (creation or cancellation)
//   at its point and time, joining a saddle and a node of its stability (sink for
//   saddle_sink_*, source for saddle_source_*);
// - a Hopf element (hopf_supercritical, hopf_subcritical): its focus at its point at every
//   frame, with the normal form's Jacobian [[μ, −1], [1, μ]] (attracting before t0 and
//   repelling after for the supercritical form, the reverse for the subcritical one), and,
//   when t0 lies strictly inside the time range, a Hopf event of its criticality
//   (integrate/periodic_orbits.h) within the tolerances of its point and time. Its
//   `bifurcation` is the event's index in the analysis JSON's "bifurcations", which lists
//   the Hopf events after Topology::bifurcations;
// - a singular element of a key frame (keyframes[k].elements[i]): a singularity of its
//   index at its point in that key frame's frame;
// - with solver.keyframe_topology "matched" (keyframe_topology.h): each pair it creates or
//   cancels between key frames, as a bifurcation of that kind at its template's point and
//   time (planned again from the field's key frames);
// - deform generator: each singular element of deform.base, fixed, at every frame, with
//   the Jacobian M(t)·J (so a turned source is expected to become a center, then a sink).
// A frame singularity matches when it has the feature's index, lies within
// DesignCheckOptions::position_tolerance mean edge lengths of where the field puts the
// designed zero, and has a compatible type. The designed zero is the element's position x
// snapped to the domain, moved by the rest of the design: the other elements (or the
// solve) add V(x) to the element's own field J·w, which moves its zero to first order to
// x − J⁻¹·V(x) (one Newton step; V(x) sampled from the field, in the element's frame). The
// type is compatible when it has the same
// topological type (saddle; or for index +1 the stability: attracting, repelling), where
// a center is compatible with a focus of either stability (a center is non-hyperbolic:
// any neighbour tilts it into a focus), and a node with the focus of its stability.
//
// Edits (the scene's `edits`, applied after the generator) change what is expected:
// - remove_bifurcation: the bifurcation element whose designed point (or, after an earlier
//   move, its new point) is nearest to the edit's `at`, within twice the tolerances, is
//   expected absent: "removed as edited" when no bifurcation of either kind lies within the
//   tolerances of its point and time, not found ("still there") otherwise. An edit that
//   names no designed bifurcation is a feature of its own ("edits[i]"), checked the same way.
// - move_bifurcation: that bifurcation element is expected at the edit's `to` instead (an
//   edit that names no designed bifurcation: a bifurcation of either kind expected there).
// - cancel: the pair is expected absent at the edit's frame (a feature "edits[i]": no
//   singularity within the tolerance of either of the edit's positions); a designed
//   singularity within the tolerance of one of them is not checked at the frames of the
//   edit's window (its pair vanishes shortly before the frame and comes back after it).
// - smooth changes nothing that is expected.
//
// The paths that carry a matched singularity (and the two paths of a matched bifurcation)
// are the designed paths, and so are their continuations across a type change. Every other
// path is extra. A found bifurcation is designed (matched to a bifurcation element),
// implied (it joins two designed paths: a designed singularity that appears or vanishes
// between key frames, or at the end of its path, with a designed partner), or extra.
// A Hopf event of the field (integrate/periodic_orbits.h; every scene's are found) that no
// Hopf element designs is implied when every path of its focus is designed and the design
// makes that focus change stability (it holds the chain of paths joined by type changes
// repelling at some frame and attracting at another: a node the key-frame plan matches to
// one of the other stability, an element or deformed base element turned from source to
// sink), and extra otherwise (a designed center that drifts into a focus with a limit
// cycle). Bifurcation indices here are those of the analysis JSON's "bifurcations":
// Topology::bifurcations, then the Hopf events.
// Extras are grouped into connected sets (paths joined by extra bifurcations, Hopf events
// and type changes), each described in one line; a Hopf event not asked for on a designed
// focus is a group of its own, without paths.
#include "tvf/analysis/topology.h"
#include "tvf/scene/design_space.h"
#include "tvf/scene/design_tolerance.h"
#include "tvf/scene/scene.h"
#include "tvf/field/field.h"

#include <nlohmann/json.hpp>

#include <string>
#include <vector>

namespace tvf {

struct PeriodicOrbits;  // integrate/periodic_orbits.h
struct KeyframeIntervalReport;  // design/keyframe_topology.h

struct DesignCheckOptions {
  // How far a found singularity or bifurcation may lie from the designed point, in mean
  // edge lengths of the domain (scene/design_tolerance.h).
  double position_tolerance = kDesignPositionTolerance;
  // How far a found bifurcation's time may lie from the designed one, in frame steps.
  double time_tolerance = kDesignTimeTolerance;
  // The field's periodic orbits and Hopf events, when the caller has them; else they are
  // found here (integrate/periodic_orbits.h).
  const PeriodicOrbits* orbits = nullptr;
  // Key-frame topology "matched": the plan of the generation that made the field, when the
  // caller has it (GenerateReport::keyframe_intervals, or a generated folder's
  // keyframe_topology.json), one interval per pair of consecutive key frames; else it is
  // planned again here from the field's key frames (the same plan, at the plan's cost:
  // seconds on a large mesh whose guide is tried and refused).
  const std::vector<KeyframeIntervalReport>* keyframe_intervals = nullptr;
};

enum class FeatureKind { singularity, bifurcation };

// One designed feature and what was found for it.
struct DesignedFeature {
  FeatureKind kind = FeatureKind::singularity;
  std::string source;  // JSON path in the scene: "elements[2]", "keyframes[0].elements[1]", ...
  std::string type;    // as designed: "ccw_center", "saddle", "jacobian", "saddle_sink_creation", ...
  int index = 0;       // singularity: +1 or −1
  double t_begin = 0;  // singularity: life span within the time range (a key frame: its
  double t_end = 0;    //   frame's time twice); bifurcation: its time twice
  Vec3 position = Vec3::Zero();  // at t_begin, on the domain
  bool found = false;
  // Singularity: frames of the life span, frames where a matching singularity was found,
  // frames where the nearest singularity of the right index was in place but of an
  // incompatible type, and the largest distance of a match (world units).
  int frames = 0;
  int frames_matched = 0;
  int frames_type_differs = 0;
  double max_distance = 0;
  double max_shift = 0;  // largest first-order shift of the designed zero, |J⁻¹·V(x)|
  // Bifurcation: the matched bifurcation (index into Topology::bifurcations, −1 if none),
  // its distance (world units) and time offset (found − designed).
  int bifurcation = -1;
  double distance = 0;
  double time_offset = 0;
  std::vector<int> paths;  // ids of the found paths that carry the feature (ascending)
  std::string note;        // what is missing when not found; empty otherwise
  // Edits that change what is expected of the feature (see above).
  std::string edit;              // "edits[i]" of the last such edit; empty when none
  bool expected_absent = false;  // removed or cancelled by the edit: `found` means absent
  bool moved = false;            // bifurcation: position and t_begin are the edit's `to`
  int frames_edited = 0;         // singularity: frames left out, in a cancel edit's window
};

// A connected set of extra paths.
struct ExtraGroup {
  std::vector<int> paths;         // path ids, ascending
  std::vector<int> bifurcations;  // bifurcations and Hopf events touching these paths (indices
                                  // as the analysis JSON's, ascending)
  double t_begin = 0, t_end = 0;  // life span of the set
  Vec3 center = Vec3::Zero();     // mean of the paths' points
  std::string description;        // "saddle+sink pair, created at t=0.410, cancelled at t=0.470"
};

struct DesignCheck {
  std::vector<DesignedFeature> designed;
  // Bifurcation indices are the analysis JSON's: i < Topology::bifurcations.size() a
  // saddle–node bifurcation, else Hopf event i − Topology::bifurcations.size().
  std::vector<int> implied_bifurcations;
  std::vector<int> extra_paths;           // path ids
  std::vector<int> extra_bifurcations;
  std::vector<ExtraGroup> extras;
  // With "keyframe_topology": "matched": per interval between consecutive key frames, the
  // bifurcations the plan creates or cancels there and the extra ones (not asked for) the
  // analysis finds in it (t0 < t ≤ t1; the first interval also takes t = t0).
  struct KeyframeInterval {
    int from_keyframe = 0, to_keyframe = 0;
    double t0 = 0, t1 = 0;
    int planned = 0;
    std::vector<int> extra_bifurcations;  // indices as DesignCheck's (Hopf events included)
    // The plan could not guide the interval and left it free (KeyframeIntervalReport):
    // nothing planned or carried there; why.
    bool fallback = false;
    std::string unguided_reason;
  };
  std::vector<KeyframeInterval> keyframe_intervals;
  double position_tolerance = 0;  // world units
  double time_tolerance = 0;      // time units

  // Every feature is as designed and edited: found, or absent where an edit removes it.
  bool all_found() const;
  // A short human summary: the first line counts designed and found features and extras,
  // one line follows per feature not found and per extra group (at most `max_lines`, then
  // "… and N more"). Positions are written as the domain has them: (x, y) on planar
  // domains, (x, y, z) on surfaces.
  std::string summary(int max_lines = 8) const;
};

// Checks `topology` (of `field`, generated from `scene` on `space`) against the scene's design.
// Throws tvf::Error naming the scene when the topology's frames are not the scene's.
DesignCheck check_design(const Scene& scene, const DesignSpace& space, const Field& field,
                         const Topology& topology, const DesignCheckOptions& options = {});

// The design-check JSON (docs/file_formats.md): {"all_found", "summary", "tolerance":
// {"position", "time"}, "designed": [...], "implied_bifurcations", "extra": {"paths",
// "bifurcations", "groups": [...]}}. Path ids and bifurcation indices refer to the
// analysis JSON of the same field.
nlohmann::json design_check_to_json(const DesignCheck& check);

}  // namespace tvf
