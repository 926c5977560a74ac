#include "tvf/serve/session.h"

#include "tvf/api/design.h"
#include "tvf/core/atomic_output.h"
#include "tvf/design/keyframe_topology.h"
#include "tvf/design/outputs.h"
#include "tvf/scene/scene_json.h"
#include "tvf/design/streamline_deform.h"
#include "tvf/field/world_vectors.h"
#include "tvf/render/texture_animation.h"
#include "tvf/render/video.h"

#include <fmt/format.h>

#include <algorithm>
#include <atomic>
#include <cctype>
#include <chrono>
#include <cstdint>
#include <cstdlib>
#include <cstring>
#include <condition_variable>
#include <mutex>
#include <new>
#include <optional>
#include <string_view>
#include <thread>

#include <cerrno>
#include <csignal>
#include <sys/resource.h>
#include <sys/types.h>
#include <unistd.h>

namespace fs = std::filesystem;
using nlohmann::json;

namespace tvf::serve {

namespace {

// A result as the readers get it: what the Design made for one scene (its field, domain and
// report: complete, immutable once published), the revision and scene it belongs to, and
// the seconds it took. The field is published as soon as it is made; its analysis
// (topology and periodic orbits) follows on the analysis thread, which publishes a copy of
// the Result with `analysis` set (an edit's result comes with its analysis at once).
struct Analysis {
  Topology topology;
  PeriodicOrbits orbits;
  double seconds = 0;
};
// The frame a viewer shows, made first by a per-frame generator while the other frames
// are still being solved (GenerateOptions::first_frame): GET /api/preview.
struct Preview {
  long long revision = 0;
  int frame = 0, frames = 0;
  double t = 0;
  bool planar = true;
  std::shared_ptr<const DesignSpace> space;
  std::vector<cplx> values;  // |V|, each in its vertex basis
};

struct Result {
  long long revision = 0;
  Scene scene;
  std::shared_ptr<const DesignResult> made;
  double seconds = 0;
  long long domain = 0;  // changes when the domain (mesh) does: GET /api/mesh again
  std::shared_ptr<const Analysis> analysis;  // the analysis thread's
  std::string analysis_error;                // the analysis failed (a non-finite value, say)
  const DesignSpace& space() const { return *made->space; }
  const Field& field() const { return made->field; }
  // The analysis is there: the analysis thread's, or the one an edit's result carries.
  bool analysed() const { return analysis || (made->topology && made->orbits); }
  const Topology& topology() const { return analysis ? analysis->topology : *made->topology; }
  const PeriodicOrbits& orbits() const { return analysis ? analysis->orbits : *made->orbits; }
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

// The binary form of a frame (docs/serve_api.md, "Binary frames"): a 4-byte little-endian
// length n, n bytes of JSON (the frame's JSON without "vectors", plus "count", the number
// of floats; padded with spaces so that the floats start at a multiple of 4), then
// `count` float32 values, little-endian: x, y, z per vertex.
std::string binary_frame(json head, const std::vector<float>& values) {
  static_assert(sizeof(float) == 4);
  head["count"] = values.size();
  std::string text = head.dump(-1, ' ', false, json::error_handler_t::replace);
  text.append((4 - text.size() % 4) % 4, ' ');
  std::string out(4 + text.size() + 4 * values.size(), '\0');
  const auto n = static_cast<std::uint32_t>(text.size());
  for (int k = 0; k < 4; ++k) out[static_cast<size_t>(k)] = static_cast<char>((n >> (8 * k)) & 0xff);
  std::memcpy(out.data() + 4, text.data(), text.size());
  unsigned char* f = reinterpret_cast<unsigned char*>(out.data()) + 4 + text.size();
  for (const float v : values) {
    std::uint32_t bits = 0;
    std::memcpy(&bits, &v, 4);
    for (int k = 0; k < 4; ++k) *f++ = static_cast<unsigned char>((bits >> (8 * k)) & 0xff);
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

}  // namespace

struct Session::State {
  SessionOptions options;
  fs::path dir;  // canonical working folder

  mutable std::mutex mutex;
  mutable std::condition_variable changed;  // a result was published or a solve failed
  std::condition_variable work;             // the worker has something to do
  // The design (tvf/api/design.h): scene, revision, undo/redo history, domain, solver
  // set-up and the field of its scene. Used under `mutex`; its Solves and EditJobs run
  // without it. Kept fields: none (an undo regenerates, as a new scene does).
  std::optional<Design> design;

  // Generation: the worker takes the newest revision; an older one still running is
  // cancelled through its own flag.
  bool pending = false;
  bool stop = false;
  std::shared_ptr<std::atomic<bool>> cancel;
  std::string state = "running";
  std::string error;
  int done = 0, total = 0;
  // The running solve's step that no frame count measures (GenerateOptions::stage), until
  // its frames' progress starts; empty otherwise.
  std::string stage;
  long long cancelled = 0;  // solves stopped because a newer change came
  bool solving = false;     // the worker runs a solve (the analysis thread waits meanwhile)
  std::shared_ptr<const Result> result;
  long long domains = 0;           // domains the results have lived on so far (Result::domain)
  long long analysed_revision = 0;  // the revision of the last analysis published
  int focus_frame = 0;                       // the frame asked for last: made first
  std::shared_ptr<const Preview> preview;    // that frame of a solve under way
  std::thread worker;
  // Changes (a new scene, an edit's commit, undo, redo) one at a time, each with its save:
  // the scene file always holds the current scene. Taken before `mutex`, never after it;
  // a new scene is saved holding this one only, so status and reads go on meanwhile.
  std::mutex change_mutex;
  // A new scene's solve starts while the scene is being saved (put_scene): `upcoming` is
  // the revision it will have once saved (0: none), `next_job` its solve for the worker.
  // What that solve makes before the scene is saved waits here and is published at the
  // commit (nothing of a revision is shown before its scene is on disk).
  long long upcoming = 0;
  std::optional<Design::Solve> next_job;
  struct Early {
    std::optional<Design::Solve> job;
    double seconds = 0;
    std::string failure;
  };
  std::optional<Early> early;             // the upcoming revision's solve, finished
  std::shared_ptr<const Preview> held_preview;  // the upcoming revision's shown frame
  bool saved_already = false;  // before_change: the scene about to be set is on disk
  std::condition_variable analysis_work;  // a result without its analysis was published
  std::thread analyst;
  // The running analysis's flag (run_analyst): set when a newer change makes its field
  // obsolete. `analyses_stopped` counts the results whose analysis a newer change stopped
  // or kept from starting (each revision once: `stopped_revision`, the last one counted).
  std::shared_ptr<std::atomic<bool>> analysis_cancel;
  long long analysing = 0;  // the revision of the result it analyses (0: none)
  long long analyses_stopped = 0, stopped_revision = 0;
  // Returns whether it counted (the status changed).
  bool count_stopped(long long revision) {
    if (revision == stopped_revision) return false;
    ++analyses_stopped;
    stopped_revision = revision;
    return true;
  }
  // A newer change is coming or came: the running analysis (of the result about to be
  // replaced) stops, so that it does not take a core from the change's solve; the analysis
  // thread then waits for the worker (a solve that fails leaves the result as it was, and
  // its analysis starts again). Caller holds `mutex`.
  void stop_analysis() {
    if (analysis_cancel) analysis_cancel->store(true);
  }
  // A newer change is on its way: a solve waits or runs, or a new scene is being saved.
  bool busy() const { return pending || solving || upcoming != 0; }

  bool interrupted = false;  // interrupt(): waits end at once
  // Counts the changes of status() that GET /api/events pushes: the revision, the
  // generation state, the field's readiness (Session::wait_change). Each status carries
  // it ("sequence"), read under the same lock as the rest, so that a client orders the
  // statuses it gets from the event stream and from polls (a poll's answer can arrive
  // after a newer pushed event) and never shows an older one after a newer one.
  long long changes = 1;
  std::string id;  // status "session": tells a client that the server started again
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

  // A new revision needs its field: cancels the running solve and wakes the worker.
  // Caller holds `mutex`.
  void schedule() {
    if (cancel) cancel->store(true);
    stop_analysis();
    // A new scene's solve that the worker has not taken yet (put_scene) is of an older
    // revision now (an undo or redo came before the worker did): taken, its field would be
    // dropped and the current revision never solved.
    if (next_job && next_job->revision() != design->revision()) next_job.reset();
    pending = true;
    state = "running";
    error.clear();
    done = 0;
    total = design->scene().time.frames;
    stage.clear();
    work.notify_one();
    touch();
  }

  // The worker: prepares the Design's Solve of the newest revision under the lock, runs it
  // without (a newer change cancels it through its own flag), and publishes its result
  // when the Design is still at that revision.
  void run_worker() {
    std::unique_lock lock(mutex);
    for (;;) {
      work.wait(lock, [&] { return pending || stop; });
      if (stop) return;
      pending = false;
      solving = true;
      // The solve of a new scene being saved (put_scene), or of the current scene.
      Design::Solve job = next_job ? std::move(*next_job) : design->prepare_solve();
      next_job.reset();
      done = 0;  // this job's progress from here (a status never shows the last job's)
      total = job.scene().time.frames;
      stage.clear();
      const int first_frame = focus_frame;
      auto flag = std::make_shared<std::atomic<bool>>(false);
      cancel = flag;
      lock.unlock();
      std::string failure;
      bool stopped = false;
      const auto start = std::chrono::steady_clock::now();
      try {
        GenerateOptions go;
        go.cancel = flag.get();
        go.first_frame = first_frame;
        go.first_frame_done = [this, &job](int frame, std::span<const cplx> values) {
          auto p = std::make_shared<Preview>();
          p->revision = job.revision();
          p->frame = frame;
          p->t = job.scene().time.time(frame);
          p->frames = job.scene().time.frames;
          p->planar = job.scene().domain.is_planar();
          p->space = job.space();
          p->values.assign(values.begin(), values.end());
          std::lock_guard preview_lock(mutex);
          // Superseded already, or on another domain than the result's (a client would
          // draw it on the mesh it has): no preview.
          if (!p->space || !result || &result->space() != p->space.get()) return;
          if (p->revision == upcoming) {
            held_preview = std::move(p);  // published once its scene is saved (put_scene)
            return;
          }
          if (p->revision != design->revision()) return;
          preview = std::move(p);
          touch();
        };
        go.progress = [this](int d, int t) {
          std::lock_guard progress_lock(mutex);
          done = d;
          total = t;
          stage.clear();
        };
        go.stage = [this](const std::string& what) {
          std::lock_guard stage_lock(mutex);
          stage = what;
        };
        job.run(go, false);  // the field only: the analysis thread follows
      } catch (const GenerationCancelled&) {
        stopped = true;
      } catch (const std::bad_alloc&) {
        const Scene& s = job.scene();
        failure = fmt::format("the scene needs more memory than this machine has ({} frames of {}): make the "
                              "grid, the mesh or time.frames smaller",
                              s.time.frames, s.domain.is_planar() && s.domain.grid
                                                 ? fmt::format("a {}×{} grid", s.domain.grid->nx, s.domain.grid->ny)
                                                 : std::string("the surface"));
      } catch (const std::exception& e) {
        failure = e.what();
      }
      const double seconds = std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
      lock.lock();
      solving = false;
      analysis_work.notify_one();  // the analysis thread waits for an idle worker
      if (stopped) ++cancelled;
      const long long job_revision = job.revision();
      if (job_revision != design->revision()) {
        // The solve of a new scene that is still being saved: kept for put_scene, which
        // publishes it once the scene is on disk. Otherwise superseded: its successor is
        // pending.
        if (job_revision == upcoming && !stopped) early = Early{std::move(job), seconds, failure};
        continue;
      }
      finish(job, seconds, failure);
    }
  }

  // Publishes what a solve of the current revision made (caller holds `mutex`): its
  // field, or its failure; a cancelled solve changes nothing but the change count.
  void finish(Design::Solve& job, double seconds, const std::string& failure) {
    if (job.result()) {
      auto published = std::make_shared<Result>();
      published->revision = job.revision();
      published->scene = job.scene();
      published->made = job.result();
      published->seconds = seconds;
      design->adopt(std::move(job));
      publish(std::move(published));
      state = "ready";
    } else if (!failure.empty()) {
      state = "failed";
      error = failure;
    }
    touch();
  }

  // Makes `r` the result readers get (caller holds `mutex`): its domain id (a new one when
  // the mesh changed) and, when it has no analysis yet, a job for the analysis thread.
  void publish(std::shared_ptr<Result> r) {
    if (!result || &result->space() != &r->space()) ++domains;
    r->domain = domains;
    if (r->analysed()) analysed_revision = r->revision;
    // The analysis of the result replaced here stops if it runs (run_analyst counts it),
    // and is counted here if it never started.
    stop_analysis();
    if (result && result->revision != analysing && !result->analysed() && result->analysis_error.empty())
      count_stopped(result->revision);
    result = std::move(r);
    if (!result->analysed()) analysis_work.notify_one();
  }

  // The analysis thread: the topology and periodic orbits of the newest result, made while
  // no solve runs, published as a copy of the Result with them. A change never waits for
  // the analysis of the one before: a newer change stops it (stop_analysis; its field is
  // about to be replaced, its analysis would be dropped) and it waits until the worker is
  // idle, then analyses the newest result. It runs on this thread alone (not TBB's
  // workers) at a lower priority (nice 10): on a busy machine the requests for the new
  // picture go first.
  void run_analyst() {
    ::setpriority(PRIO_PROCESS, static_cast<id_t>(::gettid()), 10);  // best effort: a failure changes nothing
    std::unique_lock lock(mutex);
    for (;;) {
      analysis_work.wait(lock, [&] {
        return stop || (result && !result->analysed() && result->analysis_error.empty() && !busy());
      });
      if (stop) return;
      const std::shared_ptr<const Result> r = result;
      const auto flag = std::make_shared<std::atomic<bool>>(false);
      analysis_cancel = flag;
      analysing = r->revision;
      lock.unlock();
      auto made = std::make_shared<Analysis>();
      std::string failure;
      bool stopped = false;
      const auto start = std::chrono::steady_clock::now();
      try {
        TopologyOptions to;
        to.parallel = false;
        to.cancel = flag.get();
        made->topology = analyze_topology(r->space().bundle(), r->field(), to);
        PeriodicOrbitOptions po;
        po.parallel = false;
        po.cancel = flag.get();
        made->orbits = find_periodic_orbits(r->space().bundle(), r->field(), made->topology, po);
      } catch (const AnalysisCancelled&) {
        stopped = true;
      } catch (const std::bad_alloc&) {
        failure = "the analysis needs more memory than this machine has";
      } catch (const std::exception& e) {
        failure = e.what();
      }
      made->seconds = std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
      lock.lock();
      analysis_cancel.reset();
      analysing = 0;
      // A newer change came meanwhile: a newer result, or one on its way (then this
      // analysis starts again if that change's solve fails).
      if (stopped || flag->load() || result != r) {  // (flagged after its last check: dropped too)
        // Counted after the change's own status was pushed: a status change of its own
        // (else a poll could read another analyses_stopped under the same sequence).
        if (flag->load() && count_stopped(r->revision)) touch();
        continue;
      }
      auto next = std::make_shared<Result>(*r);
      if (failure.empty()) {
        next->analysis = std::move(made);
        analysed_revision = next->revision;
      } else {
        next->analysis_error = failure;
      }
      result = std::move(next);
      touch();
    }
  }

  // The field of revision `want`, waiting for a running solve until `deadline` without
  // holding a lock: 412 as soon as the scene moves past `want`. kAnyRevision: the field of
  // whatever revision is current (following newer changes while it waits). 409 when the
  // solve failed or is not done in time; 503 when interrupted.
  std::shared_ptr<const Result> result_of(long long want, const char* what,
                                          std::chrono::steady_clock::time_point deadline) const {
    std::unique_lock lock(mutex);
    const bool any = want == kAnyRevision;
    const auto revision = [&] { return design->revision(); };
    check_revision(want, revision(), what);
    auto target = [&] { return any ? revision() : want; };
    changed.wait_until(lock, deadline, [&] {
      return interrupted || revision() != target() || (result && result->revision == target()) || state == "failed";
    });
    if (interrupted) throw RequestError(503, fmt::format("{}: the server is stopping", what));
    check_revision(want, revision(), what);
    if (result && result->revision == revision()) return result;
    if (state == "failed") throw RequestError(409, fmt::format("{}: the scene has no field: {}", what, error));
    throw RequestError(409, fmt::format("{}: the field of revision {} is still being generated ({}/{} frames); try "
                                        "again when /api/status says ready",
                                        what, revision(), done, total));
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
    return {{"revision", design->revision()},
            {"scene", scene_to_json(design->scene())},
            {"text", scene_to_text(design->scene())},
            {"path", options.scene},
            {"can_undo", design->can_undo()},
            {"can_redo", design->can_redo()}};
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
  s_->id = fmt::format("{:x}-{:x}", static_cast<long>(::getpid()),
                       std::chrono::system_clock::now().time_since_epoch().count());
  const fs::path rel(s_->options.scene);
  if (rel.empty() || rel.is_absolute() || !inside(s_->dir, fs::weakly_canonical(s_->dir / rel)))
    throw Error(fmt::format("{}: the scene must be a file inside the working folder {}", s_->options.scene,
                            s_->dir.string()));
  const fs::path path = s_->scene_path();
  Scene scene;
  if (fs::exists(path)) {
    scene = load_scene(path.string());
  } else {
    if (s_->options.initial_scene.empty())
      throw Error(fmt::format("{}: no such scene file, and no scene to start from", path.string()));
    scene = parse_scene(s_->options.initial_scene, path.string());
    scene.source_path = path.string();
    save_scene(scene, path.string());
  }
  s_->check_scene_paths(scene);
  DesignOptions design_options;
  design_options.parallel = s_->options.parallel;
  design_options.history = s_->options.history;
  design_options.kept_fields = 0;
  // Every change is saved first, so that one that cannot be saved is not made (put_scene
  // saves its scene itself, before set_scene, holding only change_mutex).
  design_options.before_change = [path, state = s_.get()](const Scene& next) {
    if (!state->saved_already) save_scene(next, path.string());
  };
  s_->design.emplace(std::move(scene), std::move(design_options));
  remove_stale_temporaries(s_->dir);
  if (path.parent_path() != s_->dir) remove_stale_temporaries(path.parent_path());
  s_->worker = std::thread([this] { s_->run_worker(); });
  s_->analyst = std::thread([this] { s_->run_analyst(); });
  std::lock_guard lock(s_->mutex);
  s_->schedule();
}

Session::~Session() {
  {
    std::lock_guard lock(s_->mutex);
    s_->stop = true;
    s_->interrupted = true;
    if (s_->cancel) s_->cancel->store(true);
    s_->stop_analysis();
    s_->work.notify_all();
    s_->analysis_work.notify_all();
    s_->changed.notify_all();
  }
  if (s_->worker.joinable()) s_->worker.join();
  if (s_->analyst.joinable()) s_->analyst.join();
}

const fs::path& Session::dir() const { return s_->dir; }
fs::path Session::scene_path() const { return s_->scene_path(); }

json Session::scene() const {
  std::lock_guard lock(s_->mutex);
  return s_->scene_json();
}

long long Session::revision() const {
  std::lock_guard lock(s_->mutex);
  return s_->design->revision();
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
    check_revision(on_revision, s_->design->revision(), "scene");
  }
  Scene next = s_->parse(j);
  // What only the domain tells (a point far off the surface, a sketched streakline that
  // meets itself on it) is refused now, as the reader refuses it on grids, when the domain
  // is built already: not taken and left to fail in the solve.
  std::shared_ptr<const DesignSpace> space;
  {
    std::lock_guard lock(s_->mutex);
    space = s_->design->space_for(next);
  }
  if (space) {
    try {
      check_scene_on_domain(*space, next, s_->options.scene);
    } catch (const Error& e) {
      throw RequestError(400, e.what(), location_of(e));
    }
  }
  if (!s_->options.solve_while_saving) {
    // Saved first (before_change), then the solve is scheduled.
    std::lock_guard change(s_->change_mutex);
    std::lock_guard lock(s_->mutex);
    check_revision(on_revision, s_->design->revision(), "scene");
    s_->design->set_scene(std::move(next));
    s_->schedule();
    return s_->scene_json();
  }
  // The new scene's solve starts at once, while the scene is saved (the durable save,
  // two fsyncs, takes 10–60 ms on a busy disk; issue 15); the answer, the new revision and
  // everything the solve makes (its shown frame, its field) only once the save succeeded.
  // A failed save changes nothing: the solve is dropped and the current one goes on.
  std::lock_guard change(s_->change_mutex);
  {
    std::lock_guard lock(s_->mutex);
    check_revision(on_revision, s_->design->revision(), "scene");
    if (s_->cancel) s_->cancel->store(true);
    s_->next_job.emplace(s_->design->prepare_solve(next));
    s_->upcoming = s_->next_job->revision();
    s_->early.reset();
    s_->held_preview.reset();
    s_->pending = true;
    s_->stop_analysis();
    s_->work.notify_one();
  }
  try {
    save_scene(next, s_->scene_path().string());
  } catch (...) {
    std::lock_guard lock(s_->mutex);
    s_->upcoming = 0;
    s_->next_job.reset();
    s_->early.reset();
    s_->held_preview.reset();
    s_->analysis_work.notify_one();  // it waited for the new scene
    if (s_->cancel) s_->cancel->store(true);
    // The current revision's solve may have been cancelled for the new one: again.
    if (!(s_->result && s_->result->revision == s_->design->revision()) && s_->state != "failed") s_->schedule();
    throw;
  }
  std::lock_guard lock(s_->mutex);
  s_->saved_already = true;
  s_->design->set_scene(std::move(next));
  s_->saved_already = false;
  s_->upcoming = 0;
  s_->analysis_work.notify_one();  // it waited for the new scene
  s_->state = "running";
  s_->error.clear();
  if (s_->next_job) {  // the worker has not taken the new scene's solve yet: nothing done
    s_->done = 0;
    s_->total = s_->design->scene().time.frames;
    s_->stage.clear();
  }
  if (s_->held_preview && s_->held_preview->revision == s_->design->revision()) s_->preview = std::move(s_->held_preview);
  s_->held_preview.reset();
  if (s_->early && s_->early->job->revision() == s_->design->revision()) s_->finish(*s_->early->job, s_->early->seconds, s_->early->failure);
  s_->early.reset();
  s_->touch();
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
  // The edit on the current revision: the scene with it appended, validated (400 naming
  // its JSON path) under the lock; applied below without it.
  std::optional<Design::EditJob> job;
  {
    std::lock_guard lock(s_->mutex);
    check_revision(on_revision, s_->design->revision(), "edit");
    try {
      job.emplace(s_->design->prepare_edit(entry, s_->options.scene));
    } catch (const Error& e) {
      throw RequestError(400, e.what(), location_of(e));
    }
  }
  s_->check_scene_paths(job->scene());
  const std::string where = fmt::format("edits[{}]", job->scene().edits.size() - 1);

  // The field of the revision the edit was made on (no lock held while waiting).
  const std::shared_ptr<const Result> r = s_->result_of(job->revision(), "edit", deadline);
  const auto start = std::chrono::steady_clock::now();
  EditReport report;
  try {
    report = job->run(r->made, false);  // its analysis follows on the analysis thread
  } catch (const EditRefused& refused) {
    throw RequestError(422, fmt::format("refused to {}: {}; the scene is unchanged", describe(job->edit()),
                                        refused.what()));
  } catch (const Error& err) {
    throw RequestError(422, fmt::format("{}: {}", where, err.what()), location_of(err));
  }
  auto made = std::make_shared<Result>();
  made->scene = job->scene();
  made->made = job->result();
  made->seconds = std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();

  std::lock_guard change(s_->change_mutex);
  std::lock_guard lock(s_->mutex);
  check_revision(job->revision(), s_->design->revision(), "edit");
  s_->design->adopt(std::move(*job));  // saves the scene first (before_change)
  made->revision = s_->design->revision();
  if (s_->cancel) s_->cancel->store(true);
  s_->publish(std::move(made));
  s_->state = "ready";
  s_->error.clear();
  s_->touch();
  return {{"revision", s_->design->revision()}, {"summary", report.summary}};
}

json Session::undo(long long on_revision) {
  std::lock_guard change(s_->change_mutex);
  std::lock_guard lock(s_->mutex);
  check_revision(on_revision, s_->design->revision(), "undo");
  if (!s_->design->can_undo()) throw RequestError(409, "nothing to undo");
  s_->design->undo();  // saves the scene first (before_change)
  s_->schedule();
  return s_->scene_json();
}

json Session::redo(long long on_revision) {
  std::lock_guard change(s_->change_mutex);
  std::lock_guard lock(s_->mutex);
  check_revision(on_revision, s_->design->revision(), "redo");
  if (!s_->design->can_redo()) throw RequestError(409, "nothing to redo");
  s_->design->redo();
  s_->schedule();
  return s_->scene_json();
}

json Session::status() const {
  std::lock_guard lock(s_->mutex);
  json j = {{"revision", s_->design->revision()},
            {"result_revision", s_->result ? s_->result->revision : 0},
            {"state", s_->state},
            {"progress", {s_->done, s_->total}},
            {"error", s_->error},
            {"cancelled", s_->cancelled},
            {"analyses_stopped", s_->analyses_stopped}};
  if (!s_->stage.empty() && s_->state == "running") j["stage"] = s_->stage;
  if (s_->result) {
    const Result& r = *s_->result;
    j["warnings"] = r.made->report.warnings;
    j["method"] = r.made->report.method;
    // Topology between key frames: per interval, whether it was guided and, if not, why
    // (the designer shows it beside the picture; keyframe_topology.json has the rest).
    if (!r.made->report.keyframe_intervals.empty()) {
      json intervals = json::array();
      for (const KeyframeIntervalReport& k : r.made->report.keyframe_intervals) {
        json i = {{"keyframes", {k.from_keyframe, k.to_keyframe}},
                  {"guided", k.guided},
                  {"fallback", k.fallback},
                  {"routing", k.routing},
                  {"matched", k.matched.size()},
                  {"linked", std::count_if(k.matched.begin(), k.matched.end(), [](const auto& m) { return m.linked; })},
                  {"created", k.created.size()},
                  {"cancelled", k.cancelled.size()},
                  // Nodes the guide leaves turning a whole turn (the warning says which).
                  {"turning", std::count_if(k.matched.begin(), k.matched.end(),
                                            [](const auto& m) { return m.phase_turns != 0; })}};
        if (!k.unguided_reason.empty()) i["unguided_reason"] = k.unguided_reason;
        if (k.first_wrong) i["first_wrong"] = wrong_frame_json(*k.first_wrong);
        if (k.collision_at) i["collision_at"] = collision_json(*k.collision_at);
        // The default separation lowered where it could not be kept: from what, to what.
        if (k.lowered_from > 0) i["lowered_from"] = k.lowered_from, i["separation"] = k.separation;
        // The key frame that would hold a turning node (the designer's "add this key frame").
        if (k.middle_keyframe) i["middle_keyframe"] = middle_keyframe_json(*k.middle_keyframe);
        intervals.push_back(std::move(i));
      }
      j["keyframe_intervals"] = std::move(intervals);
    }
    j["seconds"] = r.seconds;
    j["domain"] = r.domain;
    j["analysis"] = r.analysed() ? "ready" : r.analysis_error.empty() ? "running" : "failed";
    if (!r.analysis_error.empty()) j["analysis_error"] = r.analysis_error;
    if (r.analysis) j["analysis_seconds"] = r.analysis->seconds;
  }
  j["analysis_revision"] = s_->analysed_revision;
  // The shown frame of the solve under way, ready before the other frames: GET /api/preview.
  if (s_->preview && (!s_->result || s_->preview->revision > s_->result->revision)) {
    j["preview_revision"] = s_->preview->revision;
    j["preview_frame"] = s_->preview->frame;
  }
  j["sequence"] = s_->changes;
  j["session"] = s_->id;
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
    return (s_->result && s_->result->revision == s_->design->revision()) || s_->state == "failed";
  });
}

json Session::mesh() const {
  const auto r = s_->current_result();
  const Mesh& m = r->space().mesh();
  const bool planar = r->scene.domain.is_planar();
  std::vector<float> v;
  v.reserve(static_cast<size_t>(m.num_vertices()) * 3);
  for (const Vec3& p : m.positions())
    for (int k = 0; k < 3; ++k) v.push_back(static_cast<float>(p[k]));
  std::vector<int> f;
  f.reserve(static_cast<size_t>(m.num_faces()) * 3);
  for (const Face& face : m.faces()) f.insert(f.end(), face.begin(), face.end());
  json j = {{"revision", r->revision}, {"domain", r->domain}, {"planar", planar}, {"vertices", compact(v)}, {"faces", f}};
  if (planar) {
    const GridSpec& g = *r->scene.domain.grid;
    j["grid"] = {{"size", {g.nx, g.ny}}, {"min", {g.min.x(), g.min.y()}}, {"max", {g.max.x(), g.max.y()}}};
  }
  return j;
}

json Session::frame(int j) const {
  std::vector<float> vectors;
  json out = frame_parts(j, vectors);
  out["vectors"] = compact(vectors);
  return out;
}

std::string Session::frame_f32(int j) const {
  std::vector<float> vectors;
  return binary_frame(frame_parts(j, vectors), vectors);
}

json Session::preview() const {
  std::vector<float> vectors;
  json out = preview_parts(vectors);
  out["vectors"] = compact(vectors);
  return out;
}

std::string Session::preview_f32() const {
  std::vector<float> vectors;
  return binary_frame(preview_parts(vectors), vectors);
}

json Session::frame_parts(int j, std::vector<float>& vectors) const {
  const auto r = s_->current_result();
  const int frames = r->field().frames();
  if (j < 0 || j >= frames)
    throw RequestError(400, fmt::format("frame: {} is outside [0, {}]", j, frames - 1));
  {
    std::lock_guard lock(s_->mutex);
    s_->focus_frame = j;  // the next solve makes this frame first (preview())
  }
  const bool planar = r->scene.domain.is_planar();
  json sing = json::array();
  // The frame's singularities: the analysis's, with their paths; before it is there, found
  // for this frame alone (the same list: topology.h), with "path" −1.
  const std::vector<Singularity> own =
      r->analysed() ? std::vector<Singularity>() : find_singularities(r->space().bundle(), r->field(), j);
  const auto& list = r->analysed() ? r->topology().singularities[static_cast<size_t>(j)] : own;
  for (size_t k = 0; k < list.size(); ++k)
    sing.push_back({{"position", vec3(list[k].position, planar)},
                    {"type", to_string(list[k].type)},
                    {"index", list[k].index},
                    {"path", r->analysed() ? r->topology().singularity_path[static_cast<size_t>(j)][k] : -1}});
  vectors = world_vectors_f32(r->space().bundle(), r->field(), j);
  return {{"revision", r->revision},
          {"frame", j},
          {"frames", frames},
          {"t", r->field().time().time(j)},
          {"singularities", sing}};
}

json Session::preview_parts(std::vector<float>& world) const {
  std::shared_ptr<const Preview> p;
  long long result_revision = 0;
  {
    std::lock_guard lock(s_->mutex);
    p = s_->preview;
    result_revision = s_->result ? s_->result->revision : 0;
  }
  if (!p || p->revision <= result_revision)
    throw RequestError(404, "preview: no solve under way has its first frame ready; read GET /api/frame/J");
  json sing = json::array();
  for (const Singularity& x : find_singularities(p->space->bundle(), p->values))
    sing.push_back({{"position", vec3(x.position, p->planar)},
                    {"type", to_string(x.type)},
                    {"index", x.index},
                    {"path", -1}});
  world.clear();
  world.reserve(p->values.size() * 3);
  const TangentBundle& bundle = p->space->bundle();
  for (size_t v = 0; v < p->values.size(); ++v) {
    const Vec3 w = bundle.vertex_to_world(static_cast<int>(v), p->values[v]);
    for (int k = 0; k < 3; ++k) world.push_back(static_cast<float>(w[k]));
  }
  return {{"revision", p->revision},
          {"frame", p->frame},
          {"frames", p->frames},
          {"t", p->t},
          {"preview", true},
          {"singularities", sing}};
}

json Session::analysis() const {
  // The analysis of the current result, waiting for it (it follows the field) up to
  // field_wait_seconds; a newer result while waiting: its analysis.
  std::shared_ptr<const Result> r = s_->current_result();
  {
    std::unique_lock lock(s_->mutex);
    s_->changed.wait_until(lock, s_->wait_deadline(), [&] {
      r = s_->result;
      return s_->interrupted || r->analysed() || !r->analysis_error.empty();
    });
    if (s_->interrupted) throw RequestError(503, "analysis: the server is stopping");
  }
  if (!r->analysis_error.empty())
    throw RequestError(409, fmt::format("analysis: the field of revision {} could not be analysed: {}", r->revision,
                                        r->analysis_error));
  if (!r->analysed())
    throw RequestError(409, fmt::format("analysis: the analysis of revision {} is still running; try again when "
                                        "/api/status says its analysis is ready",
                                        r->revision));
  json j = topology_to_json(r->topology());
  add_periodic_orbits_to_json(j, r->orbits());
  j["revision"] = r->revision;
  return j;
}

Session::FieldView Session::current_field() const {
  const auto r = s_->current_result();
  return {r, &r->space().bundle(), &r->field(), r->scene.domain.is_planar(), r->revision};
}

namespace {

// The two positions of a chart request (`op`: its name in errors): [x, y] on grids,
// [x, y, z] on surfaces, finite and within the scene's number bound.
std::pair<Vec3, Vec3> chart_request(const json& request, const char* op, const char* from, bool planar) {
  if (!request.is_object())
    throw RequestError(400, fmt::format("{}: expected {{\"{}\": position, \"to\": position}}", op, from));
  auto position = [&](const char* key) {
    const size_t n = planar ? 2 : 3;
    const auto it = request.find(key);
    if (it == request.end() || !it->is_array() || it->size() != n ||
        !std::all_of(it->begin(), it->end(), [](const json& v) { return v.is_number(); }))
      throw RequestError(400, fmt::format("{}: \"{}\" must be a position of {} numbers on this {}", op, key, n,
                                          planar ? "grid" : "surface"));
    Vec3 x = Vec3::Zero();
    for (size_t k = 0; k < n; ++k) x[static_cast<int>(k)] = (*it)[k].get<double>();
    if (!x.allFinite()) throw RequestError(400, fmt::format("{}: \"{}\" is not finite", op, key));
    // The same bound as every number of a scene (docs/scene_reference.md, "Limits").
    if (x.cwiseAbs().maxCoeff() > 1e15)
      throw RequestError(400, fmt::format("{}: \"{}\" has a coordinate of magnitude over 1e15", op, key));
    return x;
  };
  return {position(from), position("to")};
}

}  // namespace

json Session::seed_translation(const json& request) const {
  const auto r = s_->current_result();
  const bool planar = r->scene.domain.is_planar();
  const auto [seed, to] = chart_request(request, "seed_translation", "seed", planar);
  try {
    return {{"translate", vec3(tvf::seed_translation(r->space(), seed, to), planar)}};
  } catch (const Error& e) {
    throw RequestError(422, e.what());
  }
}

json Session::chart_coordinates(const json& request) const {
  const auto r = s_->current_result();
  const auto [at, to] = chart_request(request, "chart_coordinates", "at", r->scene.domain.is_planar());
  try {
    const cplx w = tvf::chart_coordinates(r->space(), at, to);
    return {{"coords", {w.real(), w.imag()}}};
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
    for (const fs::path& f : write_field_outputs(out, r->space(), r->field(), r->scene, o))
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
    const TextureAnimationReport rep = write_texture_animation(r->space().bundle(), r->field(), o);
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
