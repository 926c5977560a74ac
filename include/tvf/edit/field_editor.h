#pragma once
// Applying topological edits to a field (DESIGN §7, paper §8). Every edit works on a copy
// and replaces the field only when it succeeds, so a refused edit leaves the design as it
// was. All solves are serial and direct or CG from a fixed start, so applying the same
// edits to the same field gives the same values bit for bit (replay from the scene).
//
// - cancel: the pair nearest to the two positions at the frame (find_singularities) is
//   cancelled by a grown region (region_solve.h); the frame becomes a key frame and the
//   region's interior vertices in the frames of the time window around it are re-solved
//   by the spatio-temporal optimization (SpaceTimeSolver, the frames next to the window and
//   everything outside the region held fixed, warm start from the current field).
// - remove_bifurcation: the bifurcation nearest to (x, t) (analyze_topology). An isolated
//   one — both of its singularities' tracks end on the time boundary or the domain
//   boundary, or the two meet again in a second bifurcation (a loop) — is removed by
//   cancelling the pair at every frame of its life span (key frames; a second pass redoes
//   every frame over the union of the regions so consecutive frames get consecutive fills)
//   and smoothing the window beyond it. The three-path case of paper §8.2 — one track ends
//   in a second bifurcation with a third singularity, whose track runs on to the time or
//   domain boundary — is collapsed to one singularity: at each frame of the overlap the
//   middle singularity is cancelled with the nearer outer one, and (planar domains) the
//   survivor is moved onto the straight line from its first to its last place in the
//   overlap (its neighbourhood pasted there, the region between re-solved), so one path
//   runs from one outer track to the other. On surfaces it passes from one outer track
//   to the other between two frames: one path, with a jump.
// - move_bifurcation: the bifurcation's neighbourhood is moved to the new place and time.
//   Over the window after the new time (before it for a cancellation) each frame gets the
//   pair of the original field at a source time that runs from the old bifurcation time to
//   the window's end, translated by an offset that shrinks from the full move to zero, so
//   the moved pair joins its original track at the window's end; where the original pair
//   no longer belongs, it is cancelled. The translation happens in local coordinates
//   around the old bifurcation: the plane's own on planar domains, the log map on surfaces
//   (the move is log_p(new place); a vertex x of the moved neighbourhood takes the field at
//   the surface point whose log coordinates are log_p(x) − offset, found by
//   ChartInverse, its vector carried in the chart's frame). The edited frames are key
//   frames; the frames beyond are smoothed.
// - smooth: min Σ_j z_jᴴ L z_j + b Σ |Δ_t z|² + μ Σ_j Σ_i d_i |z_ij − z⁰_ij|² over the
//   whole field, μ = 1 / (4·strength)² (strength 1 smooths over about 4 edges in space and
//   4·√b frames in time). The pull towards the current field z⁰ is written as Dirichlet
//   ghost vertices (one per vertex, joined to it with weight μ·d_i and fixed at z⁰), so the
//   solve is the SpaceTimeSolver's own.
#include "tvf/analysis/topology.h"
#include "tvf/core/error.h"
#include "tvf/scene/design_space.h"
#include "tvf/scene/edits.h"
#include "tvf/edit/region_solve.h"
#include "tvf/field/field.h"
#include "tvf/solve/connection_laplacian.h"

#include <map>
#include <string>
#include <vector>

namespace tvf {

// An edit that cannot be applied to this field. The message is one sentence without the
// file name (apply_scene_edits adds "scene.json: edits[i]: ").
class EditRefused : public Error {
public:
  using Error::Error;
};

struct EditSettings {
  LaplacianWeights weights = LaplacianWeights::cotan;  // region solves; the space-time
                                                       // solves use cotan for mean_value
  double temporal_weight = 30.0;
  double tolerance = 1e-10;
  RegionOptions region;
};

// What an edit did (STYLE 5).
struct EditReport {
  std::string summary;             // one sentence
  std::vector<int> key_frames;     // frames edited and then held fixed
  int window_first = -1;           // frames re-solved by the space-time solve
  int window_last = -1;
  int region_faces = 0;            // largest region used at a key frame
  int growths = 0;                 // most rings a region grew
  int iterations = 0;              // CG iterations of the space-time solves
  double residual = 0.0;           // worst relative residual of those solves
};

class FieldEditor {
public:
  // `space` must outlive the editor and be the domain of the fields passed to apply().
  explicit FieldEditor(const DesignSpace& space, EditSettings settings = {});
  FieldEditor(const FieldEditor&) = delete;  // the region solver refers to laplacian_
  FieldEditor& operator=(const FieldEditor&) = delete;

  // Applies one edit to `field` (in place). Throws EditRefused when the edit cannot be
  // applied; `field` is then unchanged.
  EditReport apply(Field& field, const Edit& edit);

  EditReport cancel(Field& field, const CancelEdit& edit);
  EditReport remove_bifurcation(Field& field, const RemoveBifurcationEdit& edit);
  EditReport move_bifurcation(Field& field, const MoveBifurcationEdit& edit);
  EditReport smooth(Field& field, const SmoothEdit& edit);

private:
  struct Window;
  void resolve_window(Field& field, const Window& window, EditReport& report) const;
  void move_survivor(Field& out, const Topology& topo, const std::map<int, const std::vector<char>*>& survivor,
                     std::map<int, std::vector<char>>& interiors, EditReport& report);
  void smooth_around(Field& field, const std::map<int, std::vector<char>>& key_free,
                     const std::map<int, std::vector<char>>& flank_free, int w, EditReport& report) const;

  const DesignSpace& space_;
  EditSettings settings_;
  ConnectionLaplacian laplacian_;     // settings.weights
  ConnectionLaplacian st_laplacian_;  // Hermitian weights for the space-time solves
  RegionSolver region_;
};

// The solver settings of a scene as edit settings.
EditSettings edit_settings(const Scene& scene);

// Applies the scene's edits in order to `field` (generated from `scene` on `space`).
// A refused edit throws tvf::Error "scene.json: edits[i]: <why>", leaving `field` as the
// edits before it made it.
std::vector<EditReport> apply_scene_edits(const DesignSpace& space, const Scene& scene, Field& field);

}  // namespace tvf
