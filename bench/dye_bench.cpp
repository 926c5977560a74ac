// Dye injection (integrate/dye.h; docs/benchmarks.md, "Dye injection"): the dye of three
// seeds in the double gyre (65² grid over [0, 2] × [0, 1], 100 frames on [0, 20], a
// release every quarter frame) at every one of the 100 frames, as an animation draws it.
// BM_DyeIncremental keeps it up to date with DyeInjector (each frame carries the dye one
// frame further); BM_DyeRetraced traces every frame's streaklines from scratch with
// trace_streakline (what the planar texture overlay did before). The *Walk variants force
// the surface walk, the integrator every surface uses (FlowMapOptions::walk).
#include "tvf/integrate/dye.h"
#include "tvf/integrate/streakline.h"
#include "tvf/mesh/grid.h"

#include <benchmark/benchmark.h>

#include <cmath>
#include <numbers>
#include <vector>

namespace tvf {
namespace {

struct Gyre {
  Mesh grid = make_grid(GridSpec{65, 65, {0, 0}, {2, 1}});
  TangentBundle bundle{grid};
  Field field{TimeSampling{0, 20, 100}, grid.num_vertices()};
  std::vector<Vec3> seeds{Vec3(0.9, 0.3, 0), Vec3(1.1, 0.7, 0), Vec3(0.5, 0.5, 0)};
  Gyre() {
    constexpr double A = 0.1, eps = 0.25, omega = 2 * std::numbers::pi / 10, pi = std::numbers::pi;
    for (int j = 0; j < field.frames(); ++j) {
      const double t = field.time().time(j);
      const double a = eps * std::sin(omega * t), b = 1 - 2 * a;
      for (int v = 0; v < grid.num_vertices(); ++v) {
        const double x = grid.position(v).x(), y = grid.position(v).y();
        const double f = a * x * x + b * x, df = 2 * a * x + b;
        field.at(j, v) = {-pi * A * std::sin(pi * f) * std::cos(pi * y), pi * A * std::cos(pi * f) * std::sin(pi * y) * df};
      }
    }
  }
};

const Gyre& gyre() {
  static const Gyre g;
  return g;
}

void incremental(benchmark::State& state, bool walk) {
  const Gyre& g = gyre();
  DyeOptions o;
  o.flow.walk = walk;
  long points = 0;
  for (auto _ : state) {
    DyeInjector dye(g.bundle, g.field, g.seeds, 0.0, o);
    points = 0;
    for (int k = 1; k < g.field.frames(); ++k) {
      dye.advance(g.field.time().time(k));
      for (size_t s = 0; s < g.seeds.size(); ++s) points += static_cast<long>(dye.streakline(s).points.size());
    }
    benchmark::DoNotOptimize(points);
  }
  state.counters["points_drawn"] = static_cast<double>(points);
}

void retraced(benchmark::State& state, bool walk) {
  const Gyre& g = gyre();
  StreaklineOptions o;
  o.flow.walk = walk;
  long points = 0;
  for (auto _ : state) {
    points = 0;
    for (int k = 1; k < g.field.frames(); ++k) {
      o.t1 = g.field.time().time(k);
      for (const Vec3& seed : g.seeds) points += static_cast<long>(trace_streakline(g.bundle, g.field, seed, o).points.size());
    }
    benchmark::DoNotOptimize(points);
  }
  state.counters["points_drawn"] = static_cast<double>(points);
}

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
