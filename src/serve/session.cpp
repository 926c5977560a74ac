#include "tvf/serve/session.h"

#include "tvf/analysis/topology.h"
#include "tvf/core/atomic_output.h"
#include "tvf/scene/design_space.h"
#include "tvf/design/generate.h"
#include "tvf/design/outputs.h"
#include "tvf/scene/scene_json.h"
#include "tvf/design/streamline_deform.h"
#include "tvf/scene/edits.h"
#include "tvf/edit/field_editor.h"
#include "tvf/field/world_vectors.h"
#include "tvf/integrate/periodic_orbits.h"
#include "tvf/render/texture_animation.h"
#include "tvf/render/video.h"

#include <fmt/format.h>

#include <algorithm>
#include <atomic>
#include <cctype>
#include <chrono>
#include <cstdlib>
#include <condition_variable>
#include <deque>
#include <mutex>
#include <new>
#include <string_view>
#include <thread>

#include <cerrno>
#include <csignal>
#include <sys/types.h>

namespace fs = std::filesystem;
using nlohmann::json;

namespace tvf::serve {

namespace {

// What one generation made: everything the readers need, immutable once published.
struct Result {
  long long revision = 0;
  Scene scene;
  std::shared_ptr<const DesignSpace> space;
  Field field;
  Topology topology;
  PeriodicOrbits orbits;  // cycles and Hopf events (DESIGN §12)
  std::vector<std::string> warnings;
  std::string method;
  double seconds = 0;
};

bool inside(const fs::path& root, const fs::path& p) {
  auto r = root.begin(), q = p.begin();
  for (; r != root.end(); ++r, ++q) {
    if (r->empty()) continue;  // trailing separator of the root
    if (q == p.end() || *r != *q) return false;
  }
  return true;
}

json vec3(const Vec3& v, bool planar) {
  return planar ? json::array({v.x(), v.y()}) : json::array({v.x(), v.y(), v.z()});
}

// float32 values as the JSON numbers that print them shortest (7 significant digits,
// float32's precision): a float widened to double would print 17 digits.
std::vector<double> compact(const std::vector<float>& values) {
  std::vector<double> out(values.size());
  char buffer[32];
  for (size_t i = 0; i < values.size(); ++i) {
    const auto end = fmt::format_to_n(buffer, sizeof buffer - 1, "{:.7g}", values[i]).out;
    *end = '\0';
    out[i] = std::strtod(buffer, nullptr);
  }
  return out;
}

// A change made on `on_revision` while the scene is at `current`: refused (412).
void check_revision(long long on_revision, long long current, const char* what) {
  if (on_revision != kAnyRevision && on_revision != current)
    throw RequestError(412, fmt::format("{}: made on revision {}, but the scene is at revision {} (another tab or "
                                        "client changed it): reload the scene and make the change again",
                                        what, on_revision, current));
}

// Temporary files of a crashed session: ".NAME.tmp-PID-N" (temporary_sibling) of a
// process that no longer runs. Removed at start; files of a running process are kept.
// The process id in a temporary's name ".NAME.tmp-PID-N", or -1 for any other name.
long temporary_owner(const std::string& name) {
  const auto digits = [](std::string_view v) {
    return !v.empty() && std::all_of(v.begin(), v.end(), [](char c) { return c >= '0' && c <= '9'; });
  };
  const size_t tag = name.rfind(".tmp-");
  if (name.size() < 2 || name[0] != '.' || tag == std::string::npos || tag < 2) return -1;
  const std::string_view rest = std::string_view(name).substr(tag + 5);
  const size_t dash = rest.find('-');
  if (dash == std::string_view::npos || dash > 9 || !digits(rest.substr(0, dash)) || !digits(rest.substr(dash + 1)))
    return -1;
  return std::stol(std::string(rest.substr(0, dash)));
}

void remove_stale_temporaries(const fs::path& folder) {
  std::error_code ec;
  for (fs::directory_iterator it(folder, ec), end; !ec && it != end; it.increment(ec)) {
    const long pid = temporary_owner(it->path().filename().string());
    if (pid < 0 || !it->is_regular_file(ec)) continue;
    const bool alive = pid > 0 && (::kill(static_cast<pid_t>(pid), 0) == 0 || errno == EPERM);
    if (!alive || pid == static_cast<long>(::getpid())) fs::remove(it->path(), ec);
    ec.clear();
  }
}

// The key a design space is cached under: the domain as the scene writes it.
std::string domain_key(const Scene& scene) {
  return scene_to_json(scene)["domain"].dump() + "|" + scene.resolved_mesh_path();
}

}  // namespace

struct Session::State {
  SessionOptions options;
  fs::path dir;  // canonical working folder

  mutable std::mutex mutex;
  mutable std::condition_variable changed;  // a result was published or a solve failed
  std::condition_variable work;             // the worker has something to do
  Scene scene;
  long long revision = 1;
  std::deque<json> undo, redo;

  // Generation: the worker takes the newest revision; an older one still running is
  // cancelled through its own flag.
  bool pending = false;
  bool stop = false;
  std::shared_ptr<std::atomic<bool>> cancel;
  std::string state = "running";
  std::string error;
  int done = 0, total = 0;
  long long cancelled = 0;  // solves stopped because a newer change came
  std::shared_ptr<const Result> result;
  std::shared_ptr<const DesignSpace> space;
  std::string space_key;
  // The solver set-up and last space-time solution, kept between the worker's solves
  // (GenerateCache: a re-solve after a small change starts from the last result). Only
  // the worker thread uses it.
  GenerateCache solver_cache;
  std::thread worker;

  bool interrupted = false;  // interrupt(): waits end at once
  // Counts the changes of status() that GET /api/events pushes: the revision, the
  // generation state, the field's readiness (Session::wait_change).
  long long changes = 1;
  void touch() {
    ++changes;
    changed.notify_all();
  }
  std::mutex render_mutex;  // one video at a time

  fs::path scene_path() const { return dir / options.scene; }

  // Every path the scene names must stay inside the working folder.
  void check_scene_paths(const Scene& s) const {
    auto check = [&](const std::string& path, const std::string& where) {
      if (path.empty()) return;
      std::error_code ec;  // a name too long for the file system, say: refused, not thrown on
      const fs::path p = fs::weakly_canonical(fs::path(s.resolve_path(path)), ec);
      if (ec)
        throw RequestError(400, fmt::format("{}: {}: \"{:.60}\" cannot be used as a path: {}", options.scene, where,
                                            path, ec.message()));
      if (!inside(dir, p))
        throw RequestError(403, fmt::format("{}: {}: \"{}\" is outside the working folder {}", options.scene, where,
                                            path, dir.string()));
    };
    if (!s.domain.mesh.empty()) check(s.domain.mesh, "domain.mesh");
    for (size_t k = 0; k < s.keyframes.size(); ++k)
      check(s.keyframes[k].field, fmt::format("keyframes[{}].field", k));
  }

  Scene parse(const json& j) const {
    try {
      Scene s = scene_from_json(j, options.scene, scene_path().string());
      check_scene_paths(s);
      return s;
    } catch (const RequestError&) {
      throw;
    } catch (const Error& e) {
      throw RequestError(400, e.what(), location_of(e));
    }
  }

  // Makes `next` the current scene: saved first (so a failed save changes nothing), then
  // the revision advances and a solve is scheduled. Caller holds `mutex`.
  void commit(Scene next, bool record_undo, bool schedule_solve) {
    save_scene(next, scene_path().string());
    if (record_undo) {
      undo.push_back(scene_to_json(scene));
      while (static_cast<int>(undo.size()) > options.history) undo.pop_front();
      redo.clear();
    }
    scene = std::move(next);
    ++revision;
    if (schedule_solve) schedule();
    touch();
  }

  void schedule() {
    if (cancel) cancel->store(true);
    pending = true;
    state = "running";
    error.clear();
    done = 0;
    total = scene.time.frames;
    work.notify_one();
    touch();
  }

  void run_worker() {
    std::unique_lock lock(mutex);
    for (;;) {
      work.wait(lock, [&] { return pending || stop; });
      if (stop) return;
      pending = false;
      const Scene job = scene;
      const long long job_revision = revision;
      auto flag = std::make_shared<std::atomic<bool>>(false);
      cancel = flag;
      lock.unlock();
      std::shared_ptr<Result> made;
      std::string failure;
      bool stopped = false;
      try {
        made = generate_result(job, job_revision, *flag);
      } catch (const GenerationCancelled&) {
        stopped = true;
      } catch (const std::bad_alloc&) {
        failure = fmt::format("the scene needs more memory than this machine has ({} frames of {}): make the "
                              "grid, the mesh or time.frames smaller",
                              job.time.frames, job.domain.is_planar() && job.domain.grid
                                                   ? fmt::format("a {}×{} grid", job.domain.grid->nx, job.domain.grid->ny)
                                                   : std::string("the surface"));
      } catch (const std::exception& e) {
        failure = e.what();
      }
      lock.lock();
      if (stopped) ++cancelled;
      if (job_revision != revision) continue;  // superseded: its successor is pending
      if (made) {
        result = std::move(made);
        state = "ready";
      } else if (!failure.empty()) {
        state = "failed";
        error = failure;
      }
      touch();
    }
  }

  std::shared_ptr<const DesignSpace> space_for(const Scene& s) {
    const std::string key = domain_key(s);
    {
      std::lock_guard lock(mutex);
      if (space && key == space_key) return space;
    }
    std::shared_ptr<const DesignSpace> made = make_design_space(s);
    std::lock_guard lock(mutex);
    space = made;
    space_key = key;
    return made;
  }

  std::shared_ptr<Result> generate_result(const Scene& s, long long rev, const std::atomic<bool>& flag) {
    const auto start = std::chrono::steady_clock::now();
    auto r = std::make_shared<Result>();
    r->revision = rev;
    r->scene = s;
    r->space = space_for(s);
    GenerateOptions go;
    go.parallel = options.parallel;
    go.cancel = &flag;
    go.cache = &solver_cache;
    go.progress = [this](int d, int t) {
      std::lock_guard lock(mutex);
      done = d;
      total = t;
    };
    GenerateReport report;
    r->field = generate(*r->space, s, go, &report);
    check_cancelled(go);
    TopologyOptions to;
    to.parallel = options.parallel;
    r->topology = analyze_topology(r->space->bundle(), r->field, to);
    PeriodicOrbitOptions po;
    po.parallel = options.parallel;
    r->orbits = find_periodic_orbits(r->space->bundle(), r->field, r->topology, po);
    r->warnings = report.warnings;
    r->method = report.method;
    r->seconds = std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
    return r;
  }

  // The field of revision `want`, waiting for a running solve until `deadline` without
  // holding a lock: 412 as soon as the scene moves past `want`. kAnyRevision: the field of
  // whatever revision is current (following newer changes while it waits). 409 when the
  // solve failed or is not done in time; 503 when interrupted.
  std::shared_ptr<const Result> result_of(long long want, const char* what,
                                          std::chrono::steady_clock::time_point deadline) const {
    std::unique_lock lock(mutex);
    const bool any = want == kAnyRevision;
    check_revision(want, revision, what);
    auto target = [&] { return any ? revision : want; };
    changed.wait_until(lock, deadline, [&] {
      return interrupted || revision != target() || (result && result->revision == target()) || state == "failed";
    });
    if (interrupted) throw RequestError(503, fmt::format("{}: the server is stopping", what));
    check_revision(want, revision, what);
    if (result && result->revision == revision) return result;
    if (state == "failed") throw RequestError(409, fmt::format("{}: the scene has no field: {}", what, error));
    throw RequestError(409, fmt::format("{}: the field of revision {} is still being generated ({}/{} frames); try "
                                        "again when /api/status says ready",
                                        what, revision, done, total));
  }
  std::chrono::steady_clock::time_point wait_deadline() const {
    return std::chrono::steady_clock::now() +
           std::chrono::duration_cast<std::chrono::steady_clock::duration>(
               std::chrono::duration<double>(std::max(0.0, std::min(options.field_wait_seconds, 1e6))));
  }

  std::shared_ptr<const Result> current_result() const {
    std::lock_guard lock(mutex);
    if (!result)
      throw RequestError(409, state == "failed" ? "the scene has no field: " + error
                                                : std::string("the field is still being generated; try again"));
    return result;
  }

  json scene_json() const {
    return {{"revision", revision},
            {"scene", scene_to_json(scene)},
            {"text", scene_to_text(scene)},
            {"path", options.scene},
            {"can_undo", !undo.empty()},
            {"can_redo", !redo.empty()}};
  }
};

Session::Session(SessionOptions options) : s_(std::make_unique<State>()) {
  s_->options = std::move(options);
  std::error_code ec;
  fs::create_directories(s_->options.dir, ec);
  if (ec || !fs::is_directory(s_->options.dir))
    throw Error(fmt::format("{}: cannot use this folder as the working folder: {}", s_->options.dir.string(),
                            ec ? ec.message() : "not a folder"));
  s_->dir = fs::canonical(s_->options.dir);
  const fs::path rel(s_->options.scene);
  if (rel.empty() || rel.is_absolute() || !inside(s_->dir, fs::weakly_canonical(s_->dir / rel)))
    throw Error(fmt::format("{}: the scene must be a file inside the working folder {}", s_->options.scene,
                            s_->dir.string()));
  const fs::path path = s_->scene_path();
  if (fs::exists(path)) {
    s_->scene = load_scene(path.string());
  } else {
    if (s_->options.initial_scene.empty())
      throw Error(fmt::format("{}: no such scene file, and no scene to start from", path.string()));
    s_->scene = parse_scene(s_->options.initial_scene, path.string());
    s_->scene.source_path = path.string();
    save_scene(s_->scene, path.string());
  }
  s_->check_scene_paths(s_->scene);
  remove_stale_temporaries(s_->dir);
  if (path.parent_path() != s_->dir) remove_stale_temporaries(path.parent_path());
  s_->worker = std::thread([this] { s_->run_worker(); });
  std::lock_guard lock(s_->mutex);
  s_->schedule();
}

Session::~Session() {
  {
    std::lock_guard lock(s_->mutex);
    s_->stop = true;
    s_->interrupted = true;
    if (s_->cancel) s_->cancel->store(true);
    s_->work.notify_all();
    s_->changed.notify_all();
  }
  if (s_->worker.joinable()) s_->worker.join();
}

const fs::path& Session::dir() const { return s_->dir; }
fs::path Session::scene_path() const { return s_->scene_path(); }

json Session::scene() const {
  std::lock_guard lock(s_->mutex);
  return s_->scene_json();
}

long long Session::revision() const {
  std::lock_guard lock(s_->mutex);
  return s_->revision;
}

void Session::interrupt() {
  std::lock_guard lock(s_->mutex);
  s_->interrupted = true;
  if (s_->cancel) s_->cancel->store(true);
  s_->changed.notify_all();
}

json Session::put_scene(const json& j, long long on_revision) {
  {
    std::lock_guard lock(s_->mutex);  // refuse a stale change before the work of parsing it
    check_revision(on_revision, s_->revision, "scene");
  }
  Scene next = s_->parse(j);
  std::lock_guard lock(s_->mutex);
  check_revision(on_revision, s_->revision, "scene");
  s_->commit(std::move(next), true, true);
  return s_->scene_json();
}

json Session::edit(const json& entry, long long on_revision) {
  if (!entry.is_object()) throw RequestError(400, "edit: expected a JSON object such as {\"op\": \"cancel\", ...}");
  // Without a revision, an edit overtaken by another change is applied again to the newer
  // field (a few times at most: each attempt is one edit's work).
  const auto deadline = s_->wait_deadline();  // for all attempts together
  for (int attempt = 0;; ++attempt) {
    try {
      return edit_on(entry, on_revision, deadline);
    } catch (const RequestError& e) {
      if (on_revision != kAnyRevision || e.status() != 412 || attempt == 3) throw;
    }
  }
}

json Session::edit_on(const json& entry, long long on_revision, std::chrono::steady_clock::time_point deadline) {
  Scene base;
  long long base_revision = 0;
  {
    std::lock_guard lock(s_->mutex);
    check_revision(on_revision, s_->revision, "edit");
    base = s_->scene;
    base_revision = s_->revision;
  }
  json j = scene_to_json(base);
  j["edits"].push_back(entry);
  const std::string where = fmt::format("edits[{}]", j["edits"].size() - 1);
  const Scene edited = s_->parse(j);
  const Edit e = edited.edits.back();

  // The field of the revision the edit was made on (no lock held while waiting).
  const std::shared_ptr<const Result> r = s_->result_of(base_revision, "edit", deadline);
  auto made = std::make_shared<Result>();
  made->scene = edited;
  made->space = r->space;
  made->field = r->field;
  made->warnings = r->warnings;
  made->method = r->method;
  EditReport report;
  const auto start = std::chrono::steady_clock::now();
  try {
    FieldEditor editor(*r->space, edit_settings(base));
    report = editor.apply(made->field, e);
  } catch (const EditRefused& refused) {
    throw RequestError(422, fmt::format("refused to {}: {}; the scene is unchanged", describe(e), refused.what()));
  } catch (const Error& err) {
    throw RequestError(422, fmt::format("{}: {}", where, err.what()), location_of(err));
  }
  TopologyOptions to;
  to.parallel = s_->options.parallel;
  made->topology = analyze_topology(r->space->bundle(), made->field, to);
  PeriodicOrbitOptions po;
  po.parallel = s_->options.parallel;
  made->orbits = find_periodic_orbits(r->space->bundle(), made->field, made->topology, po);
  made->seconds = std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();

  std::lock_guard lock(s_->mutex);
  check_revision(base_revision, s_->revision, "edit");
  s_->commit(edited, true, false);
  made->revision = s_->revision;
  if (s_->cancel) s_->cancel->store(true);
  s_->result = std::move(made);
  s_->state = "ready";
  s_->error.clear();
  s_->touch();
  return {{"revision", s_->revision}, {"summary", report.summary}};
}

json Session::undo(long long on_revision) {
  std::lock_guard lock(s_->mutex);
  check_revision(on_revision, s_->revision, "undo");
  if (s_->undo.empty()) throw RequestError(409, "nothing to undo");
  Scene previous = s_->parse(s_->undo.back());
  s_->redo.push_back(scene_to_json(s_->scene));
  s_->undo.pop_back();
  s_->commit(std::move(previous), false, true);
  return s_->scene_json();
}

json Session::redo(long long on_revision) {
  std::lock_guard lock(s_->mutex);
  check_revision(on_revision, s_->revision, "redo");
  if (s_->redo.empty()) throw RequestError(409, "nothing to redo");
  Scene next = s_->parse(s_->redo.back());
  s_->undo.push_back(scene_to_json(s_->scene));
  s_->redo.pop_back();
  s_->commit(std::move(next), false, true);
  return s_->scene_json();
}

json Session::status() const {
  std::lock_guard lock(s_->mutex);
  json j = {{"revision", s_->revision},
            {"result_revision", s_->result ? s_->result->revision : 0},
            {"state", s_->state},
            {"progress", {s_->done, s_->total}},
            {"error", s_->error},
            {"cancelled", s_->cancelled}};
  if (s_->result) {
    j["warnings"] = s_->result->warnings;
    j["method"] = s_->result->method;
    j["seconds"] = s_->result->seconds;
  }
  return j;
}

long long Session::wait_change(long long seen, double seconds) const {
  std::unique_lock lock(s_->mutex);
  s_->changed.wait_for(lock, std::chrono::duration<double>(seconds),
                       [&] { return s_->changes != seen || s_->interrupted; });
  return s_->interrupted ? -1 : s_->changes;
}

bool Session::wait_idle(double seconds) const {
  std::unique_lock lock(s_->mutex);
  return s_->changed.wait_for(lock, std::chrono::duration<double>(seconds), [&] {
    return (s_->result && s_->result->revision == s_->revision) || s_->state == "failed";
  });
}

json Session::mesh() const {
  const auto r = s_->current_result();
  const Mesh& m = r->space->mesh();
  const bool planar = r->scene.domain.is_planar();
  std::vector<float> v;
  v.reserve(static_cast<size_t>(m.num_vertices()) * 3);
  for (const Vec3& p : m.positions())
    for (int k = 0; k < 3; ++k) v.push_back(static_cast<float>(p[k]));
  std::vector<int> f;
  f.reserve(static_cast<size_t>(m.num_faces()) * 3);
  for (const Face& face : m.faces()) f.insert(f.end(), face.begin(), face.end());
  json j = {{"revision", r->revision}, {"planar", planar}, {"vertices", compact(v)}, {"faces", f}};
  if (planar) {
    const GridSpec& g = *r->scene.domain.grid;
    j["grid"] = {{"size", {g.nx, g.ny}}, {"min", {g.min.x(), g.min.y()}}, {"max", {g.max.x(), g.max.y()}}};
  }
  return j;
}

json Session::frame(int j) const {
  const auto r = s_->current_result();
  const int frames = r->field.frames();
  if (j < 0 || j >= frames)
    throw RequestError(400, fmt::format("frame: {} is outside [0, {}]", j, frames - 1));
  const bool planar = r->scene.domain.is_planar();
  json sing = json::array();
  const auto& list = r->topology.singularities[static_cast<size_t>(j)];
  for (size_t k = 0; k < list.size(); ++k)
    sing.push_back({{"position", vec3(list[k].position, planar)},
                    {"type", to_string(list[k].type)},
                    {"index", list[k].index},
                    {"path", r->topology.singularity_path[static_cast<size_t>(j)][k]}});
  return {{"revision", r->revision},
          {"frame", j},
          {"frames", frames},
          {"t", r->field.time().time(j)},
          {"vectors", compact(world_vectors_f32(r->space->bundle(), r->field, j))},
          {"singularities", sing}};
}

json Session::analysis() const {
  const auto r = s_->current_result();
  json j = topology_to_json(r->topology);
  add_periodic_orbits_to_json(j, r->orbits);
  j["revision"] = r->revision;
  return j;
}

json Session::seed_translation(const json& request) const {
  if (!request.is_object())
    throw RequestError(400, "seed_translation: expected {\"seed\": position, \"to\": position}");
  const auto r = s_->current_result();
  const bool planar = r->scene.domain.is_planar();
  auto position = [&](const char* key) {
    const size_t n = planar ? 2 : 3;
    const auto it = request.find(key);
    if (it == request.end() || !it->is_array() || it->size() != n ||
        !std::all_of(it->begin(), it->end(), [](const json& v) { return v.is_number(); }))
      throw RequestError(400, fmt::format("seed_translation: \"{}\" must be a position of {} numbers on this {}", key,
                                          n, planar ? "grid" : "surface"));
    Vec3 x = Vec3::Zero();
    for (size_t k = 0; k < n; ++k) x[static_cast<int>(k)] = (*it)[k].get<double>();
    if (!x.allFinite()) throw RequestError(400, fmt::format("seed_translation: \"{}\" is not finite", key));
    // The same bound as every number of a scene (docs/scene_reference.md, "Limits").
    if (x.cwiseAbs().maxCoeff() > 1e15)
      throw RequestError(400, fmt::format("seed_translation: \"{}\" has a coordinate of magnitude over 1e15", key));
    return x;
  };
  const Vec3 seed = position("seed");
  const Vec3 to = position("to");
  try {
    return {{"translate", vec3(tvf::seed_translation(*r->space, seed, to), planar)}};
  } catch (const Error& e) {
    throw RequestError(422, e.what());
  }
}

fs::path Session::resolve(const std::string& relative) const {
  if (relative.empty()) throw RequestError(400, "path: empty");
  if (relative.find('\0') != std::string::npos) throw RequestError(400, "path: contains a NUL character");
  const fs::path rel(relative);
  if (rel.is_absolute() || rel.has_root_name() || rel.has_root_directory())
    throw RequestError(400, fmt::format("path \"{}\": give a path relative to the working folder", relative));
  for (const auto& part : rel)
    if (part == "..") throw RequestError(403, fmt::format("path \"{}\": leaves the working folder", relative));
  std::error_code ec;  // a name too long for the file system, say: refused, not thrown on
  const fs::path p = fs::weakly_canonical(s_->dir / rel, ec);
  if (ec) throw RequestError(400, fmt::format("path \"{:.60}\": cannot be used: {}", relative, ec.message()));
  if (!inside(s_->dir, p)) throw RequestError(403, fmt::format("path \"{}\": leaves the working folder", relative));
  return p;
}

namespace {

void check_keys(const json& request, const char* what, std::initializer_list<const char*> keys) {
  if (!request.is_object()) throw RequestError(400, fmt::format("{}: expected a JSON object", what));
  for (auto it = request.begin(); it != request.end(); ++it)
    if (std::find_if(keys.begin(), keys.end(), [&](const char* k) { return it.key() == k; }) == keys.end())
      throw RequestError(400, fmt::format("{}: unknown key \"{}\"", what, it.key()));
}

std::string string_or(const json& request, const char* key, const char* what, const std::string& fallback) {
  if (!request.contains(key)) return fallback;
  if (!request[key].is_string()) throw RequestError(400, fmt::format("{}.{}: expected a string", what, key));
  return request[key].get<std::string>();
}

}  // namespace

json Session::export_field(const json& request, long long on_revision) {
  check_keys(request, "export", {"dir", "format"});
  const std::string format = string_or(request, "format", "export", "all");
  if (format != "all" && format != "npy" && format != "vtk")
    throw RequestError(400, fmt::format("export.format: \"{}\" is not one of all, npy, vtk", format));
  const fs::path out = resolve(string_or(request, "dir", "export", "export"));
  const auto r = s_->result_of(on_revision, "export", s_->wait_deadline());
  OutputOptions o;
  o.vtk = format != "npy";
  json files = json::array();
  try {
    for (const fs::path& f : write_field_outputs(out, *r->space, r->field, r->scene, o))
      files.push_back(fs::relative(f, s_->dir).generic_string());
  } catch (const Error& e) {
    throw RequestError(400, e.what());
  }
  return {{"revision", r->revision}, {"files", files}};
}

json Session::render_video(const json& request, long long on_revision) {
  check_keys(request, "render", {"name", "size", "singularities", "paths", "frames", "view", "up", "fov"});
  const std::string name = string_or(request, "name", "render", "video.mp4");
  const fs::path out = resolve(name);
  auto integer = [&](const char* key, int fallback, long long lo, long long hi) {
    if (!request.contains(key)) return fallback;
    if (!request[key].is_number_integer() || request[key].get<long long>() < lo || request[key].get<long long>() > hi)
      throw RequestError(400, fmt::format("render.{}: expected an integer in [{}, {}]", key, lo, hi));
    return request[key].get<int>();
  };
  auto flag = [&](const char* key, bool fallback) {
    if (!request.contains(key)) return fallback;
    if (!request[key].is_boolean()) throw RequestError(400, fmt::format("render.{}: expected true or false", key));
    return request[key].get<bool>();
  };
  auto vector = [&](const char* key, const Vec3& fallback) {
    if (!request.contains(key)) return fallback;
    const json& v = request[key];
    if (!v.is_array() || v.size() != 3 || !std::all_of(v.begin(), v.end(), [](const json& x) { return x.is_number(); }))
      throw RequestError(400, fmt::format("render.{}: expected three numbers [x, y, z]", key));
    const Vec3 d(v[0].get<double>(), v[1].get<double>(), v[2].get<double>());
    if (!d.allFinite() || d.norm() == 0)
      throw RequestError(400, fmt::format("render.{}: expected a non-zero direction", key));
    return d;
  };
  TextureAnimationOptions o;
  o.texture.size = integer("size", 512, 16, 4096);
  o.frames = integer("frames", 0, 1, 100000);
  o.overlay_singularities = flag("singularities", true);
  o.overlay_paths = flag("paths", false);
  // Surfaces: the camera (the designer sends its own view, so the video shows what the
  // page shows); planar domains ignore it.
  o.surface.direction = vector("view", o.surface.direction);
  o.surface.up = vector("up", o.surface.up);
  if (request.contains("fov")) {
    if (!request["fov"].is_number() || !(request["fov"].get<double>() > 1) || !(request["fov"].get<double>() < 170))
      throw RequestError(400, "render.fov: expected a number of degrees in (1, 170)");
    o.surface.fov = request["fov"].get<double>();
  }
  if (o.surface.direction.cross(o.surface.up).norm() < 1e-6 * o.surface.direction.norm() * o.surface.up.norm())
    throw RequestError(400, "render.up: must not be parallel to render.view");
  const std::string ext = out.extension().string();
  if (ext == ".mp4") {
    if (!ffmpeg_available()) throw RequestError(400, "render: ffmpeg is not installed (scripts/install-deps.sh)");
    o.video = out.string();
  } else if (ext.empty()) {
    o.frames_dir = out.string();
  } else {
    throw RequestError(400, fmt::format("render.name \"{}\": give an .mp4 file or a folder for PNG frames", name));
  }
  const auto r = s_->result_of(on_revision, "render", s_->wait_deadline());
  try {
    // One texture animation at a time: the offscreen renderer and ffmpeg are not worth
    // running twice at once, and a second request is refused rather than queued.
    std::unique_lock lock(s_->render_mutex, std::try_to_lock);
    if (!lock.owns_lock()) throw RequestError(503, "render: a video is being rendered; try again when it is done");
    const TextureAnimationReport rep = write_texture_animation(r->space->bundle(), r->field, o);
    return {{"revision", r->revision},
            {"file", fs::relative(out, s_->dir).generic_string()},
            {"frames", rep.frames},
            {"width", rep.width},
            {"height", rep.height},
            {"seconds", rep.seconds}};
  } catch (const RequestError&) {
    throw;
  } catch (const Error& e) {
    throw RequestError(400, e.what());
  }
}

json Session::upload_mesh(const std::string& name, const std::string& bytes) {
  const fs::path n(name);
  if (name.empty() || n.has_parent_path() || n.filename() != n)
    throw RequestError(400, fmt::format("upload \"{}\": give a plain file name", name));
  // A scene names its mesh in a JSON string, which holds UTF-8 only: a name that is not
  // could never be used (and could not be answered as JSON).
  if (valid_utf8(name) != name)
    throw RequestError(400, fmt::format("upload \"{:.60}\": the file name is not valid UTF-8", name));
  std::string ext = n.extension().string();
  std::transform(ext.begin(), ext.end(), ext.begin(), [](unsigned char c) { return static_cast<char>(std::tolower(c)); });
  if (ext != ".obj" && ext != ".ply" && ext != ".off")
    throw RequestError(400, fmt::format("upload \"{}\": meshes are .obj, .ply or .off files", name));
  if (bytes.empty()) throw RequestError(400, fmt::format("upload \"{}\": the file is empty", name));
  const fs::path out = resolve(name);
  write_file_atomically(out, bytes);
  return {{"file", name}};
}

}  // namespace tvf::serve
