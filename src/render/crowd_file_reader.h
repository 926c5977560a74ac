// The checks every crowd file reader shares (planar crowd.cpp, surface_crowd.cpp): one
// sentence naming the file and the JSON path of the bad value. Internal to render/.
#pragma once

#include "tvf/core/error.h"

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
};

}  // namespace tvf
