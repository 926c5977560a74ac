// Finite-time Lyapunov exponents of the double gyre (Shadden, Lekien & Marsden 2005) on a
// 65² grid over [0, 2] × [0, 1], 100 frames on [0, 20] (RK4 steps of half the frame
// spacing, ≈ 0.1), horizon T = 10 (Google Benchmark; docs/benchmarks.md, "FTLE"). Issue
// 20 asks the designer's overlay, one frame's forward and backward FTLE, to update while
// designing (≤ ~0.5 s on 2 cores): BM_FtleOneFrame. BM_FtleOneFrameWalk is the same on the
// generic surface walk (the planar-grid fast path off), BM_FtleSeries every frame, and
// BM_FtleSeriesComposed every frame by flow-map composition (FtleOptions::compose).
// On surfaces, one direction at one time as the designer's overlay asks it
// (compute_ftle_at, T = 0.5, t = 0.25): BM_FtleAtSphere on the 4-times subdivided sphere
// (2,562 vertices, bench_scenes.h's vortex and source, 100 frames) and BM_FtleAtBunny on
// example 04's bunny (37,706 vertices, 60 frames; skipped when its bunny.off is missing).
#include "bench_scenes.h"
#include "tvf/integrate/ftle.h"
#include "tvf/mesh/grid.h"
#include "tvf/scene/design_space.h"
#include "tvf/scene/scene_json.h"

#include <benchmark/benchmark.h>

#include <cmath>
#include <filesystem>
#include <memory>
#include <numbers>

namespace tvf {
namespace {

using bench::DoubleGyre;

// Frame 40 (t ≈ 8.1): both windows of T = 10 fit.
void one_frame(benchmark::State& state, bool walk) {
  const DoubleGyre& g = bench::double_gyre();
  FtleOptions o;
  o.horizon = 10;
  o.frames = {40};
  o.flow.walk = walk;
  for (auto _ : state) {
    const FtleResult r = compute_ftle(g.bundle, g.field, o);
    benchmark::DoNotOptimize(r.forward.data());
  }
  state.counters["vertices"] = g.grid.num_vertices();
}

void BM_FtleOneFrame(benchmark::State& state) { one_frame(state, false); }
BENCHMARK(BM_FtleOneFrame)->Unit(benchmark::kMillisecond)->MeasureProcessCPUTime()->UseRealTime();

void BM_FtleOneFrameWalk(benchmark::State& state) { one_frame(state, true); }
BENCHMARK(BM_FtleOneFrameWalk)->Unit(benchmark::kMillisecond)->MeasureProcessCPUTime()->UseRealTime();

void series(benchmark::State& state, bool compose) {
  const DoubleGyre& g = bench::double_gyre();
  FtleOptions o;
  o.horizon = 10;
  o.compose = compose;
  for (auto _ : state) {
    const FtleResult r = compute_ftle(g.bundle, g.field, o);
    benchmark::DoNotOptimize(r.forward.data());
  }
  state.counters["frames"] = g.field.frames();
}

void BM_FtleSeries(benchmark::State& state) { series(state, false); }
BENCHMARK(BM_FtleSeries)->Unit(benchmark::kMillisecond)->MeasureProcessCPUTime()->UseRealTime()->Iterations(1);

// The series by flow-map composition (FtleOptions::compose).
void BM_FtleSeriesComposed(benchmark::State& state) { series(state, true); }
BENCHMARK(BM_FtleSeriesComposed)->Unit(benchmark::kMillisecond)->MeasureProcessCPUTime()->UseRealTime();

// One direction at one time on a surface (what GET /api/ftle computes).
void ftle_at(benchmark::State& state, const Scene& scene) {
  const auto space = make_design_space(scene);
  const Field field = generate(*space, scene);
  for (auto _ : state) {
    const FtleSlice s = compute_ftle_at(space->bundle(), field, 0.25, 0.5, 1);
    benchmark::DoNotOptimize(s.values.data());
  }
  state.counters["vertices"] = space->mesh().num_vertices();
}

void BM_FtleAtSphere(benchmark::State& state) { ftle_at(state, bench::sphere_scene(4)); }
BENCHMARK(BM_FtleAtSphere)->Unit(benchmark::kMillisecond)->MeasureProcessCPUTime()->UseRealTime();

void BM_FtleAtBunny(benchmark::State& state) {
  const std::string path = std::string(TVF_SOURCE_DIR) + "/examples/04_surface_mesh/scene.json";
  if (!std::filesystem::exists(std::string(TVF_SOURCE_DIR) + "/examples/04_surface_mesh/bunny.off")) {
    state.SkipWithError("examples/04_surface_mesh/bunny.off is missing (scripts/install-deps.sh extracts it)");
    return;
  }
  ftle_at(state, load_scene(path));
}
BENCHMARK(BM_FtleAtBunny)->Unit(benchmark::kMillisecond)->MeasureProcessCPUTime()->UseRealTime()->Iterations(3);

}  // namespace
}  // namespace tvf
