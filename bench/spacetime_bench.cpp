// The spatio-temporal optimization (paper §6.1) — issue 3's table: key frames only and
// key frames with a moving element held at every frame between them, on the paper's
// 65×65 grid and a 20,252-vertex sphere; the solve alone by each method (tvf's choice,
// matrix-free CG, and the paper's kind of method, BiCGStab + Jacobi); a warm re-solve
// after a local edit; 100k and 1M vertices.
#include "bench_scenes.h"

#include "tvf/design/generate.h"
#include "tvf/mesh/grid.h"
#include "tvf/mesh/primitives.h"
#include "tvf/solve/spacetime.h"

#include <benchmark/benchmark.h>
#include <sys/resource.h>

#include <algorithm>
#include <cmath>
#include <ctime>

namespace tvf {
namespace {

// CPU time of all threads of the process, in ms (the benchmarks' own time is wall-clock):
// on a loaded machine, cpu_ms / cores is what idle cores would take.
double process_cpu_ms() {
  timespec t{};
  clock_gettime(CLOCK_PROCESS_CPUTIME_ID, &t);
  return static_cast<double>(t.tv_sec) * 1e3 + static_cast<double>(t.tv_nsec) * 1e-6;
}

double peak_memory_mb() {
  rusage u{};
  getrusage(RUSAGE_SELF, &u);
  return static_cast<double>(u.ru_maxrss) / 1024.0;  // ru_maxrss is in KiB on Linux
}

KeyframeElement static_singular(SingularType type, const Vec3& at) {
  KeyframeElement e;
  e.kind = "singular";
  e.type = type;
  e.jacobian = jacobian_of(type);
  e.at = at;
  return e;
}

// Two key frames (a saddle–source pair and a plain flow) on the grid over [-1, 1]²;
// with_element adds a vortex moving between them, held at every frame.
Scene grid_scene(int n, bool with_element) {
  Scene s;
  s.domain.grid = GridSpec{n, n, {-1, -1}, {1, 1}};
  s.time.frames = 100;
  s.generator = Generator::spacetime;
  s.falloff = 40;
  s.solver.region_radius = with_element ? 0.1 : 0.25;
  Keyframe k0, k1;
  KeyframeElement sad = static_singular(SingularType::saddle, Vec3(-0.25, 0, 0));
  sad.type.reset();
  sad.jacobian << -1, 0, 0, 1;
  k0.t = 0;
  k0.elements = {sad, static_singular(SingularType::source, Vec3(0.25, 0, 0))};
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
  }
  return s;
}

// Two key frames on the unit sphere (a vortex and a source, then the vortex elsewhere and
// a sink); with_element adds a vortex travelling along the equator.
Scene sphere_scene(bool with_element) {
  Scene s;
  s.domain.sphere = SphereSpec{5, 1.0};  // replaced by the 20,252-vertex geodesic sphere
  s.time.frames = 100;
  s.generator = Generator::spacetime;
  s.falloff = 20;
  s.solver.region_radius = 0.1;
  Keyframe k0, k1;
  k0.t = 0;
  k0.elements = {static_singular(SingularType::ccw_center, Vec3(1, 0, 0)),
                 static_singular(SingularType::source, Vec3(0, 0, 1))};
  k1.t = 1;
  k1.elements = {static_singular(SingularType::ccw_center, Vec3(0, 1, 0)),
                 static_singular(SingularType::sink, Vec3(0, 0, -1))};
  s.keyframes = {k0, k1};
  if (with_element) {
    SingularElement c;
    c.type = SingularType::cw_center;
    c.jacobian = jacobian_of(*c.type);
    c.path = {{Vec3(0, -1, 0), 0.1}, {Vec3(-1, 0, 0), 0.5}, {Vec3(0, 1, 0).normalized(), 0.9}};
    s.elements = {c};
  }
  return s;
}

std::unique_ptr<DesignSpace> sphere_space() { return std::make_unique<DesignSpace>(make_geodesic_sphere(45)); }

void counters(benchmark::State& state, int vertices, int frames, const SolveReport& r, double cpu_ms) {
  state.counters["cpu_ms"] = cpu_ms / static_cast<double>(std::max<benchmark::IterationCount>(state.iterations(), 1));
  state.counters["vertices"] = vertices;
  state.counters["frames"] = frames;
  state.counters["cg_iterations"] = r.iterations;
  state.counters["residual"] = r.residual;
  state.counters["peak_mb"] = peak_memory_mb();
}

// The whole generation: key-frame designs, element regions, the solve.
void generation(benchmark::State& state, const DesignSpace& space, const Scene& s) {
  GenerateReport report;
  const double cpu0 = process_cpu_ms();
  for (auto _ : state) benchmark::DoNotOptimize(generate(space, s, {}, &report).data().data());
  const double cpu = process_cpu_ms() - cpu0;
  SolveReport r;
  r.iterations = report.iterations;
  r.residual = report.residual;
  counters(state, space.mesh().num_vertices(), s.time.frames, r, cpu);
  state.SetLabel(report.method);
}

// The solve alone, from the interpolation-in-time first guess, by one method.
void solve_only(benchmark::State& state, const DesignSpace& space, const Scene& s, SpaceTimeMethod method,
                int coarse_modes = SpaceTimeOptions{}.coarse_modes, int local_rings = SpaceTimeOptions{}.local_rings,
                int moving_rings = SpaceTimeOptions{}.moving_rings) {
  const SpaceTimeProblem p = spacetime_problem(space, s);
  const SpaceTimeSolver solver(p.laplacian, s.time.frames, s.solver.temporal_weight);
  std::vector<cplx> z(p.values.size());
  SpaceTimeOptions o;
  o.method = method;
  o.coarse_modes = coarse_modes;
  o.local_rings = local_rings;
  o.moving_rings = moving_rings;
  o.tolerance = s.solver.tolerance;
  o.max_iterations = 100000;
  SolveReport r;
  double cpu = 0;
  for (auto _ : state) {
    state.PauseTiming();
    solver.interpolate_in_time(p.fixed, p.values, z);
    const double cpu0 = process_cpu_ms();
    state.ResumeTiming();
    r = solver.solve(p.fixed, p.values, z, o);
    cpu += process_cpu_ms() - cpu0;
  }
  counters(state, space.mesh().num_vertices(), s.time.frames, r, cpu);
  state.SetLabel(r.method.substr(0, r.method.find(',')));
}

void BM_SpaceTimeKeyframesGrid(benchmark::State& state) {
  const Scene s = grid_scene(static_cast<int>(state.range(0)), false);
  generation(state, *make_design_space(s), s);
}
BENCHMARK(BM_SpaceTimeKeyframesGrid)->Arg(65)->Arg(141)->Arg(317)->Unit(benchmark::kMillisecond);

void BM_SpaceTimeKeyframesAndElementGrid(benchmark::State& state) {
  const Scene s = grid_scene(static_cast<int>(state.range(0)), true);
  generation(state, *make_design_space(s), s);
}
BENCHMARK(BM_SpaceTimeKeyframesAndElementGrid)->Arg(65)->Arg(141)->Arg(317)->Unit(benchmark::kMillisecond);
// Issue 15's "iterations flat from 4k to 1M": the same two designs on a 1001² grid (1M
// vertices × 100 frames), run once each (minutes of CPU, ~10 GB).
BENCHMARK(BM_SpaceTimeKeyframesGrid)->Arg(1001)->Iterations(1)->Repetitions(1)->Unit(benchmark::kMillisecond);
BENCHMARK(BM_SpaceTimeKeyframesAndElementGrid)->Arg(1001)->Iterations(1)->Repetitions(1)->Unit(benchmark::kMillisecond);

void BM_SpaceTimeKeyframesSphere20k(benchmark::State& state) {
  generation(state, *sphere_space(), sphere_scene(false));
}
BENCHMARK(BM_SpaceTimeKeyframesSphere20k)->Unit(benchmark::kMillisecond);

void BM_SpaceTimeKeyframesAndElementSphere20k(benchmark::State& state) {
  generation(state, *sphere_space(), sphere_scene(true));
}
BENCHMARK(BM_SpaceTimeKeyframesAndElementSphere20k)->Unit(benchmark::kMillisecond);

// The solve alone by each method: 0 tvf's automatic choice, 1 matrix-free CG (two-level
// preconditioner), 2 BiCGStab + Jacobi on the assembled system (the paper's kind of
// method), 3 matrix-free CG with the temporal line solves alone (before issue 15), 4 the
// two-level CG with 8 coarse temporal modes instead of 4, 5 the two-level CG without the
// local solve near the moving constraints (before it; method 1 has it), 6 the local solve
// on the cut lines' vertices grown by one ring of neighbours (method 1: those vertices alone).
// 7 the two-level CG with the local solve and 2 coarse temporal modes instead of 4.
// 8 the temporal modes with local solves at the moving constraints (SpaceTimeMethod::
// modes_local, four rings: what automatic takes for a moving element since issue 15's third
// step), 9 the same with two rings, 10 with one.
SpaceTimeMethod method_of(int64_t m) {
  return m == 0 ? SpaceTimeMethod::automatic : m >= 8 ? SpaceTimeMethod::modes_local : m >= 3 ? SpaceTimeMethod::cg
         : m == 1         ? SpaceTimeMethod::cg
                          : SpaceTimeMethod::bicgstab_jacobi;
}

int coarse_modes_of(int64_t m) { return m == 3 ? 0 : m == 4 ? 8 : m == 7 ? 2 : 4; }
int local_rings_of(int64_t m) { return m == 5 ? -1 : m == 6 ? 1 : SpaceTimeOptions{}.local_rings; }
int moving_rings_of(int64_t m) { return m == 9 ? 2 : m == 10 ? 1 : SpaceTimeOptions{}.moving_rings; }

void BM_SolveGrid65(benchmark::State& state) {
  const Scene s = grid_scene(65, state.range(0) != 0);
  solve_only(state, *make_design_space(s), s, method_of(state.range(1)), coarse_modes_of(state.range(1)),
             local_rings_of(state.range(1)), moving_rings_of(state.range(1)));
}
BENCHMARK(BM_SolveGrid65)
    ->ArgNames({"element", "method"})
    ->ArgsProduct({{0, 1}, {0, 1, 3, 4, 5, 6, 7, 8, 9, 10}})
    ->Unit(benchmark::kMillisecond);
// The paper's kind of method takes tens of seconds even here: once.
BENCHMARK(BM_SolveGrid65)
    ->ArgNames({"element", "method"})
    ->ArgsProduct({{0, 1}, {2}})
    ->Iterations(1)
    ->Repetitions(1)
    ->Unit(benchmark::kMillisecond);

void BM_SolveSphere20k(benchmark::State& state) {
  solve_only(state, *sphere_space(), sphere_scene(state.range(0) != 0), method_of(state.range(1)),
             coarse_modes_of(state.range(1)), local_rings_of(state.range(1)), moving_rings_of(state.range(1)));
}
BENCHMARK(BM_SolveSphere20k)
    ->ArgNames({"element", "method"})
    ->ArgsProduct({{0, 1}, {0, 1, 3, 4, 5, 6, 7, 8, 9, 10}})
    ->Unit(benchmark::kMillisecond);
// The paper's kind of method at 20k × 100 takes minutes: once.
BENCHMARK(BM_SolveSphere20k)
    ->ArgNames({"element", "method"})
    ->ArgsProduct({{0, 1}, {2}})
    ->Iterations(1)
    ->Repetitions(1)
    ->Unit(benchmark::kMillisecond);

// A warm re-solve after a local edit: the vectors of key frame 0 within 0.2 of (1, 0, 0)
// turned by 0.3 rad (as when a designer nudges an element) and back, each re-solved to
// 1e-6 from the previous solution, by a solver object that keeps its set-up.
void BM_ResolveAfterEditSphere20k(benchmark::State& state) {
  const auto space = sphere_space();
  const Scene s = sphere_scene(state.range(0) != 0);
  SpaceTimeProblem p = spacetime_problem(*space, s);
  const SpaceTimeSolver solver(p.laplacian, s.time.frames, s.solver.temporal_weight);
  std::vector<cplx> solved(p.values.size());
  solver.interpolate_in_time(p.fixed, p.values, solved);
  SpaceTimeOptions o;
  solver.solve(p.fixed, p.values, solved, o);
  std::vector<cplx> edited = p.values;
  for (int v = 0; v < space->mesh().num_vertices(); ++v)
    if ((space->mesh().position(v) - Vec3(1, 0, 0)).norm() < 0.2)
      edited[static_cast<size_t>(v)] *= std::polar(1.0, 0.3);
  o.tolerance = 1e-6;
  // Edit, undo, edit, …: each solve starts from the last one's result with a key frame
  // changed in a small region, as in the designer.
  std::vector<cplx> z = solved;
  SolveReport r;
  double cpu = 0;
  bool edit = true;
  for (auto _ : state) {
    const double cpu0 = process_cpu_ms();
    r = solver.solve(p.fixed, edit ? edited : p.values, z, o);
    cpu += process_cpu_ms() - cpu0;
    edit = !edit;
  }
  counters(state, space->mesh().num_vertices(), s.time.frames, r, cpu);
  state.SetLabel(r.method);  // with the modes' spatial iterations in all
}
BENCHMARK(BM_ResolveAfterEditSphere20k)->ArgName("element")->Arg(0)->Arg(1)->Unit(benchmark::kMillisecond);

// Issue 15's designer case on the 20,252-vertex sphere × 100 frames: elements that stay
// put (a vortex and a source, fixed at every frame), with the two key frames of
// sphere_scene (keyframes:1) or none (keyframes:0, the page's latency test's scene). The
// whole generation (element regions, key-frame designs, the solve) by the designer's
// path: warm:0 a generation from nothing (no cache); warm:1 the source moved (to the next
// of kPlaces places, round and round: each time a fixed set the solver does not keep) and
// the design generated again with the GenerateCache that made the last one (the solver
// object, its last solution), as `tvf serve` does after a click.
constexpr int kPlaces = 4;
Scene fixed_elements_scene(bool keyframes, int place) {
  Scene s = sphere_scene(false);
  if (!keyframes) s.keyframes.clear();
  SingularElement vortex, source;
  vortex.type = SingularType::ccw_center;
  vortex.jacobian = jacobian_of(*vortex.type);
  vortex.path = {{Vec3(0.0, -0.8, 0.6).normalized(), 0}};
  source.type = SingularType::source;
  source.jacobian = jacobian_of(*source.type);
  source.path = {{Vec3(-0.3 + 0.2 * place, -1, place % 2 ? 0.5 : 0.1).normalized(), 0}};
  s.elements = {vortex, source};
  return s;
}

void BM_FixedElementsSphere20k(benchmark::State& state) {
  const auto space = sphere_space();
  const bool keyframes = state.range(0) != 0, warm = state.range(1) != 0;
  std::vector<Scene> scenes;
  for (int place = 0; place < kPlaces; ++place) scenes.push_back(fixed_elements_scene(keyframes, place));
  GenerateCache cache;
  GenerateOptions options;
  if (warm) {
    options.cache = &cache;
    generate(*space, scenes[0], options);
  }
  GenerateReport report;
  double cpu = 0;
  int k = 1;
  for (auto _ : state) {
    const double cpu0 = process_cpu_ms();
    benchmark::DoNotOptimize(generate(*space, scenes[static_cast<size_t>(k)], options, &report).data().data());
    cpu += process_cpu_ms() - cpu0;
    if (warm) k = (k + 1) % kPlaces;
  }
  SolveReport r;
  r.iterations = report.iterations;
  r.residual = report.residual;
  counters(state, space->mesh().num_vertices(), scenes[0].time.frames, r, cpu);
  state.SetLabel(report.method);
}
BENCHMARK(BM_FixedElementsSphere20k)
    ->ArgNames({"keyframes", "warm"})
    ->ArgsProduct({{0, 1}, {0, 1}})
    ->Unit(benchmark::kMillisecond);

// The solve alone of the same designer's sequence, by the temporal modes with the slow
// modes' sparse Cholesky factorizations (direct:1, SpaceTimeOptions::direct_shift's
// default) or Jacobi-PCG for every mode (direct:0, the method before). warm:0 a new solver
// from the interpolation in time; warm:1 the source moved and the last result (its fixed
// entries replaced) the first guess, the solver object kept, as generate() with a cache.
// direct:2 the modes with shifts below 0.3 factored (three with the key frames, not one).
void BM_FixedElementsSphere20kSolve(benchmark::State& state) {
  const auto space = sphere_space();
  const bool keyframes = state.range(0) != 0, warm = state.range(1) != 0;
  SpaceTimeOptions o;
  if (state.range(2) == 0) o.direct_shift = 0;
  if (state.range(2) == 2) o.direct_shift = 0.3;
  std::vector<SpaceTimeProblem> p;
  for (int place = 0; place < kPlaces; ++place) p.push_back(spacetime_problem(*space, fixed_elements_scene(keyframes, place)));
  const int frames = 100;
  auto solver = std::make_unique<SpaceTimeSolver>(p[0].laplacian, frames, 30.0);
  std::vector<cplx> z(p[0].values.size());
  solver->interpolate_in_time(p[0].fixed, p[0].values, z);
  if (warm) solver->solve(p[0].fixed, p[0].values, z, o);
  SolveReport r;
  double cpu = 0;
  int k = 1;
  for (auto _ : state) {
    state.PauseTiming();
    const SpaceTimeProblem& q = p[static_cast<size_t>(k)];
    if (warm) {
      for (size_t e = 0; e < z.size(); ++e)
        if (q.fixed[e]) z[e] = q.values[e];
    } else {
      solver = std::make_unique<SpaceTimeSolver>(q.laplacian, frames, 30.0);
      solver->interpolate_in_time(q.fixed, q.values, z);
    }
    const double cpu0 = process_cpu_ms();
    state.ResumeTiming();
    r = solver->solve(q.fixed, q.values, z, o);
    cpu += process_cpu_ms() - cpu0;
    if (warm) k = (k + 1) % kPlaces;
  }
  counters(state, space->mesh().num_vertices(), frames, r, cpu);
  state.SetLabel(r.method);
}
BENCHMARK(BM_FixedElementsSphere20kSolve)
    ->ArgNames({"keyframes", "warm", "direct"})
    ->ArgsProduct({{0, 1}, {0, 1}, {0, 1, 2}})
    ->Unit(benchmark::kMillisecond);

// 1M vertices × 100 frames: a 1000 × 1000 grid between two analytic key frames (a
// wave and a vortex), the solve alone.
void BM_SolveKeyframesGrid1M(benchmark::State& state) {
  const int n = 1000, frames = 100;
  const Mesh mesh = make_grid(GridSpec{n, n, {-1, -1}, {1, 1}}, "1M grid");
  const TangentBundle bundle(mesh);
  const ConnectionLaplacian l = connection_laplacian(bundle);
  const auto nv = static_cast<size_t>(mesh.num_vertices());
  std::vector<char> fixed(nv * frames, 0);
  std::vector<cplx> values(nv * frames, cplx(0, 0)), z(nv * frames);
  for (size_t i = 0; i < nv; ++i) {
    const Vec3& x = mesh.position(static_cast<int>(i));
    fixed[i] = fixed[(frames - 1) * nv + i] = 1;
    values[i] = std::polar(1.0 + 0.5 * x.y(), kPi * x.x());
    values[(frames - 1) * nv + i] = cplx(-x.y(), x.x());
  }
  const SpaceTimeSolver solver(l, frames, 30.0);
  SolveReport r;
  double cpu = 0;
  for (auto _ : state) {
    state.PauseTiming();
    solver.interpolate_in_time(fixed, values, z);
    const double cpu0 = process_cpu_ms();
    state.ResumeTiming();
    r = solver.solve(fixed, values, z);
    cpu += process_cpu_ms() - cpu0;
  }
  counters(state, static_cast<int>(nv), frames, r, cpu);
  state.SetLabel(r.method.substr(0, r.method.find(',')));
}
BENCHMARK(BM_SolveKeyframesGrid1M)->Iterations(1)->Repetitions(1)->Unit(benchmark::kMillisecond);

}  // namespace
}  // namespace tvf
