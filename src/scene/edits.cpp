#include "tvf/scene/edits.h"

#include <fmt/format.h>

namespace tvf {
namespace {

using json = nlohmann::json;

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
