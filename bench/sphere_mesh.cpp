// Writes the benchmarks' geodesic sphere as a mesh file, for scenes run end to end with
// `tvf generate` (bench/generate_ratio.sh's sphere scenes name sphere20k.off).
// Usage: tvf_sphere_mesh OUT.off [frequency]   (45, the default: 20,252 vertices)
#include "tvf/mesh/mesh_io.h"
#include "tvf/mesh/primitives.h"

#include <cstdio>
#include <cstdlib>

int main(int argc, char** argv) {
  if (argc < 2 || argc > 3) {
    std::fprintf(stderr, "usage: %s OUT.off [frequency]\n", argv[0]);
    return 2;
  }
  const int frequency = argc == 3 ? std::atoi(argv[2]) : 45;
  if (frequency < 1) {
    std::fprintf(stderr, "frequency must be a positive integer\n");
    return 2;
  }
  tvf::save_mesh(tvf::make_geodesic_sphere(frequency), argv[1]);
  return 0;
}
