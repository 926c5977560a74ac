// Incompressible projection (solve/hodge_projection.h): the set-up (operators and the one
// sparse factorization) and one frame's projection, on icospheres and grids.
#include "tvf/solve/hodge_projection.h"

#include "tvf/mesh/grid.h"
#include "tvf/mesh/primitives.h"

#include <benchmark/benchmark.h>

#include <random>

namespace tvf {
namespace {

Mesh bench_mesh(int kind, int size) {
  return kind == 0 ? make_icosphere(size) : make_grid({size, size, {-1, -1}, {1, 1}});
}

void BM_HodgeSetup(benchmark::State& state) {
  const Mesh mesh = bench_mesh(static_cast<int>(state.range(0)), static_cast<int>(state.range(1)));
  const TangentBundle bundle(mesh);
  for (auto _ : state) {
    const DivergenceFreeProjector p(bundle);
    benchmark::DoNotOptimize(&p);
  }
  state.counters["vertices"] = mesh.num_vertices();
}

void BM_HodgeFrame(benchmark::State& state) {
  const Mesh mesh = bench_mesh(static_cast<int>(state.range(0)), static_cast<int>(state.range(1)));
  const TangentBundle bundle(mesh);
  const DivergenceFreeProjector p(bundle);
  std::mt19937 rng(1);
  std::normal_distribution<double> g;
  std::vector<cplx> z0(static_cast<size_t>(mesh.num_vertices()));
  for (auto& c : z0) c = cplx(g(rng), g(rng));
  std::vector<cplx> z;
  for (auto _ : state) {
    z = z0;
    benchmark::DoNotOptimize(p.project(z));
  }
  state.counters["vertices"] = mesh.num_vertices();
}
// Arguments: mesh (0: icosphere of that many subdivisions, 1: grid of that size²).
BENCHMARK(BM_HodgeSetup)->Args({0, 5})->Args({1, 257})->Unit(benchmark::kMillisecond);
BENCHMARK(BM_HodgeFrame)->Args({0, 5})->Args({1, 257})->Unit(benchmark::kMillisecond);

}  // namespace
}  // namespace tvf
