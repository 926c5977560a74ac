// Writes the benchmarks' geodesic sphere as a mesh file, for scenes run end to end with
// `tvf generate` (bench/generate_ratio.sh's sphere scenes name sphere20k.off).
// Usage: tvf_sphere_mesh OUT.off [frequency]   (45, the default: 20,252 vertices)
#include "tvf/mesh/mesh_io.h"
#include "tvf/mesh/primitives.h"

#include <cstdio>
#include <cstdlib>
#include <exception>
#include <string>

int main(int argc, char** argv) {
  const std::string first = argc > 1 ? argv[1] : "";
  if (argc < 2 || argc > 3 || first == "-h" || first == "--help") {
    std::fprintf(stderr, "usage: %s OUT.off [frequency]   (45, the default: 20,252 vertices)\n", argv[0]);
    return argc == 2 && (first == "-h" || first == "--help") ? 0 : 2;
  }
  // 10 · frequency² + 2 vertices: 1000 makes 10M, beyond what a benchmark scene needs.
  char* end = nullptr;
  const long frequency = argc == 3 ? std::strtol(argv[2], &end, 10) : 45;
  if (argc == 3 && (end == argv[2] || *end != '\0' || frequency < 1 || frequency > 1000)) {
    std::fprintf(stderr, "%s: frequency '%s' must be an integer in [1, 1000]\n", argv[0], argv[2]);
    return 2;
  }
  try {
    tvf::save_mesh(tvf::make_geodesic_sphere(static_cast<int>(frequency)), argv[1]);
  } catch (const std::exception& e) {
    std::fprintf(stderr, "%s: %s\n", argv[0], e.what());
    return 1;
  }
  return 0;
}
