#pragma once
// The fuzz targets (docs/architecture.md, "Fuzzing"): each feeds one input to one of tvf's
// readers. Bad input must end in a tvf::Error; anything else (a crash, a sanitizer report,
// an internal error, any other exception) is a bug. Shared by the libFuzzer programs
// (fuzz_main.cpp, built with TVF_FUZZ=ON) and the replay test (tests/fuzz), which runs
// every seed and every input that ever crashed (fuzz/crashers/) in the ordinary build.
#include <string_view>

namespace tvf::fuzz {

void scene(std::string_view data);          // scene JSON (parse_scene: scenes and their edits)
void mesh_obj(std::string_view data);       // load_mesh on a .obj file
void mesh_ply(std::string_view data);       // load_mesh on a .ply file
void mesh_off(std::string_view data);       // load_mesh on a .off file
void field(std::string_view data);          // load_field_file on a .tvff file
void session(std::string_view data);        // a request body to the server's Session (session_target.cpp)

}  // namespace tvf::fuzz
