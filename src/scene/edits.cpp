#include "tvf/scene/edits.h"

#include "tvf/core/error.h"

#include <fmt/format.h>

#include <cmath>

namespace tvf {
namespace {

using json = nlohmann::json;

// Reads the canonical JSON of one edit. Scene::edits from files is already validated;
// these checks guard scenes built in code.
class EditReader {
public:
  EditReader(const Scene& scene, std::string path) : scene_(scene), path_(std::move(path)) {}

  [[noreturn]] void fail(const std::string& key, const std::string& message) const {
    throw_input_error(scene_.label(), key.empty() ? path_ : path_ + "." + key, message);
  }
  const json& need(const json& j, const char* key) const {
    if (!j.is_object() || !j.contains(key)) fail("", fmt::format("missing key \"{}\"", key));
    return j.at(key);
  }
  double number(const json& j, const char* key) const {
    const json& v = need(j, key);
    if (!v.is_number() || !std::isfinite(v.get<double>())) fail(key, "must be a finite number");
    return v.get<double>();
  }
  Vec3 position(const json& v, const std::string& key) const {
    const size_t n = scene_.domain.is_planar() ? 2 : 3;
    if (!v.is_array() || v.size() != n)
      fail(key, fmt::format("must be a position of {} numbers", n));
    Vec3 p = Vec3::Zero();
    for (size_t i = 0; i < n; ++i) {
      if (!v[i].is_number() || !std::isfinite(v[i].get<double>())) fail(key, "must hold finite numbers");
      p[static_cast<int>(i)] = v[i].get<double>();
    }
    return p;
  }
  PathPoint path_point(const json& j, const char* key) const {
    const json& v = need(j, key);
    const size_t n = scene_.domain.is_planar() ? 3 : 4;
    if (!v.is_array() || v.size() != n) fail(key, fmt::format("must be a path point of {} numbers", n));
    json xyz = json::array();
    for (size_t i = 0; i + 1 < n; ++i) xyz.push_back(v[i]);
    PathPoint p;
    p.position = position(xyz, key);
    if (!v[n - 1].is_number()) fail(key, "must hold finite numbers");
    p.t = v[n - 1].get<double>();
    if (!(p.t >= scene_.time.t0 && p.t <= scene_.time.t1))
      fail(key, fmt::format("t = {} is outside the time range [{}, {}]", p.t, scene_.time.t0, scene_.time.t1));
    return p;
  }
  double window(const json& j) const {
    if (!j.contains("window")) return kDefaultEditWindow;
    const double w = number(j, "window");
    if (!(w >= 0 && w <= 1)) fail("window", fmt::format("must be in [0, 1], got {}", w));
    return w;
  }

  Edit read(const json& j) const {
    const json& op = need(j, "op");
    if (!op.is_string()) fail("op", "must be a string");
    const std::string name = op.get<std::string>();
    if (name == "cancel") {
      CancelEdit e;
      const json& f = need(j, "frame");
      if (!f.is_number_integer()) fail("frame", "must be an integer");
      const auto frame = f.get<long long>();
      if (frame < 0 || frame >= scene_.time.frames)
        fail("frame", fmt::format("frame {} is outside [0, {}]", frame, scene_.time.frames - 1));
      e.frame = static_cast<int>(frame);
      const json& pair = need(j, "pair");
      if (!pair.is_array() || pair.size() != 2) fail("pair", "must be two positions");
      e.pair[0] = position(pair[0], "pair[0]");
      e.pair[1] = position(pair[1], "pair[1]");
      e.window = window(j);
      return e;
    }
    if (name == "smooth") {
      SmoothEdit e;
      e.strength = number(j, "strength");
      if (!(e.strength > 0 && e.strength <= 1))
        fail("strength", fmt::format("must be in (0, 1], got {}", e.strength));
      return e;
    }
    if (name == "remove_bifurcation") {
      RemoveBifurcationEdit e;
      e.at = path_point(j, "at");
      e.window = window(j);
      return e;
    }
    if (name == "move_bifurcation") {
      MoveBifurcationEdit e;
      e.at = path_point(j, "at");
      e.to = path_point(j, "to");
      e.window = window(j);
      return e;
    }
    fail("op", fmt::format("unknown edit \"{}\" (expected one of cancel, smooth, remove_bifurcation, "
                           "move_bifurcation)",
                           name));
  }

private:
  const Scene& scene_;
  std::string path_;
};

json point_json(const Vec3& p, bool planar) {
  return planar ? json::array({p.x(), p.y()}) : json::array({p.x(), p.y(), p.z()});
}
json path_point_json(const PathPoint& p, bool planar) {
  return planar ? json::array({p.position.x(), p.position.y(), p.t})
                : json::array({p.position.x(), p.position.y(), p.position.z(), p.t});
}
std::string point_text(const Vec3& p) {
  return p.z() == 0 ? fmt::format("({:.3g}, {:.3g})", p.x(), p.y())
                    : fmt::format("({:.3g}, {:.3g}, {:.3g})", p.x(), p.y(), p.z());
}

}  // namespace

const char* op_name(const Edit& edit) {
  struct Name {
    const char* operator()(const CancelEdit&) const { return "cancel"; }
    const char* operator()(const RemoveBifurcationEdit&) const { return "remove_bifurcation"; }
    const char* operator()(const MoveBifurcationEdit&) const { return "move_bifurcation"; }
    const char* operator()(const SmoothEdit&) const { return "smooth"; }
  };
  return std::visit(Name{}, edit);
}

std::vector<Edit> edits_from_scene(const Scene& scene) {
  std::vector<Edit> out;
  if (scene.edits.is_null()) return out;
  if (!scene.edits.is_array()) throw_input_error(scene.label(), "edits", "must be an array of edits");
  for (size_t i = 0; i < scene.edits.size(); ++i)
    out.push_back(EditReader(scene, fmt::format("edits[{}]", i)).read(scene.edits[i]));
  return out;
}

json edit_to_json(const Edit& edit, bool planar) {
  json j;
  j["op"] = op_name(edit);
  if (const auto* c = std::get_if<CancelEdit>(&edit)) {
    j["frame"] = c->frame;
    j["pair"] = json::array({point_json(c->pair[0], planar), point_json(c->pair[1], planar)});
    j["window"] = c->window;
  } else if (const auto* r = std::get_if<RemoveBifurcationEdit>(&edit)) {
    j["at"] = path_point_json(r->at, planar);
    j["window"] = r->window;
  } else if (const auto* m = std::get_if<MoveBifurcationEdit>(&edit)) {
    j["at"] = path_point_json(m->at, planar);
    j["to"] = path_point_json(m->to, planar);
    j["window"] = m->window;
  } else if (const auto* s = std::get_if<SmoothEdit>(&edit)) {
    j["strength"] = s->strength;
  }
  return j;
}

std::string describe(const Edit& edit) {
  if (const auto* c = std::get_if<CancelEdit>(&edit))
    return fmt::format("cancel the pair near {} and {} at frame {}", point_text(c->pair[0]),
                       point_text(c->pair[1]), c->frame);
  if (const auto* r = std::get_if<RemoveBifurcationEdit>(&edit))
    return fmt::format("remove the bifurcation near {} at t = {}", point_text(r->at.position), r->at.t);
  if (const auto* m = std::get_if<MoveBifurcationEdit>(&edit))
    return fmt::format("move the bifurcation near {} at t = {} to {} at t = {}", point_text(m->at.position),
                       m->at.t, point_text(m->to.position), m->to.t);
  return fmt::format("smooth with strength {}", std::get<SmoothEdit>(edit).strength);
}

}  // namespace tvf
