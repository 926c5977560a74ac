// The checks every crowd file reader shares (planar crowd.cpp, surface_crowd.cpp): one
// sentence naming the file and the JSON path of the bad value, with its line and column in
// the file (read_crowd_file: the one JSON reader, core/json_text.h, as scenes are read).
// Internal to render/.
#pragma once

#include "tvf/core/error.h"
#include "tvf/core/error_location.h"
#include "tvf/core/json_text.h"

#include <fmt/format.h>
#include <nlohmann/json.hpp>

#include <algorithm>
#include <cmath>
#include <initializer_list>
#include <string>

namespace tvf {

struct CrowdFileReader {
  std::string file;
  [[noreturn]] void fail(const std::string& path, const std::string& message) const {
    throw_input_error(file, path, message);
  }
  void keys(const nlohmann::json& j, const std::string& path, std::initializer_list<const char*> allowed) const {
    if (!j.is_object()) fail(path, "expected an object");
    for (const auto& item : j.items())
      if (std::find_if(allowed.begin(), allowed.end(), [&](const char* a) { return item.key() == a; }) == allowed.end())
        fail(path.empty() ? item.key() : path + "." + item.key(), "unknown key");
  }
  double number(const nlohmann::json& j, const std::string& path, double lo, double hi) const {
    if (!j.is_number()) fail(path, "expected a number");
    const double v = j.get<double>();
    if (!std::isfinite(v) || v < lo || v > hi) fail(path, fmt::format("{} is outside [{}, {}]", v, lo, hi));
    return v;
  }
  int integer(const nlohmann::json& j, const std::string& path, int lo, int hi) const {
    if (!j.is_number_integer()) fail(path, "expected an integer");
    const auto v = j.get<long long>();
    if (v < lo || v > hi) fail(path, fmt::format("{} is outside [{}, {}]", v, lo, hi));
    return static_cast<int>(v);
  }
  // The keys planar and surface crowd files share (agents, speed, weights, steps_per_frame,
  // avoidance.distance) into either spec; `avoidance` may also hold `avoidance_keys` beyond
  // distance, which the caller reads.
  template <class Spec>
  void shared_keys(const nlohmann::json& j, Spec& s, std::initializer_list<const char*> avoidance_keys) const {
    if (j.contains("agents")) s.agents = integer(j["agents"], "agents", 1, 100000);
    if (j.contains("speed")) s.speed = number(j["speed"], "speed", 0, 1e12);
    if (j.contains("weights")) {
      keys(j["weights"], "weights", {"goal", "field"});
      if (j["weights"].contains("goal")) s.weight_goal = number(j["weights"]["goal"], "weights.goal", 0, 1e6);
      if (j["weights"].contains("field")) s.weight_field = number(j["weights"]["field"], "weights.field", 0, 1e6);
    }
    if (j.contains("steps_per_frame")) s.steps_per_frame = integer(j["steps_per_frame"], "steps_per_frame", 1, 1000);
    if (j.contains("avoidance")) {
      keys(j["avoidance"], "avoidance", avoidance_keys);
      if (!j["avoidance"].contains("distance")) fail("avoidance", "needs distance (the least distance between agents)");
      s.separation = number(j["avoidance"]["distance"], "avoidance.distance", 0, 1e12);
    }
  }

};

// Reads the crowd file `path` through the one JSON reader (syntax errors name their line
// and column) and hands the value to `parse`. An error `parse` throws about a value gets
// that value's line and column in the file: in its location fields, as a scene's errors
// do, and in its sentence ("crowd.json: goals[0].radius (line 4, column 17): expected a
// number"), since a crowd file has no designer to point at the place.
template <class Parse>
auto read_crowd_file(const std::string& path, Parse&& parse) {
  const std::string text = read_text_file(path, "the crowd file");
  const nlohmann::json j = parse_json_text(text, path, "a crowd file is a JSON object");
  try {
    return parse(j);
  } catch (const Error& e) {
    ErrorLocation location = location_of(e);
    const std::string prefix = location.file + ": " + location.json_path + ": ";
    const std::string message = e.what();
    if (location.line == 0 && !location.json_path.empty() && message.starts_with(prefix)) {
      const JsonTextPosition p = json_path_position(text, location.json_path);
      if (p.line > 0) {
        location.line = p.line;
        location.column = p.column;
        const std::string where = fmt::format("{} (line {}, column {})", location.json_path, p.line, p.column);
        throw_located_error(where, message.substr(prefix.size()), std::move(location));
      }
    }
    rethrow_with_position(e, text);
  }
}

}  // namespace tvf
