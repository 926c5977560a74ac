#include "targets.h"

#include "tvf/core/error.h"
#include "tvf/core/json_text.h"
#include "tvf/scene/scene_json.h"
#include "tvf/serve/session.h"

#include <unistd.h>

#include <algorithm>
#include <cstdio>
#include <cstdlib>
#include <filesystem>
#include <memory>
#include <string>

namespace tvf::fuzz {
namespace {

namespace fs = std::filesystem;

// One small session for the whole run (a 9 × 9 grid, 6 frames), ready before the first
// request: requests exercise the request functions, not the solver's cost. Its field is
// exported once to export/ (so that a fuzzed scene may name export/field.tvff as a key
// frame's field). Its working folder (under $TMPDIR) is removed when the program ends.
struct Fixture {
  fs::path dir;
  std::unique_ptr<serve::Session> session;
  Fixture() : dir(fs::temp_directory_path() / ("tvf-fuzz-session-" + std::to_string(::getpid()))) {
    fs::remove_all(dir);
    serve::SessionOptions o;
    o.dir = dir;
    o.initial_scene = R"({"tvf": 1, "domain": {"grid": {"size": [9, 9]}}, "time": {"frames": 6},
      "elements": [{"kind": "singular", "type": "ccw_center", "path": [[-0.3, 0, 0], [0.3, 0, 1]]},
                   {"kind": "singular", "type": "saddle", "path": [[0.5, 0.5, 0]]}]})";
    o.parallel = false;
    o.field_wait_seconds = 15;
    session = std::make_unique<serve::Session>(o);
    session->wait_idle(60);
    session->export_field(nlohmann::json::object());
  }
  ~Fixture() {
    session.reset();
    std::error_code ec;
    fs::remove_all(dir, ec);
  }
  Fixture(const Fixture&) = delete;
  Fixture& operator=(const Fixture&) = delete;
};

serve::Session& the_session() {
  static Fixture fixture;
  return *fixture.session;
}

// TVF_FUZZ_VERBOSE=1 prints what each request was answered (to check that seeds reach
// the code they are meant for rather than being refused early).
void note(const std::string& what) {
  static const bool verbose = std::getenv("TVF_FUZZ_VERBOSE") != nullptr;
  if (verbose) std::fprintf(stderr, "fuzz_session: %s\n", what.substr(0, 300).c_str());
}

// A solve of the background worker ended in an internal check (the worker reports every
// exception as the scene's failure, so the fuzzer would not see it otherwise).
void check_not_internal(const serve::Session& s) {
  const nlohmann::json st = s.status();
  const std::string error = st.value("error", "");
  if (error.find("internal error") != std::string::npos) {
    std::fprintf(stderr, "fuzz_session: the solve stopped at an internal check: %s\n", error.c_str());
    std::abort();
  }
}

// What a request may leave in the working folder besides the scene and export/ goes.
void clean(const serve::Session& s) {
  std::error_code ec;
  for (const auto& e : fs::directory_iterator(s.dir(), ec)) {
    const std::string name = e.path().filename().string();
    if (name != "scene.json" && name != "export") fs::remove_all(e.path(), ec);
  }
}

// Everything a client reads of the current result (each may be refused: no field yet).
void read_all(serve::Session& s) {
  // Serialised strictly, as JSON answers must be (dump throws on invalid UTF-8: a message
  // quoting a file's bytes once did).
  s.status().dump();
  s.scene().dump();
  try {
    const nlohmann::json m = s.mesh();
    const bool planar = m.value("planar", true);
    s.analysis().dump();
    s.frame(0);
    // A seed at the first vertex, moved to the second.
    const nlohmann::json& x = m.at("vertices");
    if (x.size() >= 6) {
      nlohmann::json seed = {x[0], x[1]}, to = {x[3], x[4]};
      if (!planar) {
        seed.push_back(x[2]);
        to.push_back(x[5]);
      }
      s.seed_translation({{"seed", seed}, {"to", to}});
    }
    s.export_field({{"dir", "check"}, {"format", "npy"}});
    note("read all");
  } catch (const Error& e) {
    note(std::string("read refused: ") + e.what());
  }
  clean(s);
}

// Back to the one scene (and its field), so that inputs stay independent.
void back_to_start(serve::Session& s, long long revision) {
  while (s.revision() > revision) {
    try {
      s.undo();
    } catch (const Error&) {
      break;
    }
  }
  s.wait_idle(30);
  check_not_internal(s);
}

// Scenes small enough to solve in a moment (vertices × frames), so that a fuzzed scene
// exercises the session's whole change (parse, save, solve, read) and not the solver's
// cost. One the reader refuses is still sent: its refusal is the session's to give.
bool small_enough(const serve::Session& s, const nlohmann::json& j) {
  Scene scene;
  try {
    scene = scene_from_json(j, "scene.json", s.scene_path().string());
  } catch (const Error&) {
    return true;
  }
  long long vertices = 0;
  const Domain& d = scene.domain;
  if (d.grid) vertices = static_cast<long long>(d.grid->nx) * d.grid->ny;
  if (d.sphere) vertices = d.sphere->subdivisions <= 3 ? 10LL * (1LL << (2 * d.sphere->subdivisions)) + 2 : 1LL << 40;
  if (d.torus) vertices = static_cast<long long>(d.torus->nu) * d.torus->nv;
  if (!d.mesh.empty()) vertices = 500;  // a file of the working folder: an upload, at most max_len bytes
  return vertices * scene.time.frames <= 6000 && scene.time.frames <= 40 && scene.edits.size() <= 4 &&
         scene.keyframes.size() <= 6;
}

// A whole scene change (PUT /api/scene), then every read of its field.
void change_scene(serve::Session& s, const nlohmann::json& scene) {
  if (!small_enough(s, scene)) return;
  const long long start = s.revision();
  try {
    s.put_scene(scene, start);
  } catch (const Error& e) {
    note(std::string("scene refused: ") + e.what());
    return;
  }
  s.wait_idle(30);
  check_not_internal(s);
  note("scene: " + s.status().dump());
  read_all(s);
  back_to_start(s, start);
}

}  // namespace

// The first byte picks the request, the rest is its body, read as the server reads it
// (parse_json_text): the request functions of GET/PUT /api/scene, POST /api/edit,
// /api/seed_translation, /api/export, /api/render, /api/upload, and the reads of
// /api/frame, /api/analysis, /api/mesh, /api/status. Every request that changes the
// scene is undone afterwards, and what it wrote in the working folder removed.
void session(std::string_view data) {
  serve::Session& s = the_session();
  if (data.empty()) return;
  const auto which = static_cast<unsigned char>(data[0]) % 8;
  std::string body(data.substr(1));
  try {
    if (which == 6) {
      // An upload: the file name on the first line, the file after it, then a scene on it.
      const size_t eol = body.find('\n');
      const std::string name = body.substr(0, std::min(eol, body.size()));
      const std::string bytes = eol == std::string::npos ? std::string() : body.substr(eol + 1);
      try {
        s.upload_mesh(name, bytes);
        change_scene(s, {{"tvf", 1},
                         {"domain", {{"mesh", name}}},
                         {"time", {{"frames", 3}}},
                         {"elements", {{{"kind", "singular"}, {"type", "source"}, {"path", {{0, 0, 0, 0}}}}}}});
      } catch (const Error&) {
        clean(s);
        throw;
      }
      clean(s);
      return;
    }
    const nlohmann::json request = body.empty() ? nlohmann::json::object() : parse_json_text(body, "request body");
    switch (which) {
      case 0:
        s.seed_translation(request);
        break;
      case 1: {
        const long long start = s.revision();
        s.edit(request);
        read_all(s);
        back_to_start(s, start);
        break;
      }
      case 2:
        if (request.is_number_integer()) s.frame(request.get<int>());
        break;
      case 3:
        read_all(s);
        break;
      case 4:
        change_scene(s, request);
        break;
      case 5:
        try {
          s.export_field(request);
        } catch (const Error&) {
          clean(s);
          throw;
        }
        clean(s);
        break;
      default: {
        // A render: PNG frames only (an .mp4 runs ffmpeg), small and few.
        if (!request.is_object()) break;
        nlohmann::json r = request;
        if (r.contains("name") && r["name"].is_string() && fs::path(r["name"].get<std::string>()).has_extension())
          break;
        if (!r.contains("name")) r["name"] = "frames";
        if (!r.contains("size") || (r["size"].is_number_integer() && r["size"].get<long long>() > 48)) r["size"] = 32;
        if (!r.contains("frames") || (r["frames"].is_number_integer() && r["frames"].get<long long>() > 2))
          r["frames"] = 2;
        try {
          s.render_video(r);
        } catch (const Error&) {
          clean(s);
          throw;
        }
        clean(s);
        break;
      }
    }
  } catch (const InternalError&) {
    throw;
  } catch (const Error& e) {
    // Refused with a message (RequestError is a tvf::Error), which the server answers as
    // {"error": message}: serialised strictly here, so that a message that is not UTF-8 fails.
    static_cast<void>(nlohmann::json{{"error", e.what()}}.dump());
    note(std::string("refused: ") + e.what());
    return;
  }
  note("answered");
}

}  // namespace tvf::fuzz
