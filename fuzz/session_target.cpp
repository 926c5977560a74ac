#include "targets.h"

#include "tvf/core/json_text.h"
#include "tvf/serve/session.h"

#include <unistd.h>

#include <filesystem>
#include <memory>
#include <string>

namespace tvf::fuzz {
namespace {

// One small session for the whole run (a 9 × 9 grid, 6 frames), ready before the first
// request: requests exercise the request functions, not the solver's cost.
serve::Session& the_session() {
  static std::unique_ptr<serve::Session> session = [] {
    serve::SessionOptions o;
    o.dir = std::filesystem::temp_directory_path() / ("tvf-fuzz-session-" + std::to_string(::getpid()));
    std::filesystem::remove_all(o.dir);
    o.initial_scene = R"({"tvf": 1, "domain": {"grid": {"size": [9, 9]}}, "time": {"frames": 6},
      "elements": [{"kind": "singular", "type": "ccw_center", "path": [[-0.3, 0, 0], [0.3, 0, 1]]},
                   {"kind": "singular", "type": "saddle", "path": [[0.5, 0.5, 0]]}]})";
    o.parallel = false;
    o.field_wait_seconds = 30;
    auto s = std::make_unique<serve::Session>(o);
    s->wait_idle(60);
    return s;
  }();
  return *session;
}

}  // namespace

// The first byte picks the request, the rest is its JSON body, read as the server reads
// it (parse_json_text). put_scene is left out: its scenes are the scene target's, and a
// valid one may ask for a 50-million-vertex solve.
void session(std::string_view data) {
  serve::Session& s = the_session();
  if (data.empty()) return;
  const char which = data[0];
  const std::string body(data.substr(1));
  try {
    const nlohmann::json request = body.empty() ? nlohmann::json::object() : parse_json_text(body, "request body");
    switch (which % 4) {
      case 0:
        s.seed_translation(request);
        break;
      case 1:
        s.edit(request);
        s.undo();  // back to the one scene, so that runs stay independent
        break;
      case 2:
        if (request.is_number_integer()) s.frame(request.get<int>());
        break;
      default:
        s.analysis();
        s.status();
        break;
    }
  } catch (const InternalError&) {
    throw;
  } catch (const Error&) {
    // refused with a message (RequestError is a tvf::Error)
  }
}

}  // namespace tvf::fuzz
