#pragma once
// Crowd steering on a triangle-mesh surface (DESIGN §8; paper §9, Fig. 16, on a surface):
// agents are points of the mesh that move along
//     ω_G·s·G + ω_F·F,
// G = −∇φ/|∇φ| in the face holding the agent, φ the geodesic distance to the goals on the
// mesh with the obstacles cut out (the heat method, mesh/heat_distance.h, on
// the submesh of the faces outside obstacles: geodesics go round them), s the larger of
// the field's local speed |F| and a floor (`speed`, by default a quarter of the field's
// typical speed), F the designed field. Regions (start, goals, obstacles) are balls of
// world space: the faces whose centroid lies inside. Agents step together by the midpoint
// rule, walking on the surface (integrate/surface_walk.h); a walk that would enter an
// obstacle face stops at its edge (counted in contacts); an agent that enters a goal face
// has arrived and stays. With `separation` the agents keep apart (SurfaceCrowdSpec).
#include "tvf/field/field.h"
#include "tvf/field/field_sampler.h"
#include "tvf/mesh/tangent_bundle.h"
#include "tvf/render/mesh_renderer.h"
#include "tvf/render/painterly.h"
#include "tvf/render/texture_animation.h"

#include <functional>
#include <string>
#include <vector>

namespace tvf {

struct SurfaceRegion {
  Vec3 center{0, 0, 0};
  double radius = 0;
  bool contains(const Vec3& x) const { return (x - center).norm() < radius; }
};

struct SurfaceCrowdSpec {
  std::vector<SurfaceRegion> starts, goals, obstacles;
  int agents = 40;
  double speed = 0;           // least speed of the goal term; 0: a quarter of the field's typical speed
                              // (a zero field: 1.5 mesh diameters over the time range)
  double weight_goal = 0.5;   // ω_G
  double weight_field = 0.5;  // ω_F
  int steps_per_frame = 4;
  std::uint64_t seed = 1;
  // Avoidance (0: none): agents on their way keep at least this world distance apart
  // (centre to centre). After every step (and at the start) pairs closer than it are pushed
  // apart along the surface, each by half the overlap (up to 16 Gauss–Seidel sweeps of the
  // projection); an agent that reaches a goal leaves the crowd, as on the plane.
  double separation = 0;
};

// The crowd file on a surface (docs/file_formats.md): like the planar one, with regions
// {"ball": {"center": [x, y, z], "radius": r}}. Throws tvf::Error naming the file and the
// JSON path.
SurfaceCrowdSpec load_surface_crowd_spec(const std::string& path);

struct SurfaceCrowdResult {
  std::vector<double> times;                         // one per picture
  std::vector<std::vector<SurfacePoint>> where;      // [agent][picture]
  std::vector<std::vector<Vec3>> positions;          // [agent][picture], world, on the mesh
  std::vector<int> arrived;                          // per agent: first picture at a goal, −1 if never
  std::vector<double> distance;                      // φ per vertex (+∞ where no goal is reachable)
  std::vector<char> obstacle_face, goal_face;        // per face
  long contacts = 0;
};

// Throws tvf::Error on a planar domain (simulate_crowd draws those), a spec whose regions
// hold no face, or goals unreachable from every start.
SurfaceCrowdResult simulate_surface_crowd(const TangentBundle& bundle, const Field& field,
                                          const SurfaceCrowdSpec& spec, int frames = 0);

struct SurfaceCrowdAnimationOptions {
  int frames = 0;
  int size = 800;
  SurfaceView view;
  std::string frames_dir, video;
  std::string csv;  // the trajectories (write_surface_crowd_csv); any of the three outputs
  double fps = 25.0;
  std::function<void(int done, int total)> progress;
};

// The trajectories as CSV, as the planar crowd's (write_crowd_csv) with z: a header
// `agent,frame,t,x,y,z,arrived`, then one row per agent and picture (world positions on
// the mesh, full precision; arrived 1 from its first picture at a goal on). Written
// atomically; throws tvf::Error naming the file.
void write_surface_crowd_csv(const std::string& path, const SurfaceCrowdResult& result);

// Pictures: the mesh (obstacles dark grey, goals green, the rest pale), each agent's path so
// far as a brown line and the agent as a dark disc; and/or the CSV (written first: if it
// cannot be written, no pictures appear). Throws tvf::Error when no output is given.
AnimationReport write_surface_crowd_animation(const TangentBundle& bundle, const Field& field,
                                              const SurfaceCrowdSpec& spec, const SurfaceCrowdAnimationOptions& options,
                                              SurfaceCrowdResult* result = nullptr);

}  // namespace tvf
