#pragma once
// The designer's session (issue 7, docs/serve_api.md): one scene in a working folder, the
// field it makes, its analysis, and the history of changes. Headless and socket-free:
// http_server.h puts it on HTTP; tests drive it directly or over HTTP.
//
// - Every change (a new scene, an edit, undo, redo) is validated first, then the scene is
//   saved to the working folder (atomically, scene_json.h's save_scene), so a restarted
//   session comes back to the last design; a refused change leaves scene and file as
//   they were.
// - The field is generated in a background thread. A newer change cancels the older
//   solve (GenerateOptions::cancel); readers always get the last finished result, tagged
//   with the revision of the scene that made it. The field is published as soon as it is
//   made; its analysis (topology, periodic orbits) follows on a second thread, while the
//   worker is already free for the next change (issue 15: the picture does not wait for
//   the analysis of all frames). The solver set-up (Laplacian, symbolic
//   factorizations, the space-time solver and its temporal modes) and the last
//   space-time solution are kept between solves (GenerateCache), so a re-solve after a
//   small change starts warm.
// - Revisions: every change names the revision it was made on (see put_scene); a change
//   on a stale revision is refused (412), so two clients never overwrite each other.
// - Start: stale temporary files of a crashed session (".scene.json.tmp-PID-N" of a
//   process that no longer runs) are removed from the working folder.
// - Paths: every file the session reads or writes (the scene, meshes and key-frame field
//   files named by the scene, exports, videos, uploads) lies inside the working folder;
//   a path that leaves it is refused.
#include "tvf/core/error.h"
#include "tvf/core/error_location.h"
#include "tvf/core/json_text.h"

#include <nlohmann/json.hpp>

#include <chrono>
#include <filesystem>
#include <memory>
#include <string>
#include <vector>

namespace tvf {
class TangentBundle;
class Field;
}  // namespace tvf

namespace tvf::serve {

// A request that cannot be served: an HTTP status (400 bad input, 403 path outside the
// working folder, 404 missing, 409 conflict/no field yet, 412 made on a revision that is
// no longer current, 422 refused edit, 503 busy or stopping) and one sentence saying why.
class RequestError : public LocatedError {
public:
  // The message is kept as valid UTF-8 (valid_utf8): it is answered as JSON.
  RequestError(int status, const std::string& message, ErrorLocation location = {})
      : LocatedError(valid_utf8(message), std::move(location)), status_(status) {}
  int status() const { return status_; }

private:
  int status_;
};

struct SessionOptions {
  std::filesystem::path dir = ".";     // working folder (created if missing)
  std::string scene = "scene.json";    // scene file, relative to dir
  // Scene text used when the scene file does not exist yet (e.g. the default demo scene).
  std::string initial_scene;
  bool parallel = true;                // frames in parallel while generating
  int history = 200;                   // undo steps kept (in memory)
  // How long an edit, an export or a render waits for the field of the revision it was
  // asked for (the running solve) before answering 409 "still being generated". The
  // wait holds no lock: status, reads and other changes go on meanwhile.
  double field_wait_seconds = 20;
  // put_scene starts the new scene's solve while the scene is being saved (its fsyncs:
  // 10–400 ms on a busy disk), publishing nothing of it before the save succeeded (issue
  // 15). On by default; `tvf serve --save-before-solve` turns it off. (It was off while
  // the designer's page missed pushed analysis events with it: the page took a poll's late
  // answer for newer than a pushed event; statuses now carry their `sequence`.)
  bool solve_while_saving = true;
};

// The revision a change was made on (HTTP If-Match): kAnyRevision accepts the change on
// whatever revision is current (scripts that do not send If-Match).
inline constexpr long long kAnyRevision = 0;

class Session {
public:
  // Loads dir/scene (or writes initial_scene there) and starts generating it. Throws
  // tvf::Error when the scene file is invalid (naming the file and JSON path).
  explicit Session(SessionOptions options);
  ~Session();  // cancels the running solve and joins the worker
  Session(const Session&) = delete;
  Session& operator=(const Session&) = delete;

  const std::filesystem::path& dir() const;
  std::filesystem::path scene_path() const;

  // {"revision", "scene", "text" (the file's text, scene_to_text), "path", "can_undo",
  //  "can_redo"}
  nlohmann::json scene() const;
  // Every change below takes `on_revision`, the revision the client made it on (HTTP
  // If-Match). When that is no longer the current revision (another tab or client
  // changed the scene since), the change is refused with RequestError(412) naming both
  // revisions, and nothing changes: no change is lost silently. kAnyRevision: applied to
  // the current scene, whatever it is.
  //
  // Replaces the whole scene (validated; its edits are checked when it generates).
  // Returns scene(). Throws RequestError(400) naming the JSON path of a problem.
  nlohmann::json put_scene(const nlohmann::json& scene, long long on_revision = kAnyRevision);
  // Appends one entry to the scene's `edits` (DESIGN §7: {"op": "cancel", "frame": 40,
  // "pair": [[x, y], [x, y]]}, remove_bifurcation, move_bifurcation, smooth). It is
  // applied to the field of the revision it was made on (waiting for that field up to
  // field_wait_seconds, holding no lock: 409 when it is not ready by then, 412 as soon as
  // the scene moves on); a refused edit is RequestError(422) and changes nothing. The
  // edited field becomes the current result at once, without regenerating. With
  // kAnyRevision an edit overtaken by another change is applied again to the newer field
  // (up to four tries within field_wait_seconds).
  // Returns {"revision", "summary"}.
  nlohmann::json edit(const nlohmann::json& edit, long long on_revision = kAnyRevision);
  nlohmann::json undo(long long on_revision = kAnyRevision);  // RequestError(409): nothing to undo
  nlohmann::json redo(long long on_revision = kAnyRevision);
  // The current revision (the scene's ETag).
  long long revision() const;

  // {"revision", "result_revision", "state": "running" | "ready" | "failed",
  //  "progress": [done, total], "error", "cancelled" (solves stopped by newer changes so
  //  far), "warnings", "method", "seconds" (the solve), "domain" (an id of the result's
  //  domain: it changes when the mesh does), "analysis": "running" | "ready" | "failed" (of
  //  the result; "analysis_error" says why it failed), "analysis_seconds",
  //  "analysis_revision" (the revision of the last analysis made; 0 before the first),
  //  "sequence" (wait_change's count when this status was read: statuses of one session
  //  are ordered by it, whatever order they arrive in), "session" (an id of this Session:
  //  another one after a restart)}
  nlohmann::json status() const;
  // The number of changes of status() so far that a client may be told of: a new
  // revision, the generation state (running, ready, failed) or a new result. It waits up
  // to `seconds` while that number is still `seen` (0 never is: it returns at once), then
  // returns it; −1 once interrupt() was called (the server is stopping). GET /api/events.
  long long wait_change(long long seen, double seconds) const;
  // Waits until the current revision has a result or failed; false on timeout.
  bool wait_idle(double seconds) const;

  // The domain of the last result: {"revision", "domain" (status's id), "planar", "grid": {"size", "min", "max"}
  // (planar grids), "vertices": [x, y, z, ...], "faces": [i, j, k, ...]}.
  nlohmann::json mesh() const;
  // One frame of the last result: {"revision", "frame", "t", "frames", "vectors": world
  // [x, y, z] per vertex, flattened, "singularities": [{"position", "type", "index",
  // "path"}]}: "path" is the id in the analysis, −1 while the analysis of the result is
  // still running (the singularities are found for this frame alone then: the same list).
  // Frame in [0, frames − 1]. RequestError(409) before the first result. The frame read
  // last is the one the next solve makes first (preview()).
  nlohmann::json frame(int frame) const;
  // The same frame in binary (docs/serve_api.md, "Binary frames": GET /api/frame/J?format=f32):
  // a 4-byte little-endian length n, n bytes of the JSON above without "vectors" and with
  // "count" (the number of floats), then the vectors as `count` little-endian float32
  // values. A quarter of the JSON's bytes on a 65² grid, and nothing to print or parse.
  std::string frame_f32(int frame) const;
  // The frame a client shows, ready before the rest of a solve under way (issue 15): the
  // frame asked for last (frame()) is made first by the generators that solve frame by
  // frame (basis, constrained, deform; not spacetime, not for scenes with edits or an
  // incompressible projection, nor on another domain than the last result's), and
  // published here as soon as it is solved, with status's "preview_revision" and
  // "preview_frame". The same JSON as frame() plus "preview": true,
  // singularities found for the frame alone ("path" −1); its values are the final field's.
  // RequestError(404) when no solve under way has one newer than the last result.
  nlohmann::json preview() const;
  std::string preview_f32() const;  // the same in binary, as frame_f32
  // The analysis JSON of DESIGN §9 of the last result, plus "revision". Waits for it (it
  // follows the field; a newer result meanwhile: the newer one's) up to
  // field_wait_seconds: RequestError(409) when it is not there by then or failed.
  nlohmann::json analysis() const;

  // Export and render write the field of the current revision (following newer changes
  // while they wait), or of `on_revision` (412 when that is no longer current): they wait
  // for it up to field_wait_seconds while a solve runs, and answer RequestError(409)
  // naming the revision when it is not ready by then, never the field of an older
  // design. Their answers carry "revision".
  //
  // Writes the field outputs of `tvf generate` (npy, native, and VTK unless format is
  // "npy") into the folder request["dir"] (default "export") inside the working folder.
  // Returns {"revision", "files": [paths relative to the working folder]}.
  nlohmann::json export_field(const nlohmann::json& request, long long on_revision = kAnyRevision);
  // Renders the texture animation of the last result to request["name"] (default
  // "video.mp4"; .mp4 needs ffmpeg; a name without extension is a folder of PNG frames)
  // with request["size"] pixels (default 512), request["frames"] pictures (default: the
  // field's frames) and singularity markers unless request["singularities"] is false;
  // request["paths"] adds the singularity paths. Planar domains and surfaces; on surfaces
  // request["view"] (direction from the mesh's centre to the camera), ["up"] and ["fov"]
  // (degrees) place the camera (the designer sends its own). One video at a time: a
  // second request while one renders is RequestError(503).
  nlohmann::json render_video(const nlohmann::json& request, long long on_revision = kAnyRevision);
  // The `translate` of a deform.streamlines key that moves the seed request["seed"] to
  // request["to"] (positions as the domain writes them), in the domain of the last
  // result (seed_translation, streamline_deform.h): {"translate": [x, y] or [x, y, z]}.
  // RequestError(400) for a malformed position, 422 for a point too far from the seed on
  // a surface, 409 before the first result.
  nlohmann::json seed_translation(const nlohmann::json& request) const;
  // Lagrangian descriptors of the last result for the designer's overlays
  // (session_lcs.cpp, docs/serve_api.md): RequestError(400) naming the key of a bad
  // parameter, 409 before the first result.
  // FTLE at one time: request {"t", "horizon", "direction": "forward" | "backward"} →
  // {"revision", "t", "horizon", "direction", "span", "cut", "left", "min", "max", "range"
  // (colour range: 1st and 99th percentiles), "values": σ per vertex (null where
  // undefined), "seconds"}.
  nlohmann::json ftle(const nlohmann::json& request) const;
  // Streakline: {"seed", "from", "to", "spacing" (optional)} → {"revision", "t", "points",
  // "gaps" (indices of points with a gap before them), "released", "left", "seconds"}.
  nlohmann::json streakline(const nlohmann::json& request) const;
  // Timeline: {"line": [a, b], "from", "to", "count" (optional)} → the same answer.
  nlohmann::json timeline(const nlohmann::json& request) const;
  // {"at": position, "to": position}: the local coordinates of `to` in the chart an
  // element at `at` is designed in (chart_coordinates, streamline_deform.h), {"coords":
  // [u, v]}: a bifurcation's angle is their argument (the designer's Bifurcation drag).
  // The same errors as seed_translation.
  nlohmann::json chart_coordinates(const nlohmann::json& request) const;
  // Stores an uploaded mesh (OBJ, PLY or OFF, by the name's extension) in the working
  // folder under `name` (a plain file name). Returns {"file": name}.
  nlohmann::json upload_mesh(const std::string& name, const std::string& bytes);

  // A path inside the working folder for a relative path from a request; throws
  // RequestError(400) for an empty or absolute path and RequestError(403) for one that
  // leaves the folder (through "..", or a link).
  std::filesystem::path resolve(const std::string& relative) const;

  // Wakes every request waiting for a field (they answer 503 "the server is stopping")
  // and cancels the running solve; later waits end at once. For a prompt shutdown.
  void interrupt();

private:
  nlohmann::json edit_on(const nlohmann::json& edit, long long on_revision,
                         std::chrono::steady_clock::time_point deadline);
  struct State;
  std::unique_ptr<State> s_;
  // The last result's domain and field, kept alive by `keep` (session_lcs.cpp).
  struct FieldView {
    std::shared_ptr<const void> keep;
    const TangentBundle* bundle = nullptr;
    const Field* field = nullptr;
    bool planar = true;
    long long revision = 0;
  };
  FieldView current_field() const;
  // A frame's (or the preview's) JSON without "vectors", and the vectors.
  nlohmann::json frame_parts(int frame, std::vector<float>& vectors) const;
  nlohmann::json preview_parts(std::vector<float>& vectors) const;
};

}  // namespace tvf::serve
