// The spatio-temporal optimization (paper §6.1): key frames only, and key frames with a
// moving element held at every frame between them.
#include "tvf/design/generate.h"

#include <benchmark/benchmark.h>

namespace tvf {
namespace {

Scene keyframe_scene(bool with_element) {
  Scene s;
  s.time.frames = 100;
  s.generator = Generator::spacetime;
  s.falloff = 40;
  s.solver.region_radius = 0.25;
  Keyframe k0, k1;
  KeyframeElement src, sad;
  src.kind = sad.kind = "singular";
  src.type = SingularType::source;
  src.at = Vec3(0.25, 0, 0);
  sad.jacobian << -1, 0, 0, 1;
  sad.at = Vec3(-0.25, 0, 0);
  k0.t = 0;
  k0.elements = {sad, src};
  k0.streamlines = {{{Vec3(-1, -0.7, 0), Vec3(1, -0.7, 0)}, 0.1}, {{Vec3(-1, 0.7, 0), Vec3(1, 0.7, 0)}, 0.1}};
  k1.t = 1;
  k1.streamlines = k0.streamlines;
  s.keyframes = {k0, k1};
  if (with_element) {
    SingularElement c;
    c.type = SingularType::ccw_center;
    c.jacobian = jacobian_of(*c.type);
    c.path = {{Vec3(-0.5, 0.45, 0), 0.1}, {Vec3(0.5, 0.45, 0), 0.9}};
    s.elements = {c};
    s.solver.region_radius = 0.1;
  }
  return s;
}

void run(benchmark::State& state, Scene s) {
  const auto space = make_design_space(s);
  GenerateReport report;
  for (auto _ : state) benchmark::DoNotOptimize(generate(*space, s, {}, &report).data().data());
  state.counters["vertices"] = space->mesh().num_vertices();
  state.counters["frames"] = s.time.frames;
  state.counters["cg_iterations"] = report.iterations;
  state.counters["residual"] = report.residual;
}

void BM_SpaceTimeKeyframesGrid(benchmark::State& state) {
  Scene s = keyframe_scene(false);
  const int n = static_cast<int>(state.range(0));
  s.domain.grid = GridSpec{n, n, {-1, -1}, {1, 1}};
  run(state, s);
}
BENCHMARK(BM_SpaceTimeKeyframesGrid)->Arg(65)->Arg(141)->Unit(benchmark::kMillisecond);

void BM_SpaceTimeKeyframesAndElementGrid(benchmark::State& state) {
  Scene s = keyframe_scene(true);
  const int n = static_cast<int>(state.range(0));
  s.domain.grid = GridSpec{n, n, {-1, -1}, {1, 1}};
  run(state, s);
}
BENCHMARK(BM_SpaceTimeKeyframesAndElementGrid)->Arg(65)->Arg(141)->Unit(benchmark::kMillisecond);

}  // namespace
}  // namespace tvf
