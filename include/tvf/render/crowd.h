#pragma once
// Crowd steering (DESIGN §8; paper §9, Fig. 16): agents on a planar domain move along
//     ω_G·G + ω_F·F,
// G = −∇φ/|∇φ| the direction down a continuum-crowd style potential φ (Treuille et al.
// 2006): the travel time to the nearest goal around obstacles, the solution of the eikonal
// equation |∇φ| = 1 outside obstacles (grown by the agents' radius), φ = 0 on goal cells,
// by fast marching on a regular grid over the domain's bounding box, times the larger of
// the field's local speed |F| and a floor `speed` (by default a quarter of the field's
// typical speed, the 90th percentile of |V|), so that both terms are of the same size and the goal still
// draws agents on where the field is weak; F the designed field as it is, so that with
// ω_G = 0 and ω_F = 1 agents
// follow the field's pathlines exactly (the reference pathlines drawn in Fig. 16). Agents
// may also avoid each other (CrowdSpec::separation). Agents step together by the midpoint
// rule, stop on reaching a goal, and never enter an obstacle (a step that would end inside
// one is pushed back to its boundary, counted in CrowdResult::contacts).
#include "tvf/field/field.h"
#include "tvf/mesh/tangent_bundle.h"
#include "tvf/render/image.h"
#include "tvf/render/painterly.h"

#include <functional>
#include <nlohmann/json_fwd.hpp>
#include <span>
#include <string>
#include <vector>

namespace tvf {

// A circle or an axis-aligned rectangle of the domain.
struct CrowdShape {
  enum class Kind { circle, rectangle };
  Kind kind = Kind::circle;
  Vec2 center{0, 0};
  double radius = 0;
  Vec2 min{0, 0}, max{0, 0};
  static CrowdShape circle(const Vec2& c, double r);
  static CrowdShape rectangle(const Vec2& lo, const Vec2& hi);
  // Signed distance: negative inside.
  double distance(const Vec2& x) const;
  bool contains(const Vec2& x) const { return distance(x) < 0; }
  // The point closest to x on the boundary grown by `margin`.
  Vec2 push_out(const Vec2& x, double margin) const;
  // Whether the segment from a to b passes through the inside (touching or sliding along
  // the boundary does not count): the whole of an agent's step is checked with it.
  bool crosses(const Vec2& a, const Vec2& b) const;
};

struct CrowdSpec {
  std::vector<CrowdShape> obstacles;
  std::vector<CrowdShape> goals;
  std::vector<CrowdShape> starts;   // agents start spread evenly over these (outside obstacles)
  int agents = 40;
  double speed = 0;                 // least speed of the goal term, domain units per unit time; 0: a quarter
                                    // of the field's typical speed (1.5 box diagonals over the time range for a
                                    // zero field)
  double weight_goal = 0.5;         // ω_G
  double weight_field = 0.5;        // ω_F
  int grid = 160;                   // fast-marching cells on the long side
  double agent_radius = 0;          // obstacles grow by this for the potential; 0: 1.5 grid cells
  int steps_per_frame = 4;          // agent steps between two pictures
  // Agent–agent avoidance (off when separation is 0): no two agents on their way come
  // closer than `separation` (domain units between centres). Each step adds a separation
  // term (a social force, Helbing & Molnár 1995) pushing an agent away from every agent
  // within 2·separation, growing linearly to avoidance_weight × the agent's own speed at
  // `separation`; after the step, pairs still closer are pushed apart along the line
  // joining them (position-based projection), and a pair that cannot be separated keeps
  // its previous, separated positions for that step. Agents that reach a goal leave the
  // crowd (they no longer count). Start positions keep the distance too.
  double separation = 0;
  double avoidance_weight = 1.0;
};

// Reads the crowd file (JSON, docs/file_formats.md). Throws tvf::Error naming the file and
// the JSON path on a bad value or an unknown key.
CrowdSpec load_crowd_spec(const std::string& path);
CrowdSpec parse_crowd_spec(const nlohmann::json& json, const std::string& file);

// Fast marching (Sethian 1996; first-order upwind) for |∇φ| = cost on an nx × ny grid of
// spacing h, row-major (index j·nx + i). φ = 0 where `source` is non-zero; cells of
// infinite cost are blocked and, with cells they cannot reach, get +∞.
std::vector<double> fast_marching(int nx, int ny, double h, std::span<const double> cost,
                                  std::span<const char> source);

struct CrowdResult {
  std::vector<double> times;                 // one per picture
  std::vector<std::vector<Vec2>> positions;  // [agent][picture]
  std::vector<int> arrived;                  // per agent: first picture at its goal, −1 if never
  std::vector<std::vector<Vec2>> reference;  // per agent: the field's pathline from its start
  long contacts = 0;                         // steps pushed out of an obstacle
  // The potential φ on its grid (for pictures and tests).
  int nx = 0, ny = 0;
  double h = 0;
  Vec2 grid_origin{0, 0};
  std::vector<double> potential;
};

// Simulates the crowd over the field's time range with `frames` pictures (0: the field's
// frames). Throws tvf::Error on a surface domain or a bad spec (naming the value).
CrowdResult simulate_crowd(const TangentBundle& bundle, const Field& field, const CrowdSpec& spec, int frames = 0);

// Picture k of the crowd, as in Fig. 16: obstacles grey, goals green, reference pathlines
// cyan, agents' paths so far brown, agents dark dots; `size` pixels on the long side.
Image draw_crowd(const TangentBundle& bundle, const CrowdSpec& spec, const CrowdResult& result, int k, int size);

// Trajectories as CSV: agent,frame,t,x,y,arrived (docs/file_formats.md), written atomically.
void write_crowd_csv(const std::string& path, const CrowdResult& result);

struct CrowdAnimationOptions {
  int frames = 0;
  int size = 800;
  std::string frames_dir, video, csv;
  double fps = 25.0;
  std::function<void(int done, int total)> progress;
};

AnimationReport write_crowd_animation(const TangentBundle& bundle, const Field& field, const CrowdSpec& spec,
                                      const CrowdAnimationOptions& options, CrowdResult* result = nullptr);

}  // namespace tvf
