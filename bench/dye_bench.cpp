// Dye injection (integrate/dye.h; docs/benchmarks.md, "Dye injection"): the dye of three
// seeds in the double gyre (65² grid over [0, 2] × [0, 1], 100 frames on [0, 20], a
// release every quarter frame) at every one of the 100 frames, as an animation draws it.
// BM_DyeIncremental keeps it up to date with DyeInjector (each frame carries the dye one
// frame further); BM_DyeRetraced traces every frame's streaklines from scratch with
// trace_streakline (what the planar texture overlay did before). The *Walk variants force
// the surface walk, the integrator every surface uses (FlowMapOptions::walk).
// BM_TimelineIncremental and BM_TimelineRetraced do the same for a timeline across
// y = 0.5 drawn at t = 0: MaterialLine advanced frame by frame (the renderers' --timeline)
// against trace_timeline from t = 0 at every frame.
#include "bench_scenes.h"
#include "tvf/integrate/dye.h"
#include "tvf/integrate/streakline.h"
#include "tvf/mesh/grid.h"

#include <benchmark/benchmark.h>

#include <cmath>
#include <limits>
#include <numbers>
#include <vector>

namespace tvf {
namespace {

using bench::DoubleGyre;
const std::vector<Vec3> seeds{Vec3(0.9, 0.3, 0), Vec3(1.1, 0.7, 0), Vec3(0.5, 0.5, 0)};

void incremental(benchmark::State& state, bool walk) {
  const DoubleGyre& g = bench::double_gyre();
  DyeOptions o;
  o.flow.walk = walk;
  long points = 0;
  for (auto _ : state) {
    DyeInjector dye(g.bundle, g.field, seeds, 0.0, o);
    points = 0;
    for (int k = 1; k < g.field.frames(); ++k) {
      dye.advance(g.field.time().time(k));
      for (size_t s = 0; s < seeds.size(); ++s) points += static_cast<long>(dye.streakline(s).points.size());
    }
    benchmark::DoNotOptimize(points);
  }
  state.counters["points_drawn"] = static_cast<double>(points);
}

void retraced(benchmark::State& state, bool walk) {
  const DoubleGyre& g = bench::double_gyre();
  StreaklineOptions o;
  o.flow.walk = walk;
  o.max_gap = std::numeric_limits<double>::infinity();  // the injector's releases, none added
  long points = 0;
  for (auto _ : state) {
    points = 0;
    for (int k = 1; k < g.field.frames(); ++k) {
      o.t1 = g.field.time().time(k);
      for (const Vec3& seed : seeds) points += static_cast<long>(trace_streakline(g.bundle, g.field, seed, o).points.size());
    }
    benchmark::DoNotOptimize(points);
  }
  state.counters["points_drawn"] = static_cast<double>(points);
}

const Vec3 line_a(0.1, 0.5, 0), line_b(1.9, 0.5, 0);

void BM_TimelineIncremental(benchmark::State& state) {
  const DoubleGyre& g = bench::double_gyre();
  const FlowMap flow(g.bundle, g.field);
  long points = 0;
  for (auto _ : state) {
    MaterialLine line(flow, line_a, line_b, TimelineOptions{});
    points = 0;
    for (int k = 1; k < g.field.frames(); ++k) {
      line.advance(g.field.time().time(k));
      points += static_cast<long>(line.line().points.size());
    }
    benchmark::DoNotOptimize(points);
  }
  state.counters["points_drawn"] = static_cast<double>(points);
}
BENCHMARK(BM_TimelineIncremental)->Unit(benchmark::kMillisecond)->MeasureProcessCPUTime()->UseRealTime();

void BM_TimelineRetraced(benchmark::State& state) {
  const DoubleGyre& g = bench::double_gyre();
  long points = 0;
  for (auto _ : state) {
    points = 0;
    for (int k = 1; k < g.field.frames(); ++k) {
      TimelineOptions o;
      o.t1 = g.field.time().time(k);
      points += static_cast<long>(trace_timeline(g.bundle, g.field, line_a, line_b, o).points.size());
    }
    benchmark::DoNotOptimize(points);
  }
  state.counters["points_drawn"] = static_cast<double>(points);
}
BENCHMARK(BM_TimelineRetraced)->Unit(benchmark::kMillisecond)->MeasureProcessCPUTime()->UseRealTime()->Iterations(1);

void BM_DyeIncremental(benchmark::State& state) { incremental(state, false); }
BENCHMARK(BM_DyeIncremental)->Unit(benchmark::kMillisecond)->MeasureProcessCPUTime()->UseRealTime();
void BM_DyeRetraced(benchmark::State& state) { retraced(state, false); }
BENCHMARK(BM_DyeRetraced)->Unit(benchmark::kMillisecond)->MeasureProcessCPUTime()->UseRealTime()->Iterations(1);
void BM_DyeIncrementalWalk(benchmark::State& state) { incremental(state, true); }
BENCHMARK(BM_DyeIncrementalWalk)->Unit(benchmark::kMillisecond)->MeasureProcessCPUTime()->UseRealTime();
void BM_DyeRetracedWalk(benchmark::State& state) { retraced(state, true); }
BENCHMARK(BM_DyeRetracedWalk)->Unit(benchmark::kMillisecond)->MeasureProcessCPUTime()->UseRealTime()->Iterations(1);

}  // namespace
}  // namespace tvf
