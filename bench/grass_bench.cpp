// Grass (Fig. 14): the target is 32,000 strands per frame well under a second on
// 2 cores. BM_GrassPose is the per-frame simulation (field at every root, the IK solve of
// every strand); BM_GrassFrame adds the picture (Cairo lines, one thread). PNG encoding
// and video are outside both.
#include "tvf/api/design.h"
#include "tvf/render/grass.h"

#include "tvf/scene/design_space.h"
#include "tvf/design/generate.h"
#include "tvf/scene/scene_json.h"

#include "bench_scenes.h"

#include <benchmark/benchmark.h>

#include <ctime>

namespace tvf {
namespace {

double cpu_seconds() {
  timespec c{};
  clock_gettime(CLOCK_PROCESS_CPUTIME_ID, &c);
  return static_cast<double>(c.tv_sec) + 1e-9 * static_cast<double>(c.tv_nsec);
}

void grass_case(benchmark::State& state, bool picture) {
  const Scene s = bench::on_grid(bench::combined_scene(), 65);
  const GeneratedField generated = generate_scene(s);  // the facade's one-shot (api/design.h)
  const auto& space = generated.space;
  const Field& field = generated.field;
  GrassOptions o;
  o.count = static_cast<int>(state.range(0));
  o.segments = static_cast<int>(state.range(1));
  Meadow meadow(space->bundle(), field, o);
  GrassRenderOptions ro;
  ro.image_size = 960;
  GrassRenderer renderer(meadow, ro);
  meadow.pose(0.0);  // warm-up outside the timing
  int k = 0;
  const double c0 = cpu_seconds();
  for (auto _ : state) {
    k = (k + 1) % field.frames();
    meadow.pose(field.time().time(k));
    if (picture) {
      const Image img = renderer.picture();
      benchmark::DoNotOptimize(img.pixels.data());
    }
    benchmark::DoNotOptimize(meadow.strand(0).data());
  }
  // CPU time of all threads per frame (the machine is shared; see texture_bench.cpp).
  const double cpu = (cpu_seconds() - c0) / static_cast<double>(state.iterations());
  state.counters["strands"] = static_cast<double>(o.count);
  state.counters["cpu_ms"] = 1e3 * cpu;
}

void BM_GrassPose(benchmark::State& state) { grass_case(state, false); }
void BM_GrassFrame(benchmark::State& state) { grass_case(state, true); }
// Arguments: strands, segments per strand.
BENCHMARK(BM_GrassPose)->Args({32000, 4})->Args({32000, 8})->Unit(benchmark::kMillisecond)->UseRealTime();
BENCHMARK(BM_GrassFrame)->Args({32000, 4})->Unit(benchmark::kMillisecond)->UseRealTime();

}  // namespace
}  // namespace tvf
