// The designer's Lagrangian overlays (session.h: Session::ftle, streakline, timeline):
// thin wrappers of the library's FTLE (ftle.h) and streaklines/timelines (streakline.h)
// on the last result, with every parameter checked and named.
#include "tvf/serve/session.h"

#include "tvf/field/field.h"
#include "tvf/integrate/ftle.h"
#include "tvf/integrate/streakline.h"
#include "tvf/mesh/tangent_bundle.h"
#include "tvf/render/lcs_pictures.h"

#include <fmt/format.h>

#include <algorithm>
#include <chrono>
#include <cmath>
#include <limits>

using nlohmann::json;

namespace tvf::serve {

namespace {

// The most particles one request may release or place (streaklines: (to − from)/spacing).
constexpr double kMaxParticles = 20000;

double number(const json& request, const char* what, const char* key) {
  const auto it = request.find(key);
  if (it == request.end() || !it->is_number())
    throw RequestError(400, fmt::format("{}: \"{}\" must be a number", what, key));
  const double x = it->get<double>();
  if (!std::isfinite(x)) throw RequestError(400, fmt::format("{}: \"{}\" is not finite", what, key));
  return x;
}

void in_range(const Field& field, double t, const char* what, const char* key) {
  const TimeSampling& time = field.time();
  const double lo = std::min(time.t0, time.t1), hi = std::max(time.t0, time.t1);
  if (t < lo || t > hi)
    throw RequestError(400, fmt::format("{}: \"{}\" = {} is outside the field's time range [{}, {}]", what, key, t,
                                        lo, hi));
}

Vec3 position(const json& p, bool planar, const char* what, const std::string& key) {
  const size_t n = planar ? 2 : 3;
  if (!p.is_array() || p.size() != n || !std::all_of(p.begin(), p.end(), [](const json& v) { return v.is_number(); }))
    throw RequestError(400, fmt::format("{}: \"{}\" must be a position of {} numbers on this {}", what, key, n,
                                        planar ? "grid" : "surface"));
  Vec3 x = Vec3::Zero();
  for (size_t k = 0; k < n; ++k) x[static_cast<int>(k)] = p[k].get<double>();
  if (!x.allFinite() || x.cwiseAbs().maxCoeff() > 1e15)
    throw RequestError(400, fmt::format("{}: \"{}\" must be finite, each coordinate under 1e15", what, key));
  return x;
}

json curve(const Streakline& s, bool planar, long long revision, double seconds) {
  const char* by = refinement_name(s.unresolved_by);
  json points = json::array(), gaps = json::array();
  for (size_t i = 0; i < s.points.size(); ++i) {
    const Vec3& x = s.points[i].position;
    points.push_back(planar ? json::array({x.x(), x.y()}) : json::array({x.x(), x.y(), x.z()}));
    if (s.points[i].gap_before) gaps.push_back(i);
  }
  return {{"revision", revision},       {"t", s.t},
          {"points", points},           {"gaps", gaps},
          {"released", s.released},     {"left", s.left},
          {"resolution", s.resolution}, {"largest_gap", s.largest_gap},
          {"unresolved", s.unresolved}, {"unresolved_by", by ? json(by) : json()},
          {"seconds", seconds}};
}

double since(std::chrono::steady_clock::time_point start) {
  return std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
}

}  // namespace

json Session::ftle(const json& request) const {
  const char* what = "ftle";
  if (!request.is_object()) throw RequestError(400, "ftle: expected {\"t\", \"horizon\", \"direction\"}");
  const FieldView f = current_field();
  const double t = number(request, what, "t");
  in_range(*f.field, t, what, "t");
  const double horizon = number(request, what, "horizon");
  const TimeSampling& time = f.field->time();
  const double range = std::abs(time.t1 - time.t0);
  if (!(horizon > 0) || horizon > range)
    throw RequestError(400, fmt::format("ftle: \"horizon\" = {} must be positive and at most the field's time span {}",
                                        horizon, range));
  std::string direction = "forward";
  if (request.contains("direction")) {
    const json& d = request.at("direction");
    if (!d.is_string() || (d != "forward" && d != "backward"))
      throw RequestError(400, "ftle: \"direction\" must be \"forward\" or \"backward\"");
    direction = d == "forward" ? "forward" : "backward";
  }
  const auto start = std::chrono::steady_clock::now();
  const FtleSlice s = compute_ftle_at(*f.bundle, *f.field, t, horizon, direction == "forward" ? 1 : -1);
  float lo = std::numeric_limits<float>::infinity(), hi = -lo;
  for (const float v : s.values)
    if (std::isfinite(v)) {
      lo = std::min(lo, v);
      hi = std::max(hi, v);
    }
  const auto [q01, q99] = colour_range(s.values);  // the pictures' colour range (lcs_pictures.h)
  json values = json::array();
  for (const float v : s.values) values.push_back(std::isfinite(v) ? json(std::round(v * 1e5) / 1e5) : json(nullptr));
  return {{"revision", f.revision},
          {"t", t},
          {"horizon", horizon},
          {"direction", direction},
          {"span", s.span},
          {"cut", s.cut},
          {"left", s.left},
          {"min", lo <= hi ? json(lo) : json(nullptr)},
          {"max", lo <= hi ? json(hi) : json(nullptr)},
          {"range", {q01, q99}},
          {"values", values},
          {"seconds", since(start)}};
}

json Session::streakline(const json& request) const {
  const char* what = "streakline";
  if (!request.is_object()) throw RequestError(400, "streakline: expected {\"seed\", \"from\", \"to\"}");
  const FieldView f = current_field();
  const Vec3 x = position(request.contains("seed") ? request.at("seed") : json(), f.planar, what, "seed");
  StreaklineOptions o;
  o.t0 = number(request, what, "from");
  o.t1 = number(request, what, "to");
  in_range(*f.field, o.t0, what, "from");
  in_range(*f.field, o.t1, what, "to");
  if (o.t0 > o.t1) throw RequestError(400, fmt::format("streakline: \"from\" = {} is after \"to\" = {}", o.t0, o.t1));
  if (request.contains("spacing")) {
    o.release_spacing = number(request, what, "spacing");
    if (!(o.release_spacing > 0)) throw RequestError(400, "streakline: \"spacing\" must be positive");
  } else {
    const TimeSampling& time = f.field->time();
    o.release_spacing = 0.25 * std::abs(time.t1 - time.t0) / std::max(1, time.frames - 1);
  }
  if ((o.t1 - o.t0) / o.release_spacing > kMaxParticles)
    throw RequestError(400, fmt::format("streakline: (to − from)/spacing = {:.0f} releases, more than {:.0f}",
                                        (o.t1 - o.t0) / o.release_spacing, kMaxParticles));
  // Releases added where neighbours part (trace_streakline) stay within the same bound.
  o.max_added = static_cast<long>(kMaxParticles - std::floor((o.t1 - o.t0) / o.release_spacing));
  const auto start = std::chrono::steady_clock::now();
  try {
    // Traced before the clock is read: a function's arguments are evaluated in no set order,
    // and GCC read it first (the reply said 26 ns for 600 particles).
    const Streakline s = trace_streakline(*f.bundle, *f.field, x, o);
    return curve(s, f.planar, f.revision, since(start));
  } catch (const Error& e) {
    throw RequestError(422, fmt::format("streakline: {}", e.what()));
  }
}

json Session::timeline(const json& request) const {
  const char* what = "timeline";
  if (!request.is_object()) throw RequestError(400, "timeline: expected {\"line\": [a, b], \"from\", \"to\"}");
  const FieldView f = current_field();
  const json line = request.contains("line") ? request.at("line") : json();
  if (!line.is_array() || line.size() != 2) throw RequestError(400, "timeline: \"line\" must be two positions [a, b]");
  const Vec3 a = position(line.front(), f.planar, what, "line[0]");
  const Vec3 b = position(line.back(), f.planar, what, "line[1]");
  TimelineOptions o;
  o.t0 = number(request, what, "from");
  o.t1 = number(request, what, "to");
  in_range(*f.field, o.t0, what, "from");
  in_range(*f.field, o.t1, what, "to");
  if (request.contains("count")) {
    const double c = number(request, what, "count");
    if (c != std::floor(c) || c < 2 || c > 2000)
      throw RequestError(400, "timeline: \"count\" must be a whole number of particles in [2, 2000]");
    o.count = static_cast<int>(c);
  }
  const auto start = std::chrono::steady_clock::now();
  try {
    const Streakline s = trace_timeline(*f.bundle, *f.field, a, b, o);  // before the clock (above)
    return curve(s, f.planar, f.revision, since(start));
  } catch (const Error& e) {
    throw RequestError(422, fmt::format("timeline: {}", e.what()));
  }
}

}  // namespace tvf::serve
