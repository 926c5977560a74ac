#pragma once
// The designs the benchmarks share.
#include "tvf/design/element_field.h"
#include "tvf/design/generate.h"
#include "tvf/scene/scene.h"

#include <benchmark/benchmark.h>

#include <ctime>

namespace tvf::bench {

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
