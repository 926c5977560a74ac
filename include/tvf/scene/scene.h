#pragma once
// The scene: the whole design (DESIGN §10). Every client reads and writes it through
// scene_json.h; this header is the in-memory form. Positions are world coordinates:
// planar domains use (x, y) with z = 0; mesh domains use (x, y, z), snapped to the
// surface when the design is evaluated.
#include "tvf/core/types.h"
#include "tvf/field/time_sampling.h"
#include "tvf/mesh/grid.h"
#include "tvf/scene/edits.h"
#include "tvf/scene/path_point.h"
#include "tvf/solve/flux_boundary.h"

#include <optional>
#include <string>
#include <variant>
#include <vector>

namespace tvf {

// M(t) = diag(sx, sy)·R(θ), keyed; sx, sy, θ interpolated linearly (paper §5.1).
struct TransformKey {
  double t = 0.0;
  double sx = 1.0;
  double sy = 1.0;
  double theta = 0.0;
};

enum class SingularType {
  source,
  sink,
  saddle,
  ccw_center,
  cw_center,
  repelling_focus,
  attracting_focus,
};

// Jacobian of a named type. Foci spiral with equal radial and angular rates.
Mat2 jacobian_of(SingularType type);

struct SingularElement {
  std::optional<SingularType> type;  // empty when given by an explicit Jacobian
  Mat2 jacobian = Mat2::Identity();
  std::vector<PathPoint> path;       // ≥ 1 point; one point = fixed element
  std::vector<TransformKey> transform;
};

struct RegularElement {
  std::vector<PathPoint> pathline;  // ≥ 2 points with increasing t
  double attach = 0.0;              // attachment strength c ≥ 0 (0: plain regular element)
};

enum class BifurcationType {
  saddle_source_cancellation,  // eq. 1: (t + x², y)
  saddle_sink_creation,        // eq. 2: (t − x², −y)
  saddle_source_creation,      // (−t + x², y)
  saddle_sink_cancellation,    // (−t − x², −y)
  // Hopf (DESIGN §12): (μx − y − σx(x²+y²), x + μy − σy(x²+y²)), μ = t. Supercritical
  // (σ = +1): an attracting focus for μ < 0; for μ > 0 a repelling focus inside an
  // attracting cycle of radius √μ. Subcritical (σ = −1): a repelling focus for μ > 0; for
  // μ < 0 an attracting focus inside a repelling cycle of radius √(−μ).
  hopf_supercritical,
  hopf_subcritical,
};

// True for the two Hopf types (a focus that changes stability while a cycle is born
// around it), false for the four saddle–node templates.
inline bool is_hopf(BifurcationType t) {
  return t == BifurcationType::hopf_supercritical || t == BifurcationType::hopf_subcritical;
}

struct BifurcationElement {
  BifurcationType type = BifurcationType::saddle_sink_creation;
  PathPoint at;             // position and time of the bifurcation
  double scale = 0.25;      // space scale s (world units)
  double time_scale = 0.25; // time scale τ
  double angle = 0.0;       // axis angle θ (radians)
};

// A streakline the user sketches (issue 20; design/streakline_design.h): dye released
// continuously from points[0] (the seed) over [from, t] has, at time t, the shape of the
// polyline points[0] … points[n] (points[0] the youngest dye, points[n] the oldest). The
// generators that solve for the field (constrained, spacetime) make the field carry the
// dye along the polyline at the constant speed u = length / (t − from); `attach` (≥ 0, per
// unit length, as a regular element's) adds a pull onto the polyline. It has no basis
// field of its own: the basis generator ignores it (and warns).
struct StreaklineElement {
  std::vector<Vec3> points;  // ≥ 2 world points, the seed first
  double t = 1.0;            // when the dye has this shape (the end of the release)
  double from = 0.0;         // the start of the release, from < t
  double attach = 0.0;       // pull onto the polyline, c ≥ 0 per unit length
};

using Element = std::variant<SingularElement, RegularElement, BifurcationElement, StreaklineElement>;

// Key frames (DESIGN §10; used by the spacetime generator).
struct KeyframeElement {
  std::string kind;  // "singular" | "regular"
  std::optional<SingularType> type;
  Mat2 jacobian = Mat2::Identity();
  Vec3 at = Vec3::Zero();
  Vec3 vector = Vec3::UnitX();  // regular only
};
struct KeyframeStreamline {
  std::vector<Vec3> points;
  double speed = 1.0;
};
struct Keyframe {
  double t = 0.0;
  std::vector<KeyframeElement> elements;
  std::vector<KeyframeStreamline> streamlines;
  std::string field;  // a field file (resolved relative to the scene), or empty
};

enum class Generator { basis, constrained, spacetime, deform };
enum class Weights { cotan, uniform, mean_value };
// How the spacetime generator solves (SpaceTimeSolver): auto takes the temporal modes
// where the fixed set allows them, else CG; bicgstab is the paper's kind of method.
enum class SolverMethod { automatic, modes, cg, bicgstab };

// What the spacetime generator does with the singularities of consecutive key frames
// (DESIGN §12; the generator's side is tvf/design/keyframe_topology.h): "free" leaves the
// frames between to the solve (the paper's behaviour), "matched" carries each matched
// singularity from one key frame to the next and creates or cancels the others in pairs.
enum class KeyframeTopology { free, matched };

// A pair the user links (solver.links): keyframes[from_keyframe].elements[from_element] is
// carried to keyframes[to_keyframe].elements[to_element], to_keyframe = from_keyframe + 1.
struct KeyframeLink {
  int from_keyframe = 0, from_element = 0;
  int to_keyframe = 0, to_element = 0;
};

// The deform generator's block (DESIGN §10, paper §7): V(t) = M(t) V(t0), with V(t0)
// the static constrained design of `base`, M(t) from `matrix` or `transform` keys (at
// most one of them is given; neither: the identity), and representative streamlines
// moved by keyed similarities.
struct MatrixKey {
  double t = 0.0;
  Mat2 m = Mat2::Identity();  // interpolated linearly, from the identity at t0 to the first key
};
struct StreamlineKey {
  double t = 0.0;
  Vec3 translate = Vec3::Zero();  // world vector (on surfaces: in the tangent plane at the seed)
  double rotate = 0.0;            // radians, counter-clockwise about the seed
  double scale = 1.0;             // > 0
};
struct DeformStreamline {
  Vec3 seed = Vec3::Zero();
  std::vector<StreamlineKey> keys;  // ≥ 1, increasing t
};
struct Deform {
  std::vector<Element> base;  // deform.base.elements
  std::optional<std::vector<MatrixKey>> matrix;
  std::optional<std::vector<TransformKey>> transform;
  std::vector<DeformStreamline> streamlines;
};

// The solver block (DESIGN §10). Every key is read in one place (scene_json.cpp's
// Reader::solver) and written in one place (scene_json.cpp's solver_json).
struct SolverSettings {
  Weights weights = Weights::cotan;
  double temporal_weight = 30.0;
  double tolerance = 1e-10;
  double region_radius = 0.1;
  SolverMethod method = SolverMethod::automatic;
  KeyframeTopology keyframe_topology = KeyframeTopology::free;
  std::vector<KeyframeLink> links{};  // "matched" only
  // One time per interval between consecutive key frames, inside it: when its unmatched
  // singularities are created or cancelled. Empty: the middle of each interval.
  std::vector<double> bifurcation_times{};
  // "matched" only: how far apart (world units) two carried singularities stay at every
  // time; matched paths that would come closer are bent around each other. Unset: twice
  // region_radius (the two constraint regions never overlap); 0: paths stay straight.
  std::optional<double> path_separation{};
};

// Meshes made in code (tvf additions to the format, so examples need no mesh files).
struct SphereSpec {
  int subdivisions = 5;  // icosphere: 10·4^s + 2 vertices
  double radius = 1.0;
};
struct TorusSpec {
  int nu = 96;  // around the z axis
  int nv = 48;  // around the tube
  double major_radius = 1.0;
  double minor_radius = 0.35;
};

// Exactly one of grid, mesh, sphere, torus is set.
struct Domain {
  std::optional<GridSpec> grid;
  std::string mesh;  // path as written in the scene (relative to the scene file)
  std::optional<SphereSpec> sphere;
  std::optional<TorusSpec> torus;
  bool is_planar() const { return grid.has_value(); }
};

struct Scene {
  int version = 1;
  std::string description;  // free text (tvf addition)
  Domain domain;
  TimeSampling time;
  Generator generator = Generator::basis;
  SolverSettings solver;
  double falloff = 8.0;  // d̂: the basis fields decay as exp(−d̂·‖x − p‖² / diam²)
  std::vector<Element> elements;
  std::vector<Keyframe> keyframes;
  std::optional<Deform> deform;  // set when the scene has a deform block
  std::vector<Edit> edits;       // the scene's edits, in order (scene/edits.h)
  // "incompressible" (tvf addition): when set, every frame is projected onto the
  // divergence-free fields after the generator and the edits (solve/hodge_projection.h),
  // with this boundary condition.
  std::optional<FluxBoundary> incompressible;

  // Where the scene came from: used to resolve relative paths and to name the file in
  // error messages. Empty for scenes built in code.
  std::string source_path;
  std::string label() const { return source_path.empty() ? std::string("scene") : source_path; }
  // The mesh path resolved against the scene file's folder.
  std::string resolved_mesh_path() const;
  // Any path written in the scene (mesh, key-frame field files) resolved against the
  // scene file's folder; absolute paths, and every path of a scene built in code, are
  // returned unchanged.
  std::string resolve_path(const std::string& path) const;
};

// Names used in the scene format (exact strings of DESIGN §10).
const char* to_string(SingularType t);
const char* to_string(BifurcationType t);
const char* to_string(Generator g);
const char* to_string(Weights w);
const char* to_string(SolverMethod m);
const char* to_string(KeyframeTopology k);
std::optional<SingularType> singular_type_from_string(const std::string& s);
std::optional<BifurcationType> bifurcation_type_from_string(const std::string& s);
std::optional<Generator> generator_from_string(const std::string& s);
std::optional<Weights> weights_from_string(const std::string& s);

}  // namespace tvf
