// Basis field summation and the log map (Google Benchmark). bench/run.sh turns the
// results into the table in docs/benchmarks.md.
#include "tvf/design/element_field.h"
#include "tvf/design/generate.h"
#include "tvf/mesh/primitives.h"

#include "bench_scenes.h"

#include <benchmark/benchmark.h>

namespace tvf {
namespace {


void BM_BasisSumGrid(benchmark::State& state) {
  const Scene s = bench::on_grid(bench::combined_scene(), static_cast<int>(state.range(0)));
  bench::time_generation(state, s);
}
BENCHMARK(BM_BasisSumGrid)->Arg(65)->Arg(257)->Unit(benchmark::kMillisecond);


void BM_BasisSumSphere(benchmark::State& state) {
  const Scene s = bench::sphere_scene(static_cast<int>(state.range(0)));
  bench::time_generation(state, s);
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
  Scene s = bench::on_grid(bench::combined_scene(), static_cast<int>(state.range(0)));
  s.generator = Generator::constrained;
  bench::time_generation(state, s);
}
BENCHMARK(BM_ConstrainedGrid)->Arg(65)->Arg(141)->Unit(benchmark::kMillisecond);

void BM_ConstrainedSphere(benchmark::State& state) {
  Scene s = bench::sphere_scene(static_cast<int>(state.range(0)));
  s.generator = Generator::constrained;
  bench::time_generation(state, s);
}
BENCHMARK(BM_ConstrainedSphere)->Arg(5)->Unit(benchmark::kMillisecond);

// The same design on the 20,252-vertex geodesic sphere of the space-time benchmarks.
void BM_ConstrainedSphere20k(benchmark::State& state) {
  Scene s = bench::sphere_scene(5);
  s.generator = Generator::constrained;
  const DesignSpace space(make_geodesic_sphere(45));
  bench::time_generation(state, space, s);
}
BENCHMARK(BM_ConstrainedSphere20k)->Unit(benchmark::kMillisecond);

}  // namespace
}  // namespace tvf
