#include "tvf/render/surface_texture.h"

#include "tvf/analysis/singularities.h"
#include "tvf/core/error.h"
#include "tvf/integrate/streamline.h"
#include "tvf/integrate/surface_walk.h"
#include "tvf/render/frame_output.h"
#include "tvf/render/plots.h"
#include "tvf/render/video.h"

#include <fmt/format.h>
#include <tbb/blocked_range.h>
#include <tbb/parallel_for.h>

#include <algorithm>
#include <array>
#include <chrono>
#include <cmath>
#include <filesystem>
#include <memory>
#include <random>

namespace tvf {

namespace {

void check_option(bool ok, const std::string& name, const std::string& what) {
  if (!ok) throw Error(fmt::format("texture option {}: {}", name, what));
}

std::uint64_t splitmix(std::uint64_t x) {
  x += 0x9E3779B97F4A7C15ull;
  x = (x ^ (x >> 30)) * 0xBF58476D1CE4E5B9ull;
  x = (x ^ (x >> 27)) * 0x94D049BB133111EBull;
  return x ^ (x >> 31);
}

std::uint32_t to_rgb(const std::array<double, 3>& c) {
  auto ch = [](double v) { return static_cast<std::uint8_t>(std::lround(std::clamp(v, 0.0, 1.0) * 255)); };
  return rgb(ch(c[0]), ch(c[1]), ch(c[2]));
}

}  // namespace

SurfaceTextureAnimator::SurfaceTextureAnimator(const TangentBundle& bundle, const Field& field,
                                               const TextureOptions& options, const SurfaceView& view)
    : bundle_(bundle), field_(field), o_(options), view_(view) {
  const Mesh& mesh = bundle.mesh();
  if (bundle.is_flat())
    throw Error("surface texture animation: the domain is planar (TextureAnimator draws planar domains)");
  TVF_CHECK(field.num_vertices() == mesh.num_vertices(), "field of {} vertices on a mesh of {}",
            field.num_vertices(), mesh.num_vertices());
  check_option(o_.size >= 16 && o_.size <= 8192, "size", fmt::format("{} pixels is outside [16, 8192]", o_.size));
  check_option(o_.alpha > 0 && o_.alpha <= 1, "alpha", fmt::format("{} is outside (0, 1]", o_.alpha));
  check_option(std::isfinite(o_.noise_scale) && o_.noise_scale >= 0 && o_.noise_scale <= o_.size / 4.0, "noise_scale",
               fmt::format("{} pixels is outside [0, size/4]", o_.noise_scale));
  check_option(o_.noise_period >= 2 && o_.noise_period <= 100000, "noise_period",
               fmt::format("{} frames is outside [2, 100000]", o_.noise_period));
  check_option(std::isfinite(o_.pixels_per_frame) && o_.pixels_per_frame >= 0 && o_.pixels_per_frame <= o_.size,
               "pixels_per_frame", fmt::format("{} is outside [0, size]", o_.pixels_per_frame));
  check_option(o_.lic >= -1 && o_.lic <= 1000, "lic", fmt::format("{} pixels is outside [0, 1000] (or -1: automatic)", o_.lic));
  if (o_.lic < 0) o_.lic = std::max(1, static_cast<int>(std::lround(o_.size / 64.0)));
  check_option(o_.warmup >= 0 && o_.warmup <= 100000, "warmup", fmt::format("{} is outside [0, 100000]", o_.warmup));
  check_option(std::isfinite(o_.contrast) && o_.contrast > 0 && o_.contrast <= 100, "contrast",
               fmt::format("{} is outside (0, 100]", o_.contrast));
  check_option(std::isfinite(view_.spacing) && view_.spacing >= 0.25 && view_.spacing <= 100, "spacing",
               fmt::format("{} pixels is outside [0.25, 100]", view_.spacing));
  check_option(view_.max_samples >= 3 && view_.max_samples <= 100'000'000, "max_samples",
               fmt::format("{} is outside [3, 100000000]", view_.max_samples));
  check_option(view_.direction.allFinite() && view_.direction.norm() > 0, "view", "the view direction must be a non-zero vector");
  check_option(view_.up.allFinite() && view_.up.norm() > 0, "up", "the up direction must be a non-zero vector");
  check_option(std::isfinite(view_.fov) && view_.fov >= 1 && view_.fov <= 120, "fov",
               fmt::format("{}° is outside [1, 120]", view_.fov));
  for (const cplx& z : field.data())
    if (!std::isfinite(z.real()) || !std::isfinite(z.imag()))
      throw_input_error(mesh.source(), "", "the field has a value that is not a finite number");

  // The camera, and pixels per world unit at the distance of the mesh's centre.
  size_ = o_.size;
  constexpr double margin = 1.08;
  camera_ = Camera::framing(mesh.positions(), view_.direction, view_.up, 1.0, view_.fov, margin);
  const double half = 0.5 * view_.fov * kPi / 180.0;
  ppu_ = 0.5 * size_ / ((camera_.eye - camera_.target).norm() * std::tan(half));

  // Subdivision: small edges about `spacing` pixels long, within the sample budget.
  const double want = view_.spacing / ppu_;
  n_ = std::clamp(static_cast<int>(std::ceil(mesh.mean_edge_length() / want)), 1, 64);
  auto count = [&](int n) { return subdivision_vertex_count(mesh, n); };
  while (n_ > 1 && count(n_) > view_.max_samples) --n_;
  if (count(n_) > view_.max_samples)
    throw Error(fmt::format("texture option max_samples: {} is fewer than the mesh's {} vertices", view_.max_samples,
                            count(1)));
  // The samples: the vertices of the faces subdivided n_ times (mesh/face_subdivision.h),
  // each with its place on the mesh; the lattice of each face for barycentric reads.
  FaceSubdivision sub = subdivide_faces(mesh, n_);
  const size_t ns = sub.face.size();
  per_face_ = (n_ + 1) * (n_ + 2) / 2;
  grid_ = std::move(sub.grid);
  points_.resize(ns);
  for (size_t q = 0; q < ns; ++q) points_[q] = SurfacePoint{sub.face[q], sub.bary[q]};
  positions_ = sub.mesh.positions();
  triangles_ = sub.mesh.faces();

  // Speed scale as on the plane: the typical (90th-percentile) speed moves
  // pixels_per_frame pixels in one frame of the field.
  {
    std::vector<double> speeds;
    const size_t total = field.data().size();
    const size_t stride = std::max<size_t>(1, total / 1'000'000);
    for (size_t k = 0; k < total; k += stride) speeds.push_back(std::abs(field.data()[k]));
    if (!speeds.empty()) {
      auto mid = speeds.begin() + static_cast<long>(0.9 * static_cast<double>(speeds.size() - 1));
      std::nth_element(speeds.begin(), mid, speeds.end());
      p90_ = *mid;
    }
    const TimeSampling& ts = field.time();
    const double frame_dt = ts.frames > 1 ? std::abs(ts.t1 - ts.t0) / (ts.frames - 1) : 1.0;
    const double ppf = (o_.pixels_per_frame > 0 ? o_.pixels_per_frame : o_.size / 128.0) / ppu_;  // world units
    time_scale_ = p90_ > 0 && frame_dt > 0 ? ppf / (p90_ * frame_dt) : 0.0;
  }
  cell_ = (o_.noise_scale > 0 ? o_.noise_scale : std::max(view_.spacing, o_.size / 512.0)) / ppu_;
  tex_.assign(ns, 0.5f);
  next_.assign(ns, 0.5f);
  seed_hash_ = splitmix(o_.seed);
}

float SurfaceTextureAnimator::texture_at(const SurfacePoint& p) const {
  const int n = n_;
  const double u = std::clamp(p.bary[1], 0.0, 1.0) * n, v = std::clamp(p.bary[2], 0.0, 1.0) * n;
  int i = std::clamp(static_cast<int>(u), 0, n - 1);
  int j = std::clamp(static_cast<int>(v), 0, n - 1 - i);
  const double fu = u - i, fv = v - j;
  const float* t = tex_.data();
  if (fu + fv <= 1 || i + j + 2 > n) {
    const double w0 = 1 - fu - fv;
    return static_cast<float>(w0 * t[sample_of(p.face, i, j)] + fu * t[sample_of(p.face, i + 1, j)] +
                              fv * t[sample_of(p.face, i, j + 1)]);
  }
  return static_cast<float>((fu + fv - 1) * t[sample_of(p.face, i + 1, j + 1)] +
                            (1 - fu) * t[sample_of(p.face, i, j + 1)] + (1 - fv) * t[sample_of(p.face, i + 1, j)]);
}

float SurfaceTextureAnimator::lattice(long ix, long iy, long iz, long step) const {
  const std::uint64_t h = splitmix(splitmix(splitmix(seed_hash_ ^ static_cast<std::uint64_t>(ix)) ^
                                            static_cast<std::uint64_t>(iy)) ^
                                   static_cast<std::uint64_t>(iz));
  const double phase = static_cast<double>(h >> 11) * 0x1.0p-53;
  double u = static_cast<double>(step % o_.noise_period) / o_.noise_period + phase;
  u -= std::floor(u);
  return u < 0.5 ? 1.0f : 0.0f;
}

float SurfaceTextureAnimator::noise(const Vec3& a, const Vec3& b, long step) const {
  // Mean along the step (as on the plane) of the cells the step crosses: nearest cell,
  // sharp-edged, so the injected noise keeps its full contrast at the cell scale.
  const int samples = std::clamp(static_cast<int>((b - a).norm() / cell_) + 1, 1, 4);
  float sum = 0;
  for (int q = 0; q < samples; ++q) {
    const Vec3 x = (a + (b - a) * ((q + 0.5) / samples)) / cell_;
    sum += lattice(static_cast<long>(std::floor(x.x())), static_cast<long>(std::floor(x.y())),
                   static_cast<long>(std::floor(x.z())), step);
  }
  return sum / static_cast<float>(samples);
}

void SurfaceTextureAnimator::advance(double t) {
  const TimeSampling& ts = field_.time();
  const double frame_dt = ts.frames > 1 ? (ts.t1 - ts.t0) / (ts.frames - 1) : 1.0;
  const Mesh& mesh = bundle_.mesh();
  const bool uniform = o_.speed == TextureSpeed::uniform;
  const double floor = 1e-12 * p90_;
  const float a = static_cast<float>(o_.alpha);
  auto step = [&](double dt) {
    const double s = dt * time_scale_;
    const long k = step_++ % (1L << 30);
    tbb::parallel_for(tbb::blocked_range<size_t>(0, points_.size(), 1024), [&](const tbb::blocked_range<size_t>& r) {
      for (size_t q = r.begin(); q < r.end(); ++q) {
        const SurfacePoint& p = points_[q];
        auto displacement = [&](cplx z) {
          const double m = std::sqrt(std::norm(z));  // not std::abs: hypot is slow here
          if (m <= floor) return cplx(0, 0);
          return uniform ? z * (s * p90_ / m) : z * s;
        };
        const cplx z = interpolate_in_face(bundle_, values_, p);
        const cplx d0 = displacement(z);
        SurfacePoint src = p;
        if (d0 != cplx(0, 0)) {
          const SurfaceWalk half = walk_surface(bundle_, p, -0.5 * d0);
          const cplx zm = interpolate_in_face(bundle_, values_, half.end) * std::conj(half.transport);
          src = walk_surface(bundle_, p, -displacement(zm)).end;
        }
        const float old = texture_at(src);
        next_[q] = (1.0f - a) * old + a * noise(surface_position(mesh, src), positions_[q], k);
      }
    });
    tex_.swap(next_);
  };
  if (!started_) {
    values_ = values_at(field_, t);
    const int warm = o_.warmup > 0 ? o_.warmup : static_cast<int>(std::ceil(3.0 / o_.alpha));
    for (int k = 0; k < warm; ++k) step(frame_dt);
    started_ = true;
    t_ = t;
    return;
  }
  values_ = values_at(field_, 0.5 * (t + t_));
  step(t - t_);
  t_ = t;
}

std::vector<float> SurfaceTextureAnimator::shown() const {
  std::vector<float> out(tex_.size());
  if (o_.lic > 0) {
    // Line integral convolution along the surface: o_.lic pixels each way in at most 6
    // walks each way along the unit direction of the current field.
    const int steps = std::min(o_.lic, 6);
    const double h = static_cast<double>(o_.lic) / steps / ppu_;
    const double floor = 1e-12 * p90_;
    tbb::parallel_for(tbb::blocked_range<size_t>(0, points_.size(), 1024), [&](const tbb::blocked_range<size_t>& r) {
      for (size_t q = r.begin(); q < r.end(); ++q) {
        double sum = tex_[q];
        int count = 1;
        for (const double sign : {h, -h}) {
          SurfacePoint p = points_[q];
          for (int k = 0; k < steps; ++k) {
            const cplx z = interpolate_in_face(bundle_, values_, p);
            const double m = std::sqrt(std::norm(z));  // not std::abs: hypot is slow here
            if (m <= floor) break;
            const SurfaceWalk w = walk_surface(bundle_, p, z * (sign / m));
            p = w.end;
            sum += texture_at(p);
            ++count;
            if (w.hit_boundary) break;
          }
        }
        out[q] = static_cast<float>(sum / count);
      }
    });
  } else {
    out = tex_;
  }
  double sum = 0, sum2 = 0;
  for (float v : out) {
    sum += v;
    sum2 += static_cast<double>(v) * v;
  }
  const double nn = static_cast<double>(std::max<size_t>(1, out.size()));
  const double mean = sum / nn;
  const double sd = std::max(1e-3, std::sqrt(std::max(0.0, sum2 / nn - mean * mean)));
  const float gain = static_cast<float>(o_.contrast / (4.4 * sd)), m0 = static_cast<float>(mean);
  for (float& v : out) v = std::clamp(0.5f + (v - m0) * gain, 0.0f, 1.0f);
  return out;
}

std::vector<std::uint32_t> SurfaceTextureAnimator::colors() const {
  const std::vector<float> v = shown();
  std::vector<std::uint32_t> c(v.size());
  for (size_t k = 0; k < v.size(); ++k) c[k] = gray(static_cast<std::uint8_t>(std::lround(v[k] * 255.0f)));
  return c;
}

// --- Overlays ---------------------------------------------------------------------------

std::vector<RenderLine> singularity_path_lines(const Topology& topology, double t, double width) {
  std::vector<RenderLine> lines;
  for (const SingularityPath& path : topology.paths) {
    if (path.points.empty() || path.points.front().t > t) continue;
    RenderLine line;
    line.color = to_rgb(type_color(path.type));
    line.width = width;
    line.casing = true;
    for (size_t k = 0; k < path.points.size(); ++k) {
      const PathSample& s = path.points[k];
      if (s.t > t) {
        const PathSample& a = path.points[k - 1];
        const double w = s.t > a.t ? (t - a.t) / (s.t - a.t) : 1.0;
        line.points.push_back((1 - w) * a.position + w * s.position);
        break;
      }
      line.points.push_back(s.position);
    }
    if (line.points.size() == 1) line.points.push_back(line.points.front());
    lines.push_back(std::move(line));
  }
  return lines;
}

std::vector<RenderMarker> singularity_markers(const TangentBundle& bundle, const Field& field, double t,
                                              double radius) {
  std::vector<RenderMarker> markers;
  for (const Singularity& s : find_singularities(bundle, values_at(field, t)))
    markers.push_back({s.position, to_rgb(type_color(s.type)), radius});
  return markers;
}

std::vector<RenderLine> surface_streamline_lines(const TangentBundle& bundle, const Field& field, double t, int seeds,
                                                 double width, std::uint64_t seed) {
  const Mesh& mesh = bundle.mesh();
  const std::vector<cplx> values = values_at(field, t);
  // Seeds spread by area: faces drawn with probability ∝ area, uniform inside.
  std::vector<double> cumulative(static_cast<size_t>(mesh.num_faces()));
  double total = 0;
  for (int f = 0; f < mesh.num_faces(); ++f) cumulative[static_cast<size_t>(f)] = total += mesh.face_area(f);
  std::mt19937_64 rng(seed);
  std::uniform_real_distribution<double> uni(0.0, 1.0);
  StreamlineOptions so;
  so.max_length = 0.12 * mesh.diameter();
  std::vector<RenderLine> lines;
  for (int k = 0; k < seeds && total > 0; ++k) {
    const double r = uni(rng) * total;
    const int f = static_cast<int>(std::min<size_t>(
        static_cast<size_t>(std::lower_bound(cumulative.begin(), cumulative.end(), r) - cumulative.begin()),
        cumulative.size() - 1));
    double u = uni(rng), v = uni(rng);
    if (u + v > 1) u = 1 - u, v = 1 - v;
    const Streamline s = trace_streamline(bundle, values, SurfacePoint{f, Vec3(1 - u - v, u, v)}, so);
    if (s.points.size() < 2) continue;
    lines.push_back({s.points, 0x0D0D0D, width, false});
  }
  return lines;
}

// --- The animation ----------------------------------------------------------------------

TextureAnimationReport write_surface_texture_animation(const TangentBundle& bundle, const Field& field,
                                                       const TextureAnimationOptions& options, int first, int last,
                                                       int total) {
  using clock = std::chrono::steady_clock;
  const auto start = clock::now();
  SurfaceTextureAnimator animator(bundle, field, options.texture, options.surface);
  MeshRenderer renderer;
  renderer.set_mesh(animator.sample_positions(), animator.sample_triangles());
  RenderOptions ro;
  ro.width = animator.width();
  ro.height = animator.height();
  ro.background = options.texture.background;
  ro.lighting = options.surface.lighting;
  ro.ambient = 0.5;
  Topology topology;
  if (options.overlay_paths) topology = analyze_topology(bundle, field);
  FrameOutput out(options.frames_dir, options.video, ro.width, ro.height, options.fps);

  const TimeSampling& ts = field.time();
  auto time_of = [&](int k) { return total > 1 ? ts.t0 + (ts.t1 - ts.t0) * k / (total - 1) : ts.t0; };
  TextureAnimationReport report;
  report.width = ro.width;
  report.height = ro.height;
  const double line_width = std::max(1.5, animator.width() / 300.0);
  const int count = last - first + 1;
  int done = 0;
  out.add_in_order(
      first, last,
      [&](int k) {
        const double t = time_of(k);
        const auto t0 = clock::now();
        animator.advance(t);
        renderer.set_colors(animator.colors());
        std::vector<RenderLine> lines;
        std::vector<RenderMarker> markers;
        if (options.overlay_streamlines) {
          auto s = surface_streamline_lines(bundle, field, t, options.streamline_seeds,
                                            std::max(1.0, animator.width() / 600.0));
          lines.insert(lines.end(), s.begin(), s.end());
        }
        if (options.overlay_paths) {
          auto p = singularity_path_lines(topology, t, line_width);
          lines.insert(lines.end(), p.begin(), p.end());
        }
        if (options.overlay_singularities)
          markers = singularity_markers(bundle, field, t, std::max(3.5, animator.width() / 110.0));
        Image img = renderer.render(animator.camera(), ro, lines, markers);
        (k == first ? report.warmup_seconds : report.texture_seconds) +=
            std::chrono::duration<double>(clock::now() - t0).count();
        return img;
      },
      [&](int n) {
        done = n;
        if (options.progress) options.progress(n, count);
      });
  report.files = out.finish();
  report.frames = done;
  report.seconds = std::chrono::duration<double>(clock::now() - start).count();
  return report;
}

}  // namespace tvf
