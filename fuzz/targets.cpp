#include "targets.h"

#include "tvf/core/error.h"
#include "tvf/scene/scene_json.h"
#include "tvf/field/field_io.h"
#include "tvf/mesh/mesh_io.h"

#include <unistd.h>

#include <filesystem>
#include <fstream>
#include <string>

namespace tvf::fuzz {
namespace {

// The readers of files take a path: the input goes to a file of this process's own.
std::string write_input(std::string_view data, const char* extension) {
  const auto dir = std::filesystem::temp_directory_path() / ("tvf-fuzz-" + std::to_string(::getpid()));
  std::filesystem::create_directories(dir);
  const std::string path = (dir / (std::string("input") + extension)).string();
  std::ofstream out(path, std::ios::binary | std::ios::trunc);
  out.write(data.data(), static_cast<std::streamsize>(data.size()));
  return path;
}

template <class Fn>
void expect_only_input_errors(Fn&& fn) {
  try {
    fn();
  } catch (const InternalError&) {
    throw;  // a failed internal check on bad input is a bug
  } catch (const Error&) {
    // bad input, refused with a message: what should happen
  }
}

void load_mesh_as(std::string_view data, const char* extension) {
  const std::string path = write_input(data, extension);
  expect_only_input_errors([&] { load_mesh(path); });
}

}  // namespace

void scene(std::string_view data) {
  expect_only_input_errors([&] { parse_scene(std::string(data), "fuzz.json"); });
}
void mesh_obj(std::string_view data) { load_mesh_as(data, ".obj"); }
void mesh_ply(std::string_view data) { load_mesh_as(data, ".ply"); }
void mesh_off(std::string_view data) { load_mesh_as(data, ".off"); }
void field(std::string_view data) {
  const std::string path = write_input(data, ".tvff");
  expect_only_input_errors([&] { load_field_file(path); });
}

}  // namespace tvf::fuzz
