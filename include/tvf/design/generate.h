#pragma once
// Generating the field of a scene (DESIGN §5). generate() dispatches on scene.generator.
// Generators: "basis" (basis field summation, paper §5.2, eq. 8), "constrained" (paper
// §5.3), "spacetime" (paper §6.1) and "deform" (paper §7). The scene's edits are then
// applied in order (DESIGN §7, tvf/edit/field_editor.h), and last, when the scene says
// "incompressible", every frame is projected onto the divergence-free fields
// (tvf/solve/hodge_projection.h): generator → edits → projection, so the field written is
// divergence-free whatever the edits did.
#include "tvf/design/keyframe_topology.h"
#include "tvf/scene/design_space.h"
#include "tvf/scene/scene.h"
#include "tvf/field/field.h"
#include "tvf/solve/connection_laplacian.h"
#include "tvf/solve/hodge_projection.h"

#include "tvf/core/error.h"

#include <atomic>
#include <functional>
#include <memory>
#include <optional>
#include <span>
#include <string>
#include <vector>

namespace tvf {

// Set-up that generate() keeps between calls when GenerateOptions::cache is set: the
// designer's session re-generates after every change, mostly on the same domain with the
// same solver settings (STYLE 4, factor once, solve many). It holds
// - the connection Laplacian of the domain and solver.weights (constrained, spacetime);
// - the constrained generator's per-frame Dirichlet solvers with their symbolic
//   factorization, one per thread;
// - the space-time solver (its operator, temporal eigenbases, the temporal modes of its
//   last solve and its vectors; tvf/solve/spacetime.h) for time.frames and
//   solver.temporal_weight;
// - the last space-time solution, the first guess of the next space-time solve (warm
//   start: after a small change it is close to the new solution).
// Each part is kept while what it was made from is unchanged (the domain — its mesh, by
// content —, the weights, the frame count, the temporal weight) and rebuilt otherwise.
// A warm solve meets the same tolerance as a cold one (fields agree to it, not bit for bit).
// Not used (yet) by basis, deform, and key frames' static solves. One call at a time.
class GenerateCache {
public:
  GenerateCache();
  ~GenerateCache();
  GenerateCache(const GenerateCache&) = delete;
  GenerateCache& operator=(const GenerateCache&) = delete;
  void clear();  // forget everything (the next generate() builds from scratch)
  // Solves that started from the last solution instead of the linear-in-time guess,
  // generations that reused a kept Laplacian, and key frames whose designed field was
  // kept (the same elements, streamlines, falloff and region radius), since construction.
  int warm_starts() const;
  int reused_laplacians() const;
  int reused_keyframes() const;

  struct State;  // private to generate.cpp
  State& state() const { return *state_; }

private:
  std::unique_ptr<State> state_;
};

struct GenerateOptions {
  bool parallel = true;  // frames in parallel (TBB)
  // Called as frames complete (from any thread, serialised): frames done, frames total.
  std::function<void(int, int)> progress;
  // Called from the generating thread as it starts a long step that no frame count
  // measures: "planning the topology between key frames (interval 1 of 2)" (the key-frame
  // topology plan: seconds on a scanned mesh; tvf::Design's solve also says "building the
  // domain" for a new mesh), so that a terminal or the designer says what it waits for
  // before the frames' progress starts.
  std::function<void(const std::string&)> stage;
  // Apply the scene's "incompressible" projection (generate() only). `tvf edit` turns it
  // off to check a new edit on the field that the edit will really act on.
  bool project = true;
  // When set, generation checks it between frames (and before and after whole solves and
  // each edit) and stops with GenerationCancelled once it is true. The designer's server
  // sets it when a newer edit makes the running solve pointless.
  const std::atomic<bool>* cancel = nullptr;
  // When set, the solver set-up and the last space-time solution are kept here between
  // calls (see GenerateCache). Null: everything is built for this call alone.
  GenerateCache* cache = nullptr;
  // The frame a viewer shows (the designer's current frame), made first: generators that
  // solve frame by frame (basis, constrained, deform) make frame `first_frame` before the
  // others and then call first_frame_done with its values (|V|, each in its vertex basis;
  // valid during the call), from the generating thread, while the other frames are still
  // to come. Those values are the final field's frame: generate() does not call it for a
  // scene with edits or an "incompressible" projection, which change frames afterwards.
  // The spacetime generator solves all frames at once and never calls it. −1: none.
  int first_frame = -1;
  std::function<void(int frame, std::span<const cplx> values)> first_frame_done;
};

// Thrown by generate*() when GenerateOptions::cancel became true; no field is returned.
class GenerationCancelled : public Error {
public:
  GenerationCancelled() : Error("generation cancelled") {}
};
// Throws GenerationCancelled when options.cancel is set and true.
void check_cancelled(const GenerateOptions& options);

struct GenerateReport {
  std::vector<std::string> warnings;  // design problems that do not stop generation
  std::vector<std::string> edits;     // one sentence per edit applied (Scene::edits)
  std::string method;                 // the generator and solver used
  double residual = 0.0;              // worst relative residual of the linear solves
  int iterations = 0;                 // iterations of the iterative solve (0 for direct)
  double seconds = 0.0;
  int frames = 0;
  int vertices = 0;
  // Set when the scene's "incompressible" projection ran: divergence per frame before and
  // after it.
  std::optional<IncompressibleReport> incompressible;
  // The spacetime generator with solver.keyframe_topology "matched": what was matched,
  // created and cancelled in each interval between key frames (keyframe_topology.h).
  std::vector<KeyframeIntervalReport> keyframe_intervals;
};

// Field of the scene on `space` (which must be make_design_space(scene)): the generator's
// field with the scene's edits applied in order, then projected onto the divergence-free
// fields when scene.incompressible is set (and options.project). Throws tvf::Error for scenes it cannot
// generate (naming the scene and JSON path), including fields that would not fit in this
// machine's memory and edits that cannot be applied ("scene.json: edits[2]: ...").
Field generate(const DesignSpace& space, const Scene& scene, const GenerateOptions& options = {},
               GenerateReport* report = nullptr);
// The generator's field alone, before the scene's edits.
Field generate_unedited(const DesignSpace& space, const Scene& scene, const GenerateOptions& options = {},
                        GenerateReport* report = nullptr);

// Basis field summation: V(x; t) = Σ_i exp(−d‖w_i‖²) V_i(w_i; t), w_i the local
// coordinate of x around element i, d = falloff / diam².
Field generate_basis_sum(const DesignSpace& space, const Scene& scene,
                         const GenerateOptions& options = {}, GenerateReport* report = nullptr);

// Constrained optimization per frame (paper §5.3, DESIGN §5.2): the vertices within
// solver.region_radius of each active element (geodesic distance on surfaces; at least the
// element's face and its corners' neighbours; a bifurcation's region covers 2·scale) take
// that element's own basis field; every other vertex solves L z = 0 with the connection
// Laplacian of solver.weights. Frames are solved in parallel; the symbolic factorization
// is shared by all frames.
Field generate_constrained(const DesignSpace& space, const Scene& scene,
                           const GenerateOptions& options = {}, GenerateReport* report = nullptr);

// Spatio-temporal optimization (paper §6.1, eq. 10; DESIGN §5.3): all frames in one
// solve. Key frames (keyframes.h) hold whole frames fixed; element regions (as in the
// constrained generator) hold vertices at the other frames, so key frames and elements
// combine; everything else minimises the spatial smoothness energy plus
// solver.temporal_weight times the temporal one. Needs cotan or uniform weights.
Field generate_spacetime(const DesignSpace& space, const Scene& scene,
                         const GenerateOptions& options = {}, GenerateReport* report = nullptr);

// The spatio-temporal system of a scene before it is solved: the connection Laplacian
// and which entries (frame-major, frames × |V|) are fixed, to what. generate_spacetime()
// solves it with SpaceTimeSolver; benchmarks and edits reuse it.
struct SpaceTimeProblem {
  ConnectionLaplacian laplacian;
  std::vector<char> fixed;
  std::vector<cplx> values;
};
SpaceTimeProblem spacetime_problem(const DesignSpace& space, const Scene& scene,
                                   const GenerateOptions& options = {});

// Time-varying transformation (paper §7, DESIGN §5.4): V(t) = M(t) V(t0), V(t0) the
// static constrained design of deform.base's elements, M(t) from deform.matrix keys
// (linear from the identity) or deform.transform keys (sx, sy, θ linear). With
// deform.streamlines, representative streamlines traced in V(t0) are moved by keyed
// similarity transforms (streamline_deform.h: on surfaces in the log-map chart around
// each seed), and each frame is the constrained solve of the moved streamlines' tangents
// plus the base elements' regions (transformed by M(t)). On surfaces M acts in each
// vertex's tangent basis.
Field generate_deform(const DesignSpace& space, const Scene& scene,
                      const GenerateOptions& options = {}, GenerateReport* report = nullptr);

// The deform generator's parts, for checking a deformed design against its field: the
// base design (the scene with deform.base's elements, constrained, without key frames and
// edits) and M(t) (the identity without keys). deform_base_scene needs a scene with a
// deform block.
Scene deform_base_scene(const Scene& scene);
Mat2 deform_matrix(const Scene& scene, double t);

// Checks that need the scene only (no mesh): singular paths that begin or end inside
// the time range without a bifurcation there (DESIGN §4). One warning per problem.
std::vector<std::string> design_warnings(const Scene& scene);

// A template element (a bifurcation or Hopf template) whose point holds more Gaussian
// curvature than this within half its scale does not fit the surface there: the disk
// closes round (the end of a tail, a finger), and its cycles and ramps cannot be as
// designed (DesignSpace::curvature_within). generate() warns; the design check's note says so.
inline constexpr double kTemplateMostCurvature = 3.141592653589793;

// How many mean edge lengths a template element must span for the mesh to resolve it (a
// grid's mean edge, its diagonals included, is 1.14 spacings). A Hopf template narrower
// than 6: its cubic term at one edge from the focus is of the order of its linear part near
// t0, so the piecewise-linear focus keeps its old stability for frames past t0 (example 23
// on its 65² grid, the scale swept: every feature found from 6.2 edges, at 5.3 one event
// lost and an extra one, at 1.8 none; on a sphere of subdivisions 4, 0.006 late at 8 edges,
// 0.011 at 6, 0.035 at 3.3 (a tenth of its time scale), lost at 2). A saddle–node template's term is quadratic: example 02's
// pair and event found from 1.5 edges, lost at 1.3. Far below one edge the normal form's
// higher terms (|w|³/scale² for a Hopf template) swamp every other element (scale 1e-12 on
// a 65² grid: |V| up to 5e21). generate() warns; the design check's note says so.
inline double template_resolved_edges(BifurcationType type) { return is_hopf(type) ? 6.0 : 1.5; }

// What only the domain tells of a scene, refused (tvf::Error naming `label`, empty:
// scene.label(), and the JSON place): on a surface, a point of an element, a key frame or
// the deform block farther from the surface than a quarter of its bounding box's diagonal
// (points are moved onto the surface, but one that far off lands wherever the nearest part
// of it happens to be: a scene made for another mesh, another unit); a sketched streakline
// of no length or that meets itself once snapped (check_surface_sketches). generate()
// calls it first; tvf serve and Design::set_scene call it on the domain they have built,
// to refuse a change before taking it. Nothing on planar domains (the reader has tested
// the points there).
void check_scene_on_domain(const DesignSpace& space, const Scene& scene, const std::string& label = "");

// Checks that need the domain: template elements narrower than the mesh resolves
// (template_resolved_edges), or placed where the surface closes round within half their
// scale. One warning per element and problem.
std::vector<std::string> domain_warnings(const DesignSpace& space, const Scene& scene);

}  // namespace tvf
