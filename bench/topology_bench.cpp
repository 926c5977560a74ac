// Topology analysis (singularities per frame, space-time tracking, bifurcations, coherence)
// of a generated 20,000-vertex × 100-frame field (Google Benchmark). Issue 4 asks that
// analysing such a field take a small fraction of generating it (BM_BasisSum*,
// BM_Constrained* in basis_sum_bench.cpp).
#include "tvf/api/design.h"
#include "tvf/analysis/topology.h"
#include "tvf/design/element_field.h"
#include "tvf/design/generate.h"
#include "tvf/integrate/periodic_orbits.h"
#include "tvf/scene/scene_json.h"

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

// The periodic-orbit search (periodic_orbits.h) of the designer's analysis, serial (as the
// designer's analysis thread runs it), on its topology: the 65² × 100 deform design of
// web/e2e/latency.e2e.mjs (a vortex turned by 0.5 rad over the frames: a center at the
// first frames, an attracting focus after) and example 09 (two storms merging on a
// 10,242-vertex sphere: centers whose closed orbits are neutral).
void orbits(benchmark::State& state, const Scene& s) {
  const GeneratedField generated = generate_scene(s);
  const auto& space = generated.space;
  const Topology t = analyze_topology(space->bundle(), generated.field);
  PeriodicOrbitOptions o;
  o.parallel = false;
  PeriodicOrbits p;
  for (auto _ : state) {
    p = find_periodic_orbits(space->bundle(), generated.field, t, o);
    benchmark::DoNotOptimize(p.orbits.data());
  }
  state.counters["orbits"] = static_cast<double>(p.orbits.size());
  state.counters["hopf"] = static_cast<double>(p.hopf.size());
}

void BM_PeriodicOrbitsDeform65(benchmark::State& state) {
  orbits(state, parse_scene(R"({"tvf": 1, "domain": {"grid": {"size": [65, 65], "min": [-1, -1], "max": [1, 1]}},
    "time": {"frames": 100, "range": [0, 1]}, "falloff": 8, "generator": "deform",
    "deform": {"base": {"elements": [{"kind": "singular", "type": "ccw_center", "path": [[0, 0, 0]]}]},
      "transform": [{"t": 0, "sx": 1, "sy": 1, "theta": 0}, {"t": 1, "sx": 1, "sy": 1, "theta": 0.5}]}})",
                            "deform design"));
}
BENCHMARK(BM_PeriodicOrbitsDeform65)->Unit(benchmark::kMillisecond);

void BM_PeriodicOrbitsStorms(benchmark::State& state) {
  orbits(state, load_scene(std::string(TVF_SOURCE_DIR) + "/examples/09_sphere_storms_merging/scene.json"));
}
BENCHMARK(BM_PeriodicOrbitsStorms)->Unit(benchmark::kMillisecond);

}  // namespace
}  // namespace tvf
