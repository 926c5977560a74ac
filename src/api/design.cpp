#include "tvf/api/design.h"

#include "tvf/integrate/periodic_orbits.h"

#include "tvf/core/error.h"
#include "tvf/scene/scene_json.h"
#include "tvf/field/field_io.h"
#include "tvf/mesh/mesh_io.h"
#include "tvf/solve/hodge_projection.h"

#include <fmt/format.h>

#include <algorithm>
#include <deque>
#include <filesystem>
#include <utility>

namespace fs = std::filesystem;

namespace tvf {

namespace {

// Two scenes with the same key have the same domain (the session's rule).
std::string domain_key(const Scene& scene) {
  return scene_to_json(scene)["domain"].dump() + "|" + scene.resolved_mesh_path();
}

}  // namespace

// What one scene made: its field (after the projection), the field before the
// projection (incompressible scenes: what an edit acts on), the report and the topology.
struct DesignResult {
  std::shared_ptr<const DesignSpace> space;  // the domain it lives on
  Field field;
  std::optional<Field> unprojected;
  GenerateReport report;
  std::optional<Topology> topology;
  std::optional<PeriodicOrbits> orbits;
};

struct Design::State {
  DesignOptions options;
  std::optional<Scene> scene;
  std::string label;  // names the input in messages when there is no scene
  std::shared_ptr<const DesignSpace> space;
  std::string space_key;
  // A mesh given in code (Design(Scene, Mesh)) and the domain key of the scenes on it.
  std::shared_ptr<const DesignSpace> given_space;
  std::string given_key;
  std::unique_ptr<GenerateCache> cache = std::make_unique<GenerateCache>();
  std::shared_ptr<DesignResult> result;  // of *scene, or null
  std::shared_ptr<DesignResult> last;    // the last result made (field() after a change)

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
    if (scene) {
      undo.push_back({std::move(*scene), result});
      trim(undo);
    }
    redo.clear();
    scene = std::move(next);
    result = std::move(made);
    if (result) last = result;
  }

  const std::shared_ptr<const DesignSpace>& domain() {
    const Scene& s = need_scene();
    const std::string key = domain_key(s);
    if (!space || key != space_key) {
      space = given_space && key == given_key ? given_space : std::shared_ptr<const DesignSpace>(make_design_space(s));
      space_key = key;
    }
    return space;
  }

  DesignResult& made(GenerateOptions go) {
    if (result) return *result;
    const Scene& s = need_scene();
    auto r = std::make_shared<DesignResult>();
    r->space = domain();
    go.cache = cache.get();
    go.parallel = options.parallel;
    // Generator and edits; the projection is done here so that the field before it, the
    // one a new edit acts on, is kept (generate()'s last step, as generate.cpp does it).
    go.project = false;
    r->field = tvf::generate(*r->space, s, go, &r->report);
    if (s.incompressible) {
      check_cancelled(go);
      r->unprojected = r->field;
      project(*r, s);
    }
    result = r;
    last = r;
    return *r;
  }

  // The scene's "incompressible" projection of r.field, reported in r.report.
  void project(DesignResult& r, const Scene& s) const {
    IncompressibleOptions io;
    io.boundary = *s.incompressible;
    io.parallel = options.parallel;
    IncompressibleReport report = make_incompressible(r.space->bundle(), r.field, io);
    r.report.seconds += report.seconds;
    r.report.incompressible = std::move(report);
  }

  // The result of the scene (made if needed), or without a scene the field read.
  DesignResult& current() {
    if (result) return *result;
    if (scene) return made({});
    TVF_CHECK(last != nullptr, "a Design without a scene holds the field it read");
    return *last;
  }

  Topology& topology() {
    DesignResult& r = current();
    if (!r.topology) {
      TopologyOptions to;
      to.parallel = options.parallel;
      r.topology = analyze_topology(r.space->bundle(), r.field, to);
    }
    return *r.topology;
  }

  PeriodicOrbits& orbits() {
    Topology& topo = topology();
    DesignResult& r = current();
    if (!r.orbits) r.orbits = find_periodic_orbits(r.space->bundle(), r.field, topo);
    return *r.orbits;
  }
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
  set_scene(scene_from_json(scene, label, source));
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
  return check_design(*s_->scene, *r.space, r.field, topology, options);
}

EditReport Design::edit(const nlohmann::json& entry, GenerateOptions options) {
  const Scene& scene = s_->need_scene();
  // The new scene, validated as a whole (JSON paths name the new entry).
  nlohmann::json j = scene_to_json(scene);
  j["edits"].push_back(entry);
  Scene edited = scene_from_json(j, scene.label(), scene.source_path);
  const Edit e = edited.edits.back();

  // The edit acts on the field the scene makes now, before its projection.
  DesignResult& now = s_->made(options);
  if (scene.incompressible && !now.unprojected) {
    // Read from a file: the field before the projection is not there; make it.
    GenerateOptions go;
    go.parallel = s_->options.parallel;
    go.cache = s_->cache.get();
    go.project = false;
    now.unprojected = tvf::generate(*now.space, scene, go);
  }
  auto r = std::make_shared<DesignResult>();
  r->space = now.space;
  Field field = scene.incompressible ? *now.unprojected : now.field;
  FieldEditor editor(*now.space, edit_settings(scene));
  EditReport report;
  try {
    report = editor.apply(field, e);
  } catch (const EditRefused& refused) {
    throw Error(fmt::format("{}: refused to {}: {}; the scene is unchanged", scene.label(), describe(e),
                            refused.what()));
  }
  r->report = now.report;
  r->report.edits.push_back(report.summary);
  r->field = std::move(field);
  if (scene.incompressible) {
    r->unprojected = r->field;
    s_->project(*r, scene);
  }
  s_->commit(std::move(edited), std::move(r));
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
