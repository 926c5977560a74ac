// Topology analysis (singularities per frame, space-time tracking, bifurcations, coherence)
// of a generated 20,000-vertex × 100-frame field (Google Benchmark). Issue 4 asks that
// analysing such a field take a small fraction of generating it (BM_BasisSum*,
// BM_Constrained* in basis_sum_bench.cpp).
#include "tvf/api/design.h"
#include "tvf/analysis/topology.h"
#include "tvf/design/element_field.h"
#include "tvf/design/generate.h"

#include "bench_scenes.h"

#include <benchmark/benchmark.h>

namespace tvf {
namespace {

// The benchmarks' combined design on an n × n grid.
Scene grid_scene(int n) { return bench::on_grid(bench::combined_scene(), n); }

void report(benchmark::State& state, const DesignSpace& space, const Field& field, const Topology& t) {
  state.counters["vertices"] = space.mesh().num_vertices();
  state.counters["frames"] = field.frames();
  state.counters["paths"] = static_cast<double>(t.paths.size());
  state.counters["bifurcations"] = static_cast<double>(t.bifurcations.size());
  state.counters["crossings"] = static_cast<double>(t.stats.crossings);
}

// Generates the scene once, then times its analysis.
void run(benchmark::State& state, const Scene& s) {
  const GeneratedField generated = generate_scene(s);  // the facade's one-shot (api/design.h)
  const auto& space = generated.space;
  const Field& field = generated.field;
  Topology t;
  for (auto _ : state) {
    t = analyze_topology(space->bundle(), field);
    benchmark::DoNotOptimize(t.paths.data());
  }
  report(state, *space, field, t);
}

void BM_TopologyGrid(benchmark::State& state) { run(state, grid_scene(static_cast<int>(state.range(0)))); }
BENCHMARK(BM_TopologyGrid)->Arg(65)->Arg(141)->Unit(benchmark::kMillisecond);

// Example 03's design (a vortex along the equator, a source at the north pole) on an
// icosphere: subdivisions 5 (10,242 vertices) and 6 (40,962).
void BM_TopologySphere(benchmark::State& state) {
  run(state, bench::sphere_scene(static_cast<int>(state.range(0))));
}
BENCHMARK(BM_TopologySphere)->Arg(5)->Arg(6)->Unit(benchmark::kMillisecond);

}  // namespace
}  // namespace tvf
