#pragma once
// Topological edits of a time-varying field (DESIGN §7, paper §8): the typed form of the
// scene's `edits` list. scene_json.cpp reads and validates the JSON once (naming the JSON
// path of every problem) into Scene::edits; field_editor.h applies them.
//
// Edits name singularities and bifurcations by position (the nearest one of that frame,
// or in space-time), so an edit keeps its meaning when the design is regenerated.
// Positions are world coordinates (z = 0 on planar domains); times are design times.
#include "tvf/core/types.h"
#include "tvf/scene/path_point.h"

#include <nlohmann/json.hpp>

#include <array>
#include <string>
#include <variant>

namespace tvf {

// Default half-width of the time window re-solved around an edit, as a fraction of the
// time range (±10 % of the frames).
inline constexpr double kDefaultEditWindow = 0.1;

// Cancel the pair of singularities (index +1 and −1) nearest to `pair` at `frame`.
struct CancelEdit {
  int frame = 0;
  std::array<Vec3, 2> pair{Vec3::Zero(), Vec3::Zero()};
  double window = kDefaultEditWindow;
};

// Remove the bifurcation nearest to `at` (space-time): an isolated one by cancelling its
// pair over the pair's life span.
struct RemoveBifurcationEdit {
  PathPoint at;
  double window = kDefaultEditWindow;
};

// Move the bifurcation nearest to `at` to the place and time `to` (on a surface, `to` is
// snapped to the surface).
struct MoveBifurcationEdit {
  PathPoint at;
  PathPoint to;
  double window = kDefaultEditWindow;
};

// Global spatio-temporal smoothing; strength in (0, 1].
struct SmoothEdit {
  double strength = 0.5;
};

using Edit = std::variant<CancelEdit, RemoveBifurcationEdit, MoveBifurcationEdit, SmoothEdit>;

// "cancel" | "remove_bifurcation" | "move_bifurcation" | "smooth" (the scene's "op").
const char* op_name(const Edit& edit);

// One entry of the canonical `edits` list (2-D positions on planar domains).
nlohmann::json edit_to_json(const Edit& edit, bool planar);
// One line describing an edit for messages, e.g. "cancel the pair near (0.1, 0.2) and
// (0.15, 0.22) at frame 40".
std::string describe(const Edit& edit);

}  // namespace tvf
