// Texture animation frames (IBFV) on a planar domain: the target is ≥ 10 frames/s
// at 1024 × 1024 on 2 cores. One iteration advances the texture by one frame and makes
// its picture (the per-frame work; PNG encoding and video are outside it).
#include "tvf/api/design.h"
#include "tvf/render/texture_animation.h"
#include "tvf/mesh/primitives.h"
#include "tvf/render/mesh_renderer.h"
#include "tvf/render/surface_texture.h"

#include "bench_scenes.h"

#include <benchmark/benchmark.h>

#include <ctime>
#include <filesystem>
#include <string>

#include <sys/resource.h>
#include <unistd.h>

namespace tvf {
namespace {

void BM_TextureFrame(benchmark::State& state) {
  const Scene s = bench::on_grid(bench::combined_scene(), 65);
  const GeneratedField generated = generate_scene(s);  // the facade's one-shot (api/design.h)
  const auto& space = generated.space;
  const Field& field = generated.field;
  TextureOptions o;
  o.size = static_cast<int>(state.range(0));
  o.lic = static_cast<int>(state.range(1));
  TextureAnimator animator(space->bundle(), field, o);
  animator.advance(0.0);  // warm-up outside the timing
  int k = 0;
  timespec c0{}, c1{};
  clock_gettime(CLOCK_PROCESS_CPUTIME_ID, &c0);
  for (auto _ : state) {
    k = (k + 1) % field.frames();
    animator.advance(field.time().time(k));
    const Image img = animator.picture();
    benchmark::DoNotOptimize(img.pixels.data());
  }
  clock_gettime(CLOCK_PROCESS_CPUTIME_ID, &c1);
  // CPU time of all threads per frame: on a machine shared with other work the wall-clock
  // rate understates what two free cores do; 2 / cpu is the rate on two idle cores when
  // the frame's loops split evenly (they are row-parallel).
  const double cpu = (static_cast<double>(c1.tv_sec - c0.tv_sec) + 1e-9 * static_cast<double>(c1.tv_nsec - c0.tv_nsec)) /
                     static_cast<double>(state.iterations());
  state.counters["frames"] = 1;
  state.counters["fps"] = benchmark::Counter(static_cast<double>(state.iterations()), benchmark::Counter::kIsRate);
  state.counters["cpu_ms"] = 1e3 * cpu;
  state.counters["fps_2_idle_cores"] = 2.0 / cpu;
}
// Arguments: size, LIC length (size/64 is the default; 0: the advected texture only).
BENCHMARK(BM_TextureFrame)->Args({512, 8})->Args({1024, 0})->Args({1024, 16})
    ->Unit(benchmark::kMillisecond)->UseRealTime();

// The whole `tvf render texture` of the 65² combined design at SIZE² into an MP4 (issue
// 15's target: ≥ 10 frames/s at 1024² end to end with the video): warm-up, every frame's
// advection and picture, and ffmpeg encoding them as they come (a child process: its CPU
// time is counted, from getrusage(RUSAGE_CHILDREN) once it has been waited for).
// cpu_ms: CPU time of tvf and ffmpeg per frame; fps_2_idle_cores = 2 / cpu.
void BM_TextureVideo(benchmark::State& state) {
  const Scene s = bench::on_grid(bench::combined_scene(), 65);
  const GeneratedField generated = generate_scene(s);
  TextureAnimationOptions o;
  o.texture.size = static_cast<int>(state.range(0));
  const std::filesystem::path dir =
      std::filesystem::temp_directory_path() / ("tvf-bench-video-" + std::to_string(::getpid()));
  std::filesystem::create_directories(dir);
  o.video = (dir / "texture.mp4").string();
  auto cpu_now = [] {
    rusage self{}, children{};
    getrusage(RUSAGE_SELF, &self);
    getrusage(RUSAGE_CHILDREN, &children);
    auto sec = [](const timeval& t) { return static_cast<double>(t.tv_sec) + 1e-6 * static_cast<double>(t.tv_usec); };
    return sec(self.ru_utime) + sec(self.ru_stime) + sec(children.ru_utime) + sec(children.ru_stime);
  };
  int frames = 0;
  const double c0 = cpu_now();
  for (auto _ : state) frames += write_texture_animation(generated.space->bundle(), generated.field, o).frames;
  const double cpu = (cpu_now() - c0) / std::max(1, frames);
  std::filesystem::remove_all(dir);
  state.counters["frames"] = static_cast<double>(frames) / static_cast<double>(state.iterations());
  state.counters["fps"] = benchmark::Counter(static_cast<double>(frames), benchmark::Counter::kIsRate);
  state.counters["cpu_ms"] = 1e3 * cpu;
  state.counters["fps_2_idle_cores"] = 2.0 / cpu;
}
BENCHMARK(BM_TextureVideo)->Arg(1024)->Unit(benchmark::kMillisecond)->UseRealTime();

// One frame of the texture animation on a 20,000-vertex surface (a 200 × 100 torus, a
// time-varying swirl round its axis) at SIZE × SIZE: advect the texture samples, the LIC
// along the surface, the vertex colours, and the offscreen OpenGL picture (llvmpipe on a
// machine without a GPU).
void BM_SurfaceTextureFrame(benchmark::State& state) {
  const Mesh torus = make_torus(200, 100);
  const TangentBundle bundle(torus);
  Field field(TimeSampling{0, 1, 40}, torus.num_vertices());
  for (int j = 0; j < field.frames(); ++j)
    for (int v = 0; v < torus.num_vertices(); ++v) {
      const Vec3& x = torus.position(v);
      const Vec3 w = Vec3::UnitZ().cross(x) + (0.5 + field.time().time(j)) * Vec3(0, 0, 1).cross(x).cross(x).normalized();
      field.at(j, v) = bundle.world_to_vertex(v, w);
    }
  TextureOptions o;
  o.size = static_cast<int>(state.range(0));
  SurfaceTextureAnimator animator(bundle, field, o);
  MeshRenderer renderer;
  renderer.set_mesh(animator.sample_positions(), animator.sample_triangles());
  RenderOptions ro;
  ro.width = ro.height = o.size;
  animator.advance(0.0);
  int k = 0;
  timespec c0{}, c1{};
  clock_gettime(CLOCK_PROCESS_CPUTIME_ID, &c0);
  for (auto _ : state) {
    k = (k + 1) % field.frames();
    animator.advance(field.time().time(k));
    renderer.set_colors(animator.colors());
    const Image img = renderer.render(animator.camera(), ro);
    benchmark::DoNotOptimize(img.pixels.data());
  }
  clock_gettime(CLOCK_PROCESS_CPUTIME_ID, &c1);
  const double cpu = (static_cast<double>(c1.tv_sec - c0.tv_sec) + 1e-9 * static_cast<double>(c1.tv_nsec - c0.tv_nsec)) /
                     static_cast<double>(state.iterations());
  state.counters["cpu_ms"] = 1e3 * cpu;  // all threads, llvmpipe's included
  state.counters["samples"] = static_cast<double>(animator.sample_positions().size());
  state.counters["fps"] = benchmark::Counter(static_cast<double>(state.iterations()), benchmark::Counter::kIsRate);
}
BENCHMARK(BM_SurfaceTextureFrame)->Arg(512)->Arg(800)->Unit(benchmark::kMillisecond)->UseRealTime();

// The same frame in image space (SurfaceImageAnimator, what `tvf render texture` uses on
// surfaces since issue 14): SIZE × SIZE texels, the mesh rasterized once for the camera;
// per frame the field at the texels, the advection, the LIC and the composite with the
// renderer's two pictures (made once, outside the timing). VERTICES picks the surface: the
// 20,000-vertex torus above, or a 40,962-vertex geodesic sphere (icosphere level 6) with a
// rotation about a tilted axis plus a time-varying swirl.
void BM_SurfaceImageFrame(benchmark::State& state) {
  const bool sphere = state.range(1) > 30000;
  const Mesh mesh = sphere ? make_icosphere(6, 1.0) : make_torus(200, 100);
  const TangentBundle bundle(mesh);
  Field field(TimeSampling{0, 1, 40}, mesh.num_vertices());
  for (int j = 0; j < field.frames(); ++j)
    for (int v = 0; v < mesh.num_vertices(); ++v) {
      const Vec3& x = mesh.position(v);
      const double t = field.time().time(j);
      const Vec3 w = sphere ? Vec3(Vec3(0.3, 0.2, 1).normalized().cross(x) + t * Vec3(0, 0, 1).cross(x).cross(x))
                            : Vec3(Vec3::UnitZ().cross(x) + (0.5 + t) * Vec3(0, 0, 1).cross(x).cross(x).normalized());
      field.at(j, v) = bundle.world_to_vertex(v, w);
    }
  TextureOptions o;
  o.size = static_cast<int>(state.range(0));
  SurfaceImageAnimator animator(bundle, field, o);
  MeshRenderer renderer;
  renderer.set_mesh(mesh);
  RenderOptions ro;
  ro.width = ro.height = o.size;
  ro.ambient = 0.5;
  renderer.set_colors(std::vector<std::uint32_t>(static_cast<size_t>(mesh.num_vertices()), 0u));
  const Image dark = renderer.render(animator.camera(), ro);
  renderer.set_colors(std::vector<std::uint32_t>(static_cast<size_t>(mesh.num_vertices()), 0xFFFFFFu));
  const Image lit = renderer.render(animator.camera(), ro);
  animator.advance(0.0);
  int k = 0;
  timespec c0{}, c1{};
  clock_gettime(CLOCK_PROCESS_CPUTIME_ID, &c0);
  for (auto _ : state) {
    k = (k + 1) % field.frames();
    animator.advance(field.time().time(k));
    const Image img = animator.composite(lit, dark);
    benchmark::DoNotOptimize(img.pixels.data());
  }
  clock_gettime(CLOCK_PROCESS_CPUTIME_ID, &c1);
  const double cpu = (static_cast<double>(c1.tv_sec - c0.tv_sec) + 1e-9 * static_cast<double>(c1.tv_nsec - c0.tv_nsec)) /
                     static_cast<double>(state.iterations());
  state.counters["cpu_ms"] = 1e3 * cpu;
  state.counters["vertices"] = mesh.num_vertices();
  state.counters["fps"] = benchmark::Counter(static_cast<double>(state.iterations()), benchmark::Counter::kIsRate);
  state.counters["fps_2_idle_cores"] = 2.0 / cpu;
}
BENCHMARK(BM_SurfaceImageFrame)->Args({512, 20000})->Args({512, 40962})->Args({800, 20000})
    ->Unit(benchmark::kMillisecond)->UseRealTime();

}  // namespace
}  // namespace tvf
