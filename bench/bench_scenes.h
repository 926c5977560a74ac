#pragma once
// The designs the benchmarks share.
#include "tvf/design/element_field.h"
#include "tvf/design/generate.h"
#include "tvf/field/field.h"
#include "tvf/mesh/grid.h"
#include "tvf/mesh/tangent_bundle.h"
#include "tvf/scene/scene.h"

#include <benchmark/benchmark.h>

#include <cmath>
#include <ctime>
#include <numbers>

namespace tvf::bench {

// The double gyre (Shadden, Lekien & Marsden 2005) on a 65² grid over [0, 2] × [0, 1],
// 100 frames on [0, 20]: the FTLE and dye benchmarks' field (made once).
struct DoubleGyre {
  Mesh grid = make_grid(GridSpec{65, 65, {0, 0}, {2, 1}});
  TangentBundle bundle{grid};
  Field field{TimeSampling{0, 20, 100}, grid.num_vertices()};
  DoubleGyre() {
    constexpr double A = 0.1, eps = 0.25, omega = 2 * std::numbers::pi / 10, pi = std::numbers::pi;
    for (int j = 0; j < field.frames(); ++j) {
      const double t = field.time().time(j);
      const double a = eps * std::sin(omega * t), b = 1 - 2 * a;
      for (int v = 0; v < grid.num_vertices(); ++v) {
        const double x = grid.position(v).x(), y = grid.position(v).y();
        const double f = a * x * x + b * x, df = 2 * a * x + b;
        // On a planar grid each vertex's tangent basis is world x, y.
        field.at(j, v) = {-pi * A * std::sin(pi * f) * std::cos(pi * y), pi * A * std::cos(pi * f) * std::sin(pi * y) * df};
      }
    }
  }
};

inline const DoubleGyre& double_gyre() {
  static const DoubleGyre g;
  return g;
}

// A moving center, a source, a bifurcation and a regular element with attachment (the
// demo's kind of design); the domain is left for the caller.
inline Scene combined_scene() {
  Scene s;
  s.time.frames = 100;
  s.falloff = 40;
  SingularElement c;
  c.type = SingularType::ccw_center;
  c.jacobian = jacobian_of(*c.type);
  c.path = {{Vec3(-0.6, 0.45, 0), 0}, {Vec3(0, 0.6, 0), 0.5}, {Vec3(0.6, 0.45, 0), 1}};
  SingularElement src;
  src.type = SingularType::source;
  src.jacobian = jacobian_of(*src.type);
  src.path = {{Vec3(-0.55, -0.2, 0), 0}};
  BifurcationElement b;
  b.at = {Vec3(0.55, -0.2, 0), 0.4};
  b.scale = 0.2;
  RegularElement r;
  r.pathline = {{Vec3(-0.6, -0.8, 0), 0}, {Vec3(0.6, -0.8, 0), 1}};
  r.attach = 2;
  s.elements = {c, src, b, r};
  return s;
}

// A vortex moving along the equator and a source at a pole, on an icosphere.
inline Scene sphere_scene(int subdivisions) {
  Scene s;
  s.time.frames = 100;
  s.falloff = 20;
  s.domain.sphere = SphereSpec{subdivisions, 1.0};
  SingularElement c;
  c.type = SingularType::ccw_center;
  c.jacobian = jacobian_of(*c.type);
  c.path = {{Vec3(1, 0, 0), 0}, {Vec3(0, 1, 0), 0.5}, {Vec3(-1, 0, 0), 1}};
  SingularElement src;
  src.type = SingularType::source;
  src.jacobian = jacobian_of(*src.type);
  src.path = {{Vec3(0, 0, 1), 0}};
  s.elements = {c, src};
  return s;
}

// CPU time of all threads of the process, in ms.
inline double process_cpu_ms() {
  timespec t{};
  clock_gettime(CLOCK_PROCESS_CPUTIME_ID, &t);
  return static_cast<double>(t.tv_sec) * 1e3 + static_cast<double>(t.tv_nsec) * 1e-6;
}

// Times generating the scene's field on a domain built once (cpu_ms: CPU of all threads
// per generation; on a loaded machine, cpu_ms / cores is what idle cores would take).
inline void time_generation(benchmark::State& state, const DesignSpace& space, const Scene& s) {
  GenerateReport report;
  const double cpu0 = process_cpu_ms();
  for (auto _ : state) benchmark::DoNotOptimize(generate(space, s, {}, &report).data().data());
  state.counters["cpu_ms"] = (process_cpu_ms() - cpu0) / static_cast<double>(state.iterations());
  state.counters["vertices"] = space.mesh().num_vertices();
  state.counters["frames"] = s.time.frames;
  state.SetLabel(report.method);
}

// Builds the scene's domain once, then times generating its field.
inline void time_generation(benchmark::State& state, const Scene& s) {
  const auto space = make_design_space(s);
  time_generation(state, *space, s);
}

// The combined design on an n × n grid over [-1, 1]².
inline Scene on_grid(Scene s, int n) {
  s.domain.grid = GridSpec{n, n, {-1, -1}, {1, 1}};
  return s;
}

}  // namespace tvf::bench
