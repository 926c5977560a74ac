// Field-guided texture synthesis (issue 8): the target is a later frame of a 512 × 512
// picture or of a 20,000-vertex surface in about a second on 2 cores. One iteration is one
// later frame (advect the last frame, optimize the finest levels against it); the first
// frame (coarse to fine from random pixels) is made once, outside the timing.
// cpu_ms is the CPU time of all threads per frame: on a shared machine the wall-clock time
// says little; cpu_ms / 2 is what two idle cores take when the work splits evenly.
#include "bench_scenes.h"

#include "tvf/api/design.h"
#include "tvf/mesh/primitives.h"
#include "tvf/synth/planar_synthesis.h"
#include "tvf/synth/surface_synthesis.h"

#include <benchmark/benchmark.h>

#include <ctime>

namespace tvf {
namespace {

double process_cpu_ms() {
  timespec t{};
  clock_gettime(CLOCK_PROCESS_CPUTIME_ID, &t);
  return static_cast<double>(t.tv_sec) * 1e3 + static_cast<double>(t.tv_nsec) * 1e-6;
}

template <class Synth>
void time_frames(benchmark::State& state, Synth& synth, const Field& field, int samples) {
  synth.advance(field.time().time(0));
  int k = 0;
  double distance = 0;
  const double cpu0 = process_cpu_ms();
  for (auto _ : state) {
    k = k % (field.frames() - 1) + 1;
    distance += synth.advance(field.time().time(k)).patch_distance;
  }
  const double cpu = process_cpu_ms() - cpu0;
  const auto n = static_cast<double>(std::max<benchmark::IterationCount>(state.iterations(), 1));
  state.counters["cpu_ms"] = cpu / n;
  state.counters["vertices"] = samples;
  state.counters["frames"] = 1;
  state.counters["patch_distance"] = distance / n;
}

// The combined design (bench_scenes.h) on a 65 × 65 grid; pebbles, 64-pixel exemplar.
void BM_SynthPlanarFrame(benchmark::State& state) {
  const Scene s = bench::on_grid(bench::combined_scene(), 65);
  const GeneratedField generated = generate_scene(s);  // the facade's one-shot (api/design.h)
  const auto& space = generated.space;
  const Field& field = generated.field;
  SynthesisOptions o;
  o.size = static_cast<int>(state.range(0));
  PlanarSynthesizer synth(space->bundle(), field, make_procedural_exemplar(ProceduralExemplar::pebbles, 64, 1), o);
  time_frames(state, synth, field, synth.width() * synth.height());
}
BENCHMARK(BM_SynthPlanarFrame)->Arg(256)->Arg(512)->Unit(benchmark::kMillisecond)->UseRealTime();

// A vortex and a source on the 20,252-vertex geodesic sphere; pebbles, 64-pixel exemplar.
// The argument is the sample density (samples per mesh edge): 1, a sample per vertex; 0,
// the automatic default (2 here: 80,992 samples).
void BM_SynthSphere20kFrame(benchmark::State& state) {
  Scene s = bench::sphere_scene(5);
  DesignSpace space(make_geodesic_sphere(45));
  const Field field = generate(space, s);
  SynthesisOptions o;
  o.density = static_cast<int>(state.range(0));
  SurfaceSynthesizer synth(space.bundle(), field, make_procedural_exemplar(ProceduralExemplar::pebbles, 64, 1), o);
  time_frames(state, synth, field, synth.sample_mesh().num_vertices());
}
BENCHMARK(BM_SynthSphere20kFrame)->Arg(1)->Arg(0)->Unit(benchmark::kMillisecond)->UseRealTime();

}  // namespace
}  // namespace tvf
