// Basis field summation and the log map (Google Benchmark). bench/run.sh turns the
// results into the table in docs/benchmarks.md.
#include "tvf/design/element_field.h"
#include "tvf/design/generate.h"

#include <benchmark/benchmark.h>

namespace tvf {
namespace {

Scene combined_scene() {
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

void BM_BasisSumGrid(benchmark::State& state) {
  Scene s = combined_scene();
  const int n = static_cast<int>(state.range(0));
  s.domain.grid = GridSpec{n, n, {-1, -1}, {1, 1}};
  const auto space = make_design_space(s);
  for (auto _ : state) benchmark::DoNotOptimize(generate(*space, s).data().data());
  state.counters["vertices"] = n * n;
  state.counters["frames"] = s.time.frames;
}
BENCHMARK(BM_BasisSumGrid)->Arg(65)->Arg(257)->Unit(benchmark::kMillisecond);

// A vortex moving along the equator and a source at a pole, on an icosphere.
Scene sphere_scene(int subdivisions) {
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

void BM_BasisSumSphere(benchmark::State& state) {
  const Scene s = sphere_scene(static_cast<int>(state.range(0)));
  const auto space = make_design_space(s);
  for (auto _ : state) benchmark::DoNotOptimize(generate(*space, s).data().data());
  state.counters["vertices"] = space->mesh().num_vertices();
  state.counters["frames"] = s.time.frames;
}
BENCHMARK(BM_BasisSumSphere)->Arg(5)->Arg(6)->Unit(benchmark::kMillisecond);

void BM_LogMapSetup(benchmark::State& state) {
  Scene s;
  s.domain.sphere = SphereSpec{static_cast<int>(state.range(0)), 1.0};
  for (auto _ : state) benchmark::DoNotOptimize(make_design_space(s).get());
}
BENCHMARK(BM_LogMapSetup)->Arg(5)->Arg(6)->Unit(benchmark::kMillisecond);

}  // namespace
}  // namespace tvf

namespace tvf {
namespace {

// Constrained optimization per frame (paper §5.3) on the same designs.
void BM_ConstrainedGrid(benchmark::State& state) {
  Scene s = combined_scene();
  s.generator = Generator::constrained;
  const int n = static_cast<int>(state.range(0));
  s.domain.grid = GridSpec{n, n, {-1, -1}, {1, 1}};
  const auto space = make_design_space(s);
  for (auto _ : state) benchmark::DoNotOptimize(generate(*space, s).data().data());
  state.counters["vertices"] = n * n;
  state.counters["frames"] = s.time.frames;
}
BENCHMARK(BM_ConstrainedGrid)->Arg(65)->Arg(141)->Unit(benchmark::kMillisecond);

void BM_ConstrainedSphere(benchmark::State& state) {
  Scene s = sphere_scene(static_cast<int>(state.range(0)));
  s.generator = Generator::constrained;
  const auto space = make_design_space(s);
  for (auto _ : state) benchmark::DoNotOptimize(generate(*space, s).data().data());
  state.counters["vertices"] = space->mesh().num_vertices();
  state.counters["frames"] = s.time.frames;
}
BENCHMARK(BM_ConstrainedSphere)->Arg(5)->Unit(benchmark::kMillisecond);

}  // namespace
}  // namespace tvf
