#pragma once
// The library's entry point (issue 18, STYLE 15): one object for a whole design, which
// the command line and the Python module call instead of assembling
// load → domain → generate → analyze by hand, and one-shot functions for scripts
// (generate_scene, analyze_field). geometry-central's HeatMethodDistanceSolver beside
// computeHeatDistance is the model: a stateful object that keeps what it built, and a
// plain function.
//
// A Design holds
// - the scene (the whole design, edits included; DESIGN §10), with an undo/redo history;
// - the domain built from it (DesignSpace: mesh, tangent bundle, log map), kept while the
//   scene's domain is unchanged;
// - the solver set-up kept between generations (GenerateCache: Laplacian, factorizations,
//   the space-time solver and its last solution, so a re-solve after a small change
//   starts warm);
// - the field the current scene makes, its generation report and, once asked for, its
//   topology (analysis/topology.h).
// Everything is computed when first asked for and kept until the scene changes. A
// Design is used from one thread at a time; GenerateOptions::cancel (set from another
// thread) stops a running generation, which then leaves the Design as it was.
//
// Bad input throws tvf::Error with the sentence the command line prints (the file and
// the JSON path); a refused edit or a cancelled generation changes nothing.
#include "tvf/analysis/topology.h"
#include "tvf/design/design_check.h"
#include "tvf/integrate/periodic_orbits.h"
#include "tvf/scene/design_space.h"
#include "tvf/design/generate.h"
#include "tvf/design/outputs.h"
#include "tvf/scene/scene.h"
#include "tvf/scene/edits.h"
#include "tvf/edit/field_editor.h"
#include "tvf/field/field.h"

#include <nlohmann/json.hpp>

#include <filesystem>
#include <functional>
#include <memory>
#include <optional>
#include <string>
#include <vector>

namespace tvf {

struct DesignOptions {
  bool parallel = true;  // frames in parallel (generation, analysis, projection)
  int history = 200;     // undo steps kept
  // Undo steps that keep their field too (undo/redo then need no regeneration); older
  // steps keep only their scene. A field costs 16 bytes per vertex and frame.
  int kept_fields = 4;
  // Called with the scene about to become the current one, before anything changes
  // (set_scene, edit, undo, redo, adopt of an edit): an exception from it leaves the
  // Design as it was. tvf serve's session saves the scene here, so that a change that
  // cannot be saved is not made.
  std::function<void(const Scene&)> before_change;
};

// The solver set-up a Design keeps between generations and the lock its Solves take.
struct DesignSolverCache;

// What one scene made, complete once handed out: its field (after the scene's
// "incompressible" projection), the field before the projection (incompressible scenes:
// what a new edit acts on), the generation report and the analysis (computed when first
// asked for, or by the Solve/EditJob that made it with `analyze`). Shared: a reader on
// another thread keeps it, unchanged, while the Design moves on (tvf serve's session).
struct DesignResult {
  std::shared_ptr<const DesignSpace> space;  // the domain it lives on
  Field field;
  std::optional<Field> unprojected;
  GenerateReport report;
  std::optional<Topology> topology;
  std::optional<PeriodicOrbits> orbits;
};

class Design {
public:
  // A scene built in code or read by scene_json.h. Nothing is built yet.
  explicit Design(Scene scene, DesignOptions options = {});
  // A scene on a mesh made in code (vertices and faces from a script: the Python module's
  // vertices=/faces=). The Mesh constructor has checked it as a mesh file is checked
  // (mesh_validate.h; nothing repaired). The scene's domain becomes {"mesh":
  // mesh.source()}, and every scene of this design with that domain (set_scene, undo)
  // lives on this mesh; a scene with another domain builds its own. Throws tvf::Error
  // when the field would not fit in memory (check_field_memory).
  Design(Scene scene, Mesh mesh, DesignOptions options = {});
  // A scene file, or a folder written by `tvf generate` (or its field.tvff). A folder's
  // field is read, not regenerated, and its scene (DIR/scene.json, else the copy inside
  // the field file) becomes the design's scene; a field file without any scene gives a
  // Design that can analyze and export but not generate or edit. Throws tvf::Error
  // naming `path` for a missing or invalid input.
  static Design open(const std::string& path, DesignOptions options = {});
  ~Design();
  Design(Design&&) noexcept;
  Design& operator=(Design&&) noexcept;

  bool has_scene() const;
  // The current scene. Throws tvf::Error when the Design was opened from a field file
  // without a scene.
  const Scene& scene() const;
  // Replaces the scene (recorded in the history; the field is made again when next asked
  // for; the domain is kept when the new scene's domain is the same).
  void set_scene(Scene scene);
  // The same from scene JSON, validated as a file would be (errors name `label` and the
  // JSON path), and on a domain already built what only it tells refused too
  // (check_scene_on_domain: a point far off the surface, a sketched streakline that meets
  // itself on it), as generate() would (the Design unchanged). Mesh paths resolve
  // against the current scene's file.
  void set_scene(const nlohmann::json& scene, const std::string& label = "scene");
  // Writes the scene (atomically, scene_json.h's save_scene) to `path`, or to the file it
  // was read from when `path` is empty. A mesh given to the constructor (as arrays) is
  // written beside it as NAME.mesh.off, which the saved scene's domain names.
  void save(const std::string& path = "") const;

  // The domain of the scene, built on first use (make_design_space).
  const DesignSpace& space();
  // The domain of `scene`'s domain when the Design has it built (the current scene's, or a
  // mesh given in code), else null: what a client needs to test a change that only the
  // domain can tell (check_scene_on_domain) before taking it, without building anything.
  std::shared_ptr<const DesignSpace> space_for(const Scene& scene) const;

  // The field of the current scene: generated (generator, edits, projection; generate.h)
  // unless it is already there. options.cache is the Design's own; options.parallel is
  // taken from DesignOptions. Throws GenerationCancelled when options.cancel became true
  // (the Design is then as it was).
  const Field& generate(GenerateOptions options = {});
  bool has_field() const;  // the current scene's field is there (generate() returns at once)
  // The field made last; throws tvf::Error when there is none.
  const Field& field() const;
  // The same field and the domain it lives on, shared: they stay valid, unchanged, after
  // the Design moves on (how the Python module hands out numpy views without copies).
  std::shared_ptr<const Field> field_ptr() const;
  std::shared_ptr<const DesignSpace> field_space() const;
  // What the last generation reported (empty for a field read from a file).
  const GenerateReport& report() const;

  // The topology of the field (singularities, paths, bifurcations, coherence), generating
  // the field first if needed.
  const Topology& analyze();
  // The periodic orbits and Hopf events of the field (integrate/periodic_orbits.h, DESIGN §12).
  const PeriodicOrbits& periodic_orbits();
  // The analysis JSON of DESIGN §9 (topology_to_json of analyze()) with the periodic
  // orbits and Hopf events of DESIGN §12.
  nlohmann::json analysis_json();
  // The design check (design_check.h) of the field against the scene; none without a scene.
  std::optional<DesignCheck> check();

  // Appends an edit to the scene's `edits` (DESIGN §7) after applying it to the current
  // field (generated first if needed), exactly as `tvf edit` does: the edit acts on the
  // field before the scene's "incompressible" projection, which is then applied again. A
  // refused edit throws tvf::Error ("scene.json: refused to cancel …: why; the scene is
  // unchanged") and changes nothing. The edited field is the current field at once.
  // `options` (progress, cancel) serve the generation the edit needs when the field is not
  // there yet; the entry is validated before it.
  EditReport edit(const Edit& edit, GenerateOptions options = {});
  // The same from one JSON entry ({"op": "cancel", "frame": 40, "pair": [[x, y], [x, y]]},
  // …): validated with the scene, errors naming "edits[k]".
  EditReport edit(const nlohmann::json& entry, GenerateOptions options = {});
  bool can_undo() const;
  bool can_redo() const;
  // Steps back to the scene before the last change (set_scene or edit), and its field when
  // kept. Throws tvf::Error when there is nothing to undo / redo.
  void undo();
  void redo();

  // Writes the outputs of `tvf generate` (outputs.h) into `dir`, generating first if needed.
  std::vector<std::filesystem::path> write_outputs(const std::filesystem::path& dir, OutputOptions options = {});

  // --- The same steps for a caller with threads (tvf serve's session) ---
  // The Design stays single-threaded: the caller serialises its calls with a lock of its
  // own. A Solve or an EditJob is prepared under that lock, run without it (a solve takes
  // seconds; status, reads and other changes go on meanwhile) and adopted under it again,
  // which makes it the Design's only when the Design is still at the revision it was
  // prepared on. generate() and edit() are these three steps in a row.

  // The revision of the scene: 1 for the first scene, one more with every change
  // (set_scene, edit, undo, redo, an adopted EditJob).
  long long revision() const;
  // The result of the current scene when it is there (null otherwise), and the last one
  // made or adopted (null before the first).
  std::shared_ptr<const DesignResult> result() const;
  std::shared_ptr<const DesignResult> last_result() const;

  // A generation of the scene at one revision.
  class Solve {
  public:
    long long revision() const { return revision_; }
    const Scene& scene() const { return scene_; }
    // Builds the domain unless the Design had it, generates (options.progress and
    // options.cancel; the cache and `parallel` are the Design's) and, with `analyze`, finds
    // the topology and periodic orbits. Needs no lock; one Solve runs at a time per Design
    // (a second one waits: they share the solver set-up). Throws GenerationCancelled or
    // tvf::Error as generate() does.
    void run(GenerateOptions options = {}, bool analyze = false);
    // What run() made (null before).
    std::shared_ptr<const DesignResult> result() const { return made_; }
    // The domain it generates on: the Design's when it had it, else built by run() (null
    // until then; set before the generation starts, so GenerateOptions' callbacks see it).
    std::shared_ptr<const DesignSpace> space() const { return space_; }

  private:
    friend class Design;
    long long revision_ = 0;
    Scene scene_;
    std::shared_ptr<const DesignSpace> space_;  // null: built by run()
    std::shared_ptr<const DesignSpace> given_;  // the mesh given in code, for its domain
    std::string space_key_, given_key_;
    std::shared_ptr<DesignSolverCache> shared_;  // the Design's solver cache and its lock
    bool parallel_ = true;
    std::shared_ptr<DesignResult> made_;
  };
  // The generation of the current scene (throws tvf::Error without a scene).
  Solve prepare_solve() const;
  // The generation of `next`, the scene that a change about to be made will make current
  // (revision() + 1), so that it can run while the change is still being saved (tvf
  // serve's session starts the solve before the scene file is durable). adopt() takes its
  // result only once set_scene(next) has made that revision, and the caller makes sure
  // that no other change comes between (the session serialises its changes).
  Solve prepare_solve(Scene next) const;
  // Makes solve's result the current scene's when the Design is still at its revision
  // (true), and keeps the domain it built; false (nothing changes but the kept domain)
  // when a change came since.
  bool adopt(Solve&& solve);

  // One edit of the scene at one revision: the scene with the entry appended to its edits
  // (validated with the scene, errors naming `label` and "edits[k]"; a missing label is
  // the scene's), applied later to the field of that revision.
  class EditJob {
  public:
    long long revision() const { return revision_; }
    const Scene& scene() const { return scene_; }  // with the new edit
    const Edit& edit() const { return scene_.edits.back(); }
    // Applies the edit to `base`, the result of revision() (Design::result() then, or one
    // the caller kept): on the field before the scene's projection, which is then done
    // again, exactly as Design::edit; with `analyze`, the topology and periodic orbits of
    // the edited field too. Needs no lock. A refused edit throws EditRefused (Design::edit
    // turns it into its tvf::Error sentence), and nothing changes.
    EditReport run(const std::shared_ptr<const DesignResult>& base, bool analyze = false);
    std::shared_ptr<const DesignResult> result() const { return made_; }

  private:
    friend class Design;
    long long revision_ = 0;
    Scene base_scene_, scene_;
    bool parallel_ = true;
    std::shared_ptr<DesignResult> made_;
  };
  EditJob prepare_edit(const nlohmann::json& entry, const std::string& label = "") const;
  // Commits the edited scene with its field (recorded in the history, one revision more)
  // when the Design is still at the job's revision and the job has run (true); false and
  // nothing changes otherwise. DesignOptions::before_change is called first.
  bool adopt(EditJob&& job);

private:
  struct State;
  std::unique_ptr<State> s_;
  explicit Design(std::unique_ptr<State> state);
};

// A field with the domain it lives on: what the one-shot functions return.
struct GeneratedField {
  std::shared_ptr<const DesignSpace> space;
  Field field;
  GenerateReport report;
};

// One-shot: the field of a scene (make_design_space, then generate()).
GeneratedField generate_scene(const Scene& scene, const GenerateOptions& options = {});
// One-shot: the topology of a field on its domain.
Topology analyze_field(const DesignSpace& space, const Field& field, const TopologyOptions& options = {});
// One-shot: the whole analysis JSON of a field (DESIGN §9, with §12's periodic orbits and
// Hopf events), as `tvf analyze` writes it.
nlohmann::json analysis_json_of(const DesignSpace& space, const Field& field);

}  // namespace tvf
