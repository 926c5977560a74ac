#pragma once
namespace tvf::cli {
// The demo scene `tvf` runs when given no scene (examples/02_combined_elements).
const char* default_scene_text();
}  // namespace tvf::cli
