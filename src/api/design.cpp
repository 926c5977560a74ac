#include "tvf/api/design.h"

#include "tvf/integrate/periodic_orbits.h"

#include "tvf/core/error.h"
#include "tvf/design/keyframe_topology.h"
#include "tvf/scene/scene_json.h"
#include "tvf/field/field_io.h"
#include "tvf/mesh/mesh_io.h"
#include "tvf/solve/hodge_projection.h"

#include <fmt/format.h>

#include <algorithm>
#include <deque>
#include <filesystem>
#include <fstream>
#include <mutex>
#include <utility>

namespace fs = std::filesystem;

namespace tvf {

namespace {

// Two scenes with the same key have the same domain (the session's rule).
std::string domain_key(const Scene& scene) {
  return scene_to_json(scene)["domain"].dump() + "|" + scene.resolved_mesh_path();
}

}  // namespace

struct DesignSolverCache {
  std::mutex mutex;  // one Solve at a time uses the cache
  GenerateCache cache;
};

namespace {

// The scene's "incompressible" projection of r.field, reported in r.report.
void project_result(DesignResult& r, const Scene& s, bool parallel) {
  IncompressibleOptions io;
  io.boundary = *s.incompressible;
  io.parallel = parallel;
  IncompressibleReport report = make_incompressible(r.space->bundle(), r.field, io);
  r.report.seconds += report.seconds;
  r.report.incompressible = std::move(report);
}

Topology& topology_of(DesignResult& r, bool parallel) {
  if (!r.topology) {
    TopologyOptions to;
    to.parallel = parallel;
    r.topology = analyze_topology(r.space->bundle(), r.field, to);
  }
  return *r.topology;
}

PeriodicOrbits& orbits_of(DesignResult& r, bool parallel) {
  Topology& topology = topology_of(r, parallel);
  if (!r.orbits) {
    PeriodicOrbitOptions po;
    po.parallel = parallel;
    r.orbits = find_periodic_orbits(r.space->bundle(), r.field, topology, po);
  }
  return *r.orbits;
}

}  // namespace

struct Design::State {
  DesignOptions options;
  std::optional<Scene> scene;
  std::string label;  // names the input in messages when there is no scene
  std::shared_ptr<const DesignSpace> space;
  std::string space_key;
  // A mesh given in code (Design(Scene, Mesh)) and the domain key of the scenes on it.
  std::shared_ptr<const DesignSpace> given_space;
  std::string given_key;
  std::shared_ptr<DesignSolverCache> solver = std::make_shared<DesignSolverCache>();
  std::shared_ptr<DesignResult> result;  // of *scene, or null
  std::shared_ptr<DesignResult> last;    // the last result made (field() after a change)
  long long revision = 1;

  struct Step {
    Scene scene;
    std::shared_ptr<DesignResult> result;  // dropped beyond options.kept_fields
  };
  std::deque<Step> undo, redo;

  const Scene& need_scene() const {
    if (!scene)
      throw Error(fmt::format("{}: no scene with this field (no scene.json beside it, none stored in it): "
                              "it can be analysed and exported, not generated or edited",
                              label));
    return *scene;
  }

  void trim(std::deque<Step>& steps) const {
    while (static_cast<int>(steps.size()) > std::max(options.history, 0)) steps.pop_front();
    const int keep = std::max(options.kept_fields, 0);
    for (int i = 0; i + keep < static_cast<int>(steps.size()); ++i) steps[static_cast<size_t>(i)].result.reset();
  }

  // Makes `next` the scene (with its result, when known), recording the old one.
  void commit(Scene next, std::shared_ptr<DesignResult> made) {
    if (options.before_change) options.before_change(next);
    if (scene) {
      undo.push_back({std::move(*scene), result});
      trim(undo);
    }
    redo.clear();
    scene = std::move(next);
    result = std::move(made);
    if (result) last = result;
    ++revision;
  }

  // The domain already built for domain key `key` (the last one built, or a mesh given in
  // code), or null.
  std::shared_ptr<const DesignSpace> built(const std::string& key) const {
    if (space && key == space_key) return space;
    if (given_space && key == given_key) return given_space;
    return nullptr;
  }

  const std::shared_ptr<const DesignSpace>& domain() {
    const Scene& s = need_scene();
    const std::string key = domain_key(s);
    if (!space || key != space_key) {
      auto have = built(key);
      space = have ? std::move(have) : std::shared_ptr<const DesignSpace>(make_design_space(s));
      space_key = key;
    }
    return space;
  }

  Design::Solve prepare_solve() const {
    Design::Solve job;
    job.scene_ = need_scene();
    job.revision_ = revision;
    job.space_key_ = domain_key(job.scene_);
    if (space && space_key == job.space_key_) job.space_ = space;
    job.given_ = given_space;
    job.given_key_ = given_key;
    job.shared_ = solver;
    job.parallel_ = options.parallel;
    return job;
  }

  bool adopt(Design::Solve& job) {
    TVF_CHECK(job.made_ != nullptr, "a Solve is adopted after it ran");
    // The domain it built serves the current scene when that has the same domain.
    if (scene && job.space_ && job.space_ != space && domain_key(*scene) == job.space_key_) {
      space = job.space_;
      space_key = job.space_key_;
    }
    if (!scene || job.revision_ != revision) return false;
    result = job.made_;
    last = result;
    return true;
  }

  DesignResult& made(GenerateOptions go) {
    if (result) return *result;
    Design::Solve job = prepare_solve();
    job.run(std::move(go), false);
    adopt(job);
    return *result;
  }

  // The result of the scene (made if needed), or without a scene the field read.
  DesignResult& current() {
    if (result) return *result;
    if (scene) return made({});
    TVF_CHECK(last != nullptr, "a Design without a scene holds the field it read");
    return *last;
  }

  Topology& topology() { return topology_of(current(), options.parallel); }
  PeriodicOrbits& orbits() { return orbits_of(current(), options.parallel); }
};

Design::Design(std::unique_ptr<State> state) : s_(std::move(state)) {}

Design::Design(Scene scene, DesignOptions options) : s_(std::make_unique<State>()) {
  s_->options = options;
  s_->label = scene.label();
  s_->scene = std::move(scene);
}

Design::Design(Scene scene, Mesh mesh, DesignOptions options) : s_(std::make_unique<State>()) {
  s_->options = options;
  s_->label = scene.label();
  check_field_memory(scene, mesh.num_vertices());
  scene.domain = Domain{};
  scene.domain.mesh = mesh.source();
  s_->given_key = domain_key(scene);
  s_->given_space = std::make_shared<DesignSpace>(std::move(mesh));
  s_->space = s_->given_space;
  s_->space_key = s_->given_key;
  s_->scene = std::move(scene);
}

namespace {

// The copy of the scene inside a field file, written with the field: one that does not
// describe this field (a spliced or corrupt file) is refused rather than checked against
// the wrong design.
Scene embedded_scene(const FieldFile& file, const std::string& label, const std::string& source) {
  Scene scene = scene_from_json(file.scene, label, source);
  const TimeSampling& t = file.field.time();
  if (scene.time.t0 != t.t0 || scene.time.t1 != t.t1 || scene.time.frames != t.frames)
    throw Error(fmt::format("{}: time: the scene's {} frames over [{}, {}] do not match the field's {} frames over "
                            "[{}, {}] (the file is corrupt)",
                            label, scene.time.frames, scene.time.t0, scene.time.t1, t.frames, t.t0, t.t1));
  if (const auto& g = scene.domain.grid) {
    if (!file.mesh.is_planar_xy() ||
        static_cast<long long>(g->nx) * g->ny != static_cast<long long>(file.mesh.num_vertices()))
      throw Error(fmt::format("{}: domain.grid: a grid of {} × {} vertices does not match the field's mesh of {} "
                              "vertices (the file is corrupt)",
                              label, g->nx, g->ny, file.mesh.num_vertices()));
  } else if ((scene.domain.sphere || scene.domain.torus) && file.mesh.is_planar_xy()) {
    throw Error(fmt::format("{}: domain: the scene's surface does not match the field's planar mesh (the file is "
                            "corrupt)",
                            label));
  }
  return scene;
}

}  // namespace

Design Design::open(const std::string& path, DesignOptions options) {
  const fs::path input(path);
  std::error_code ec;
  if (!fs::exists(input, ec))
    throw Error(fmt::format("{}: no such file or folder (give a folder written by `tvf generate`, "
                            "its field.tvff, or a scene file)",
                            path));
  if (!fs::is_directory(input, ec) && input.extension() != ".tvff") return Design(load_scene(path), options);

  const fs::path file = fs::is_directory(input, ec) ? input / "field.tvff" : input;
  if (!fs::exists(file, ec))
    throw Error(fmt::format("{}: no field.tvff in this folder (write one with `tvf generate SCENE -o {}`)", path,
                            path));
  FieldFile ff = load_field_file(file.string());
  auto s = std::make_unique<State>();
  s->options = options;
  s->label = path;
  // The scene that made the field: scene.json beside it, else the copy inside the file.
  const fs::path beside = (fs::is_directory(input, ec) ? input : input.parent_path()) / "scene.json";
  if (fs::exists(beside, ec))
    s->scene = load_scene(beside.string());
  else if (!ff.scene.is_null())
    s->scene = embedded_scene(ff, path + " (its scene)", beside.string());
  // The domain is the file's mesh (a scene's mesh path is relative to where it was
  // written, which need not be beside the field).
  s->space = std::make_shared<DesignSpace>(std::move(ff.mesh));
  if (s->scene) s->space_key = domain_key(*s->scene);
  auto r = std::make_shared<DesignResult>();
  r->space = s->space;
  r->field = std::move(ff.field);
  r->report.frames = r->field.frames();
  r->report.vertices = r->field.num_vertices();
  r->report.method = "read from " + file.string();
  // The key-frame plan of the generation that wrote the folder, for the design check (which
  // else makes it again); a file that does not parse is left to that.
  const fs::path plan = file.parent_path() / "keyframe_topology.json";
  if (fs::exists(plan, ec)) {
    std::ifstream in(plan);
    const nlohmann::json j = nlohmann::json::parse(in, nullptr, false);
    if (auto intervals = keyframe_intervals_from_json(j)) r->report.keyframe_intervals = std::move(*intervals);
  }
  s->result = r;
  s->last = r;
  return Design(std::move(s));
}

Design::~Design() = default;
Design::Design(Design&&) noexcept = default;
Design& Design::operator=(Design&&) noexcept = default;

bool Design::has_scene() const { return s_->scene.has_value(); }
const Scene& Design::scene() const { return s_->need_scene(); }

void Design::set_scene(Scene scene) { s_->commit(std::move(scene), nullptr); }

void Design::set_scene(const nlohmann::json& scene, const std::string& label) {
  const std::string source = s_->scene ? s_->scene->source_path : std::string();
  Scene next = scene_from_json(scene, label, source);
  if (const auto space = space_for(next)) check_scene_on_domain(*space, next, label);
  set_scene(std::move(next));
}

void Design::save(const std::string& path) const {
  const Scene& s = s_->need_scene();
  const std::string target = path.empty() ? s.source_path : path;
  if (target.empty()) throw Error("scene: built in code, so it has no file to save to: give a path");
  if (s_->given_space && domain_key(s) == s_->given_key) {
    // A mesh given as arrays has no file the scene could name: it is written beside the
    // scene (NAME.mesh.off, every double exactly) and the saved scene names it, so that
    // the file loads again on its own.
    const std::filesystem::path scene_path(target);
    const std::string mesh_name = scene_path.stem().string() + ".mesh.off";
    save_mesh(s_->given_space->mesh(), (scene_path.parent_path() / mesh_name).string());
    Scene copy = s;
    copy.domain.mesh = mesh_name;
    save_scene(copy, target);
    return;
  }
  save_scene(s, target);
}

const DesignSpace& Design::space() {
  if (!s_->scene && s_->space) return *s_->space;
  return *s_->domain();
}

std::shared_ptr<const DesignSpace> Design::space_for(const Scene& scene) const {
  return s_->built(domain_key(scene));
}

const Field& Design::generate(GenerateOptions options) { return s_->made(std::move(options)).field; }

bool Design::has_field() const { return s_->result != nullptr; }

const Field& Design::field() const {
  if (!s_->last) throw Error(fmt::format("{}: no field yet (generate it first)", s_->label));
  return s_->last->field;
}

std::shared_ptr<const Field> Design::field_ptr() const {
  field();  // throws when there is none
  return {s_->last, &s_->last->field};
}

std::shared_ptr<const DesignSpace> Design::field_space() const {
  field();
  return s_->last->space;
}

const GenerateReport& Design::report() const {
  static const GenerateReport none;
  return s_->last ? s_->last->report : none;
}

const Topology& Design::analyze() { return s_->topology(); }

const PeriodicOrbits& Design::periodic_orbits() { return s_->orbits(); }

nlohmann::json Design::analysis_json() {
  nlohmann::json analysis = topology_to_json(analyze());
  add_periodic_orbits_to_json(analysis, periodic_orbits());
  return analysis;
}

std::optional<DesignCheck> Design::check() {
  if (!s_->scene) return std::nullopt;
  const Topology& topology = analyze();
  DesignCheckOptions options;
  options.orbits = &periodic_orbits();
  const DesignResult& r = *s_->result;
  if (!r.report.keyframe_intervals.empty()) options.keyframe_intervals = &r.report.keyframe_intervals;
  return check_design(*s_->scene, *r.space, r.field, topology, options);
}

EditReport Design::edit(const nlohmann::json& entry, GenerateOptions options) {
  // The new scene, validated as a whole (JSON paths name the new entry).
  EditJob job = prepare_edit(entry);
  const Scene& scene = job.base_scene_;
  // The edit acts on the field the scene makes now, before its projection.
  DesignResult& now = s_->made(options);
  if (scene.incompressible && !now.unprojected) {
    // Read from a file: the field before the projection is not there; make it.
    GenerateOptions go;
    go.parallel = s_->options.parallel;
    go.cache = &s_->solver->cache;
    go.project = false;
    std::lock_guard lock(s_->solver->mutex);
    now.unprojected = tvf::generate(*now.space, scene, go);
  }
  EditReport report;
  try {
    report = job.run(s_->result, false);
  } catch (const EditRefused& refused) {
    throw Error(fmt::format("{}: refused to {}: {}; the scene is unchanged", scene.label(), describe(job.edit()),
                            refused.what()));
  }
  adopt(std::move(job));
  return report;
}

EditReport Design::edit(const Edit& e, GenerateOptions options) {
  const Scene& scene = s_->need_scene();
  return edit(edit_to_json(e, scene.domain.is_planar()), std::move(options));
}

bool Design::can_undo() const { return !s_->undo.empty(); }
bool Design::can_redo() const { return !s_->redo.empty(); }

void Design::undo() {
  if (s_->undo.empty()) throw Error(fmt::format("{}: nothing to undo", s_->label));
  if (s_->options.before_change) s_->options.before_change(s_->undo.back().scene);
  ++s_->revision;
  State::Step step = std::move(s_->undo.back());
  s_->undo.pop_back();
  s_->redo.push_back({std::move(*s_->scene), s_->result});
  s_->trim(s_->redo);
  s_->scene = std::move(step.scene);
  s_->result = std::move(step.result);
  if (s_->result) s_->last = s_->result;
}

void Design::redo() {
  if (s_->redo.empty()) throw Error(fmt::format("{}: nothing to redo", s_->label));
  if (s_->options.before_change) s_->options.before_change(s_->redo.back().scene);
  ++s_->revision;
  State::Step step = std::move(s_->redo.back());
  s_->redo.pop_back();
  s_->undo.push_back({std::move(*s_->scene), s_->result});
  s_->trim(s_->undo);
  s_->scene = std::move(step.scene);
  s_->result = std::move(step.result);
  if (s_->result) s_->last = s_->result;
}

std::vector<fs::path> Design::write_outputs(const fs::path& dir, OutputOptions options) {
  const Scene& scene = s_->need_scene();
  const DesignResult& r = s_->made({});
  if (r.report.incompressible && !options.incompressible) options.incompressible = &*r.report.incompressible;
  if (!r.report.keyframe_intervals.empty() && !options.keyframe_intervals)
    options.keyframe_intervals = &r.report.keyframe_intervals;
  return write_field_outputs(dir, *r.space, r.field, scene, options);
}

long long Design::revision() const { return s_->revision; }
std::shared_ptr<const DesignResult> Design::result() const { return s_->result; }
std::shared_ptr<const DesignResult> Design::last_result() const { return s_->last; }

Design::Solve Design::prepare_solve() const { return s_->prepare_solve(); }

Design::Solve Design::prepare_solve(Scene next) const {
  s_->need_scene();  // a Design opened from a field file without a scene does not generate
  Solve job = s_->prepare_solve();
  job.scene_ = std::move(next);
  job.revision_ = s_->revision + 1;
  job.space_key_ = domain_key(job.scene_);
  job.space_ = s_->space && s_->space_key == job.space_key_ ? s_->space : nullptr;
  return job;
}

bool Design::adopt(Solve&& solve) { return s_->adopt(solve); }

void Design::Solve::run(GenerateOptions options, bool analyze) {
  TVF_CHECK(shared_ != nullptr, "a Solve comes from Design::prepare_solve");
  std::lock_guard lock(shared_->mutex);
  if (!space_ && given_ && space_key_ == given_key_) space_ = given_;
  if (!space_) {
    // A new domain (seconds for a scanned mesh of 10⁵ vertices: its point locator, charts
    // and connection), said before the frames' progress.
    if (options.stage) options.stage("building the domain");
    space_ = make_design_space(scene_);
  }
  auto r = std::make_shared<DesignResult>();
  r->space = space_;
  options.cache = &shared_->cache;
  options.parallel = parallel_;
  // Generator and edits; the projection is done here so that the field before it, the
  // one a new edit acts on, is kept (generate()'s last step, as generate.cpp does it).
  options.project = false;
  r->field = tvf::generate(*r->space, scene_, options, &r->report);
  // Under mpirun the field may be rank 0's alone (solve/distributed.h): the others project
  // nothing.
  if (scene_.incompressible && r->field.num_vertices() == r->space->mesh().num_vertices()) {
    check_cancelled(options);
    r->unprojected = r->field;
    project_result(*r, scene_, parallel_);
  }
  if (analyze) {
    check_cancelled(options);
    orbits_of(*r, parallel_);
  }
  made_ = std::move(r);
}

Design::EditJob Design::prepare_edit(const nlohmann::json& entry, const std::string& label) const {
  const Scene& scene = s_->need_scene();
  nlohmann::json j = scene_to_json(scene);
  j["edits"].push_back(entry);
  EditJob job;
  job.scene_ = scene_from_json(j, label.empty() ? scene.label() : label, scene.source_path);
  job.base_scene_ = scene;
  job.revision_ = s_->revision;
  job.parallel_ = s_->options.parallel;
  return job;
}

EditReport Design::EditJob::run(const std::shared_ptr<const DesignResult>& base, bool analyze) {
  TVF_CHECK(base != nullptr, "an edit needs the result it acts on");
  const bool incompressible = base_scene_.incompressible.has_value();
  if (incompressible && !base->unprojected)
    throw Error(fmt::format("{}: the field before the scene's projection is not kept with this result, so the edit "
                            "cannot act on it",
                            base_scene_.label()));
  Field field = incompressible ? *base->unprojected : base->field;
  FieldEditor editor(*base->space, edit_settings(base_scene_));
  const EditReport report = editor.apply(field, edit());
  auto r = std::make_shared<DesignResult>();
  r->space = base->space;
  r->report = base->report;
  r->report.edits.push_back(report.summary);
  r->field = std::move(field);
  if (incompressible) {
    r->unprojected = r->field;
    project_result(*r, base_scene_, parallel_);
  }
  if (analyze) orbits_of(*r, parallel_);
  made_ = std::move(r);
  return report;
}

bool Design::adopt(EditJob&& job) {
  if (!job.made_ || !s_->scene || job.revision_ != s_->revision) return false;
  s_->commit(std::move(job.scene_), std::move(job.made_));
  return true;
}

GeneratedField generate_scene(const Scene& scene, const GenerateOptions& options) {
  GeneratedField out;
  out.space = make_design_space(scene);
  out.field = generate(*out.space, scene, options, &out.report);
  return out;
}

Topology analyze_field(const DesignSpace& space, const Field& field, const TopologyOptions& options) {
  return analyze_topology(space.bundle(), field, options);
}

nlohmann::json analysis_json_of(const DesignSpace& space, const Field& field) {
  const Topology topology = analyze_field(space, field);
  nlohmann::json analysis = topology_to_json(topology);
  add_periodic_orbits_to_json(analysis, find_periodic_orbits(space.bundle(), field, topology));
  return analysis;
}

}  // namespace tvf
