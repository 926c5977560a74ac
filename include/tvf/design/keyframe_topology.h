#pragma once
// Topology kept between key frames (DESIGN §12, beyond the paper's §10: "only the
// topology at the key frames is defined"). With "solver": {"keyframe_topology":
// "matched"} the spacetime generator
//  1. finds the singularities of every key frame's field (find_singularities);
//  2. matches those of consecutive key frames (match_keyframe_singularities): first the
//     pairs the scene links (solver.links, by key-frame element), then the same type
//     nearest first, then the same index nearest first (never a source with a sink: a node
//     keeps its stability); two of the static solve's own nodes that would trade places
//     are matched in place instead where their paths would cross or where that carries
//     less (a stability change counting solver.path_separation more); last, of what step 4
//     leaves neither matched nor paired, the same index nearest first across stability (a source-like node in one key frame, a sink-like one in the next,
//     within a quarter of the domain's diameter): its α turns through a center on the way
//     (|α| > |β| throughout, det J > 0), a Hopf-like type change, not a saddle–node pair;
//     the shorter way round, or the other where the planar guide's nodes' phases would
//     otherwise end whole turns apart (step 8);
//  3. carries each matched singularity from its key-frame position to the next one's as a
//     moving constraint (the linear field J(t)·w within solver.region_radius, as a moving
//     singular element is constrained; the position follows a smoothstep in time along
//     the straight segment, on a surface along a curve on it: the shortest path, the
//     shortest edge path straightened on the surface, by arclength; J(t) turns from one
//     end's Jacobian to the other's with det J keeping its sign, so the index cannot
//     change on the way);
//  4. pairs the unmatched ones of each key frame (opposite index, nearest first) and
//     cancels (first key frame's) or creates (second key frame's) each pair with a
//     saddle–node template (the bifurcation elements of DESIGN §4) centred between the
//     two, at the interval's bifurcation time (solver.bifurcation_times, default
//     mid-interval): the two are carried to the template's zeros at t_c − τ (cancellation)
//     or from them at t_c + τ (creation), and the template holds [t_c − τ, t_c + τ].
//  5. keeps every two singularities carried at the same time solver.path_separation apart
//     (default twice region_radius, so their constraint regions never overlap): where two
//     paths come closer (paths that cross), one or both are bent around the other by a
//     smooth bump perpendicular to their relative motion at the closest approach, full
//     while they are too close and vanishing at the key frames (ends and times kept; near
//     a key frame that holds them closer, the separation eases to what their straight
//     paths keep; two that both key frames hold closer than the separation and whose
//     straight paths do not approach need keep only what those keep; a path that moves
//     less than a tenth of the separation is never bent), shared between the two in
//     proportion to their lengths (the shortest pair of paths) unless that leaves the
//     domain or comes nearer its boundary than half the separation, when the other side
//     or one path alone is taken; when no detour fits, the interval's paths stay straight
//     and its report (and a warning) names the two paths that meet.
//     Distances are chord distances on surfaces (never more than the geodesic ones); there
//     a detour is an offset tangent to the surface walked along it from the path's curve.
//  6. when bending one pair after the other does not settle (three or more paths
//     knotted), leaves a path nearer than the separation to a saddle–node template while
//     it holds, or (planar domains) lets the nodes' phases in the product model
//     c Π_j g_j(z) drift half a turn apart, routes all the interval's moving paths at once
//     (the ones that move less than a tenth of the separation stand in the way): smooth
//     detours (sin(πs) sin(kπs), k = 1..4) that bend least under the separation, the
//     boundary margin and the phase drift (Levenberg–Marquardt from each choice of sides);
//     when that fails too, the paths stay straight with the warning of 5. Bounded: the
//     joint search is not tried for two paths a key frame already holds closer than the
//     separation that no detour of their own parts (the collision is the key frames' own;
//     it is where the pairwise rounds merely ran out), and stops after a fixed number of
//     Levenberg–Marquardt steps over all its starts.
//  7. in a routed interval, turns each saddle's axes with its neighbours (its β follows
//     the product model's phase) instead of keeping the key frames' axes.
//  8. on planar domains, fixes every free vertex of the frames strictly between the two
//     key frames to the interval's guide field (keyframe_topology.cpp, Guide): a field
//     whose zeros are the carried singularities and the planned pairs alone, equal to the
//     key frames at the ends, the matched nodes' types held; so the analysis finds no
//     bifurcation but the planned ones. On surfaces (SurfaceGuide) the first key frame's
//     field carried along the paths: each matched singularity's zero moved by a ratio
//     factor (z − p(t)) / (z − p(t₀)) in a projection chart around its path, blended to 1
//     outside a tube round the path, each created or cancelled pair's template likewise
//     as a ratio, then turned into the second key frame's field by a zero-free factor.
//     Not in an interval with a singularity left unpaired or paths that could not be
//     kept apart.
//  9. an interval that is not guided falls back to "free": none of its tracks or
//     templates is placed (the key frames alone constrain its frames), since the carried
//     regions alone left the band between them to the key frames' blend and made far more
//     bifurcations than none; its report says `fallback` and `unguided_reason`.
// Key frames themselves are unchanged. What could not be paired (an odd singularity out,
// e.g. one that must leave through the boundary) is left to the solve and reported.
#include "tvf/analysis/singularities.h"
#include "tvf/scene/design_space.h"
#include "tvf/scene/scene.h"

#include <nlohmann/json.hpp>

#include <array>
#include <functional>
#include <limits>
#include <optional>
#include <span>
#include <string>
#include <utility>
#include <vector>

namespace tvf {

// What happens in one interval between consecutive key frames (in time order).
struct KeyframeIntervalReport {
  int from_keyframe = 0, to_keyframe = 0;  // indices into scene.keyframes
  double t0 = 0, t1 = 0;                   // the two key frames' times
  double bifurcation_t = 0;                // when unmatched pairs are created/cancelled
  struct Match {
    SingularityType type = SingularityType::source;  // at the first key frame
    Vec3 from = Vec3::Zero(), to = Vec3::Zero();
    bool linked = false;  // named by solver.links
    double detour = 0;    // largest distance of its path from the straight segment, on a
                          // surface from its curve on it (0: not bent)
    // At the second key frame: the same as `type`, or of the other stability (a node
    // matched as the last resort, its type changing through a center on the way).
    SingularityType to_type = SingularityType::source;
    // A node of a guided interval on a surface that the guide does not hold to its type:
    // the turn of its linear part from the plan's (radians; a turn of π/2 is a center, π
    // the other stability). phase_turns: whole turns at the second key frame (its type
    // going round source, center, sink, center, source; on the sphere's knot every route
    // tried gives the same: docs/architecture.md); phase_swing: the largest turn on the
    // way. 0 where held.
    int phase_turns = 0;
    double phase_swing = 0;
  };
  struct Pair {
    SingularityType saddle_type = SingularityType::saddle, node_type = SingularityType::source;
    Vec3 saddle = Vec3::Zero(), node = Vec3::Zero();  // positions at the key frame
    Vec3 at = Vec3::Zero();                           // where the template sits
    double t = 0;
  };
  std::vector<Match> matched;
  std::vector<Pair> created, cancelled;
  std::vector<Vec3> unpaired_first, unpaired_second;  // left to the solve
  // The distance the carried singularities keep (solver.path_separation, or twice
  // region_radius), and the smallest distance between two of them that the plan reaches
  // (sampled at 257 times; infinite with fewer than two).
  double separation = 0;
  double closest_approach = std::numeric_limits<double>::infinity();
  // The default separation (no solver.path_separation: twice region_radius) lowered: it
  // could not be kept (lowered_because: the collision it met, in one sentence), and
  // `separation` is the three quarters of it, or of that, that could; 0 when not lowered.
  double lowered_from = 0;
  std::string lowered_because;
  // Not empty when two paths could not be kept apart (the domain too narrow for a detour,
  // or no set of detours found): why, in one sentence; the interval's paths then stay
  // straight. The generator also gives it as a warning.
  std::string collision;
  // Where (with `collision`): at time t the two paths the sentence names, of `types`, are
  // at `points`, `distance` apart where they must keep `required`; `template_` when the
  // second is a created or cancelled pair's saddle–node template (its middle), not a path.
  // The designer's "show where" goes there.
  struct Collision {
    double t = 0;
    std::array<Vec3, 2> points{Vec3::Zero(), Vec3::Zero()};
    std::array<SingularityType, 2> types{SingularityType::saddle, SingularityType::saddle};
    bool template_ = false;
    double distance = 0, required = 0;
  };
  std::optional<Collision> collision_at;
  // How the paths were kept apart: "straight" (none came too close, or they could not be
  // kept apart: see collision), "pairwise" (bent one pair at a time) or "joint" (all the
  // interval's paths bent at once, keeping clear of its saddle–node templates too).
  std::string routing = "straight";
  // The frames strictly between the two key frames are the interval's guide field: a
  // field whose zeros are the plan's alone (keyframe_topology.cpp, Guide; on surfaces
  // SurfaceGuide, where every singularity is matched or in a created or cancelled pair),
  // so the analysis finds no bifurcation but the planned ones.
  bool guided = false;
  // Not guided: the interval falls back to what "free" does there (the key frames alone;
  // none of its matched singularities carried, none of its pairs' templates placed), since
  // the carried regions alone make far more bifurcations than none; unguided_reason says
  // why it could not be guided, in one sentence (a collision, singularities left
  // unpaired, the surface folding over a path's chart, the guide's frames holding extra
  // zeros).
  bool fallback = false;
  std::string unguided_reason;
  // Turned down by the surface guide's check (its frames hold other singularities than the
  // plan's): where the first such frame goes wrong, as unguided_reason says it in words.
  // `extra`: the frame holds more than the plan carries, and `type` at `at` is the one
  // farthest from every planned singularity (`distance` from the nearest, of `nearest_type`);
  // else `type` at `at` is the plan's singularity farthest from any the frame holds
  // (`distance` from the nearest found). `distance` is infinite, and `nearest_type` means
  // nothing, when the other side holds none. `face_edges`: the longest edge of the face
  // holding `at`, in mean edge lengths (the extras found so far lay in coarse faces).
  struct WrongFrame {
    double t = 0;
    int found = 0, planned = 0;
    bool extra = true;
    SingularityType type = SingularityType::saddle;
    Vec3 at = Vec3::Zero();
    double distance = std::numeric_limits<double>::infinity();
    SingularityType nearest_type = SingularityType::saddle;
    double face_edges = 0;
  };
  std::optional<WrongFrame> first_wrong;
  // Where the guide leaves a node turning a whole turn (a Match with phase_turns ≠ 0): a
  // key frame at the frame nearest the interval's middle holding each singular
  // element of the first key frame where the plan carries it then, as it was designed, which
  // holds the nodes to their types (the sphere's knot of example 26: its source a source in
  // every frame, no warning). Offered where both key frames hold singular elements alone,
  // each carried, and the interval creates and cancels no pair. `from[i]`, `to[i]`: the
  // indices in the first and the second key frame of the element keyframe.elements[i] is
  // carried from and to (so that a client inserting it can keep a link through it).
  struct MiddleKeyframe {
    Keyframe keyframe;
    std::vector<int> from, to;
  };
  std::optional<MiddleKeyframe> middle_keyframe;
};

// Step 2's and 4's matching of two consecutive key frames' singularities (A: the first's,
// B: the second's). Matched: the links, then the same type nearest first, then the same
// index nearest first with the stability kept (both: the static solve's own singularities,
// neither linked nor designed, only within `carry_reach`, which the plan sets on its second
// try of an interval the first could not guide); then, among the matched nodes
// that neither a link nor a designed element holds (the static solve's own), two that trade
// places are matched in place instead where their paths would cross (their relative
// position passing nearer than half of what either key frame holds them apart) and in place
// they would not, or else where that carries less, a stability change counting
// `turnover_cost` more (the static solve's far foci turn over where they are rather than
// travel across the surface to where the other key frame has one of their kind); then the
// left over are paired (saddle with node, nearest first, each key frame apart), and a
// static solve's own node carried far exchanges roles with a paired node (not designed)
// where the carry plus the pair's distance is lower so (turnover_cost counted); then what
// is neither matched nor paired is matched across stability within `stability_reach`; what
// is still left, by type and then by index and stability, however far.
struct KeyframeMatchRules {
  std::vector<std::pair<size_t, size_t>> links;  // (in A, in B), checked by the caller
  std::vector<char> designed_a, designed_b;      // the singularity a singular element names (empty: none)
  double turnover_cost = 0;
  double stability_reach = std::numeric_limits<double>::infinity();
  double carry_reach = std::numeric_limits<double>::infinity();
};
struct KeyframeMatch {
  std::vector<std::pair<size_t, size_t>> matched;  // (in A, in B): the links first
  std::vector<std::pair<size_t, size_t>> cancelled, created;  // (saddle, node) of A, of B
};
KeyframeMatch match_keyframe_singularities(std::span<const Singularity> A, std::span<const Singularity> B,
                                           const KeyframeMatchRules& rules);

// The constraints that keep the topology between key frames, planned once per generation.
class KeyframeTopologyPlan {
public:
  // keyframe_fields[k]: the field of scene.keyframes[k] (|V|, vertex bases). Throws
  // tvf::Error naming solver.links[i] when a linked element has no singularity of the
  // key frame's field near it. checkpoint, when set, is called between the plan's steps
  // (each interval, each routing round, each guide frame counted: well under a second
  // apart) and may throw to stop it: generation passes its cancellation check, so that a
  // newer scene in the designer does not wait for a plan it has made pointless.
  // on_interval, when set, is called as the plan starts interval k of n (from key frame k
  // to k + 1; n = key frames − 1): generation says so (GenerateOptions::stage).
  KeyframeTopologyPlan(const DesignSpace& space, const Scene& scene,
                       const std::vector<std::vector<cplx>>& keyframe_fields,
                       const std::function<void()>& checkpoint = {},
                       const std::function<void(size_t k, size_t n)>& on_interval = {});

  // Adds the plan's constraints at time t (a frame that is not a key frame) to a frame's
  // fixed set and values, as constrain_elements does: d is the falloff's d.
  void constrain(const DesignSpace& space, const Scene& scene, double t, double d, std::span<char> fixed,
                 std::span<cplx> values) const;

  const std::vector<KeyframeIntervalReport>& intervals() const { return intervals_; }
  // Where the plan puts the singularities it carries at time t (world, one per path
  // present at t; on a surface the point before constrain() snaps it to the surface).
  std::vector<Vec3> carried(double t) const;

  struct Track;     // one singularity carried between two times
  struct Template;  // one saddle–node template
  struct Guide;     // one interval's guide field (planar domains)
  struct SurfaceGuide;  // one interval's guide field on a surface
  ~KeyframeTopologyPlan();
  KeyframeTopologyPlan(KeyframeTopologyPlan&&) noexcept;

private:
  std::vector<Track> tracks_;
  std::vector<Template> templates_;
  std::vector<Guide> guides_;
  std::vector<SurfaceGuide> surface_guides_;
  std::vector<KeyframeIntervalReport> intervals_;
};

// {"interval": [t0, t1], "keyframes": [k0, k1], "bifurcation_t", "matched": [{"type",
// "from", "to", "linked", "detour", "to_type", "phase_turns", "phase_swing" (guided
// intervals)}], "created": [{"t", "at", "saddle", "node",
// "node_type"}], "cancelled": [same], "separation", "lowered_from" and "lowered_because"
// (when the default separation was lowered), "closest_approach" (when two or more
// are carried), "collision" (when not empty), "routing", "guided", "fallback" (not guided:
// the interval left free), "unguided_reason" (when not guided), "first_wrong": {"t",
// "found", "planned", "extra", "type", "at", "distance", "nearest_type" (the last two when
// the other side holds any), "face_edges"} (when the guide's check turned it down),
// "middle_keyframe": {"keyframe" (a key frame in the scene's form, DESIGN §10), "from",
// "to"} (where one is offered), "collision_at": {"t", "points", "types", "template",
// "distance", "required"} (with "collision"), "unpaired": [[x, y, z], ...]} per interval.
nlohmann::json keyframe_intervals_json(const std::vector<KeyframeIntervalReport>& intervals);

// An interval's "first_wrong" object (the same in keyframe_topology.json and the server's
// status).
nlohmann::json wrong_frame_json(const KeyframeIntervalReport::WrongFrame& w);
// An interval's "collision_at" object (the same in keyframe_topology.json and the server's
// status).
nlohmann::json collision_json(const KeyframeIntervalReport::Collision& c);
// An interval's "middle_keyframe" object (the same in keyframe_topology.json and the
// server's status). Only surfaces have one (the planar guide holds every node to its
// type), so its points are [x, y, z].
nlohmann::json middle_keyframe_json(const KeyframeIntervalReport::MiddleKeyframe& m);

// The intervals back from keyframe_topology.json ({"intervals": keyframe_intervals_json}),
// as the design check uses them (what was matched, created and cancelled, guided or left
// free, and why); nullopt when the JSON is not such a file (the check then plans again).
std::optional<std::vector<KeyframeIntervalReport>> keyframe_intervals_from_json(const nlohmann::json& file);

}  // namespace tvf
