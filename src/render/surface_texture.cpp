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
#include <limits>
#include <memory>
#include <optional>
#include <random>
#include <tuple>
#include <utility>

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

void check_surface_options(TextureOptions& o, const SurfaceView& view) {
  check_texture_options(o, 8192);
  check_option(std::isfinite(view.spacing) && view.spacing >= 0.25 && view.spacing <= 100, "spacing",
               fmt::format("{} pixels is outside [0.25, 100]", view.spacing));
  check_option(view.max_samples >= 3 && view.max_samples <= 100'000'000, "max_samples",
               fmt::format("{} is outside [3, 100000000]", view.max_samples));
  check_option(view.direction.allFinite() && view.direction.norm() > 0, "view", "the view direction must be a non-zero vector");
  check_option(view.up.allFinite() && view.up.norm() > 0, "up", "the up direction must be a non-zero vector");
  check_option(std::isfinite(view.fov) && view.fov >= 1 && view.fov <= 120, "fov",
               fmt::format("{}° is outside [1, 120]", view.fov));
}

// The 90th-percentile speed of the field and the time scale that moves it `ppf` world
// units per frame of the field (as on the plane).
std::pair<double, double> speed_scale(const Field& field, double ppf) {
  std::vector<double> speeds;
  const size_t total = field.data().size();
  const size_t stride = std::max<size_t>(1, total / 1'000'000);
  for (size_t k = 0; k < total; k += stride) speeds.push_back(std::abs(field.data()[k]));
  double p90 = 0;
  if (!speeds.empty()) {
    auto mid = speeds.begin() + static_cast<long>(0.9 * static_cast<double>(speeds.size() - 1));
    std::nth_element(speeds.begin(), mid, speeds.end());
    p90 = *mid;
  }
  const TimeSampling& ts = field.time();
  const double frame_dt = ts.frames > 1 ? std::abs(ts.t1 - ts.t0) / (ts.frames - 1) : 1.0;
  return {p90, p90 > 0 && frame_dt > 0 ? ppf / (p90 * frame_dt) : 0.0};
}

// World-space noise cells (cell world units) that switch on and off with random phases
// over `period` steps, averaged along the segment a → b.
float cell_noise(std::uint64_t seed_hash, int period, double cell, const Vec3& a, const Vec3& b, long step) {
  auto lattice = [&](long ix, long iy, long iz) {
    const std::uint64_t h = splitmix(splitmix(splitmix(seed_hash ^ static_cast<std::uint64_t>(ix)) ^
                                              static_cast<std::uint64_t>(iy)) ^
                                     static_cast<std::uint64_t>(iz));
    const double phase = static_cast<double>(h >> 11) * 0x1.0p-53;
    double u = static_cast<double>(step % period) / period + phase;
    u -= std::floor(u);
    return u < 0.5 ? 1.0f : 0.0f;
  };
  const int samples = std::clamp(static_cast<int>((b - a).norm() / cell) + 1, 1, 4);
  float sum = 0;
  for (int q = 0; q < samples; ++q) {
    const Vec3 x = (a + (b - a) * ((q + 0.5) / samples)) / cell;
    sum += lattice(static_cast<long>(std::floor(x.x())), static_cast<long>(std::floor(x.y())),
                   static_cast<long>(std::floor(x.z())));
  }
  return sum / static_cast<float>(samples);
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
  check_surface_options(o_, view_);
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
  std::tie(p90_, time_scale_) =
      speed_scale(field, (o_.pixels_per_frame > 0 ? o_.pixels_per_frame : o_.size / 128.0) / ppu_);
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

float SurfaceTextureAnimator::noise(const Vec3& a, const Vec3& b, long step) const {
  // Mean along the step (as on the plane) of the cells the step crosses: nearest cell,
  // sharp-edged, so the injected noise keeps its full contrast at the cell scale.
  return cell_noise(seed_hash_, o_.noise_period, cell_, a, b, step);
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

// --- Image-space advection on the surface ------------------------------------------------

SurfaceImageAnimator::SurfaceImageAnimator(const TangentBundle& bundle, const Field& field,
                                           const TextureOptions& options, const SurfaceView& view)
    : bundle_(bundle), field_(field), o_(options), view_(view) {
  const Mesh& mesh = bundle.mesh();
  if (bundle.is_flat())
    throw Error("surface texture animation: the domain is planar (TextureAnimator draws planar domains)");
  TVF_CHECK(field.num_vertices() == mesh.num_vertices(), "field of {} vertices on a mesh of {}",
            field.num_vertices(), mesh.num_vertices());
  check_surface_options(o_, view_);
  for (const cplx& z : field.data())
    if (!std::isfinite(z.real()) || !std::isfinite(z.imag()))
      throw_input_error(mesh.source(), "", "the field has a value that is not a finite number");

  size_ = o_.size;
  constexpr double margin = 1.08;
  camera_ = Camera::framing(mesh.positions(), view_.direction, view_.up, 1.0, view_.fov, margin);
  const double tan_half = std::tan(0.5 * view_.fov * kPi / 180.0);
  ppu_ = 0.5 * size_ / ((camera_.eye - camera_.target).norm() * tan_half);
  // Texels: one every `spacing` pixels, within the sample budget.
  g_ = std::max(2, static_cast<int>(std::lround(size_ / view_.spacing)));
  while (static_cast<long>(g_) * g_ > view_.max_samples && g_ > 2) --g_;
  focal_ = 0.5 * g_ / tan_half;  // texels per unit of lateral offset at unit depth
  const Eigen::Matrix4d vm = camera_.view();
  rot_ = vm.block<3, 3>(0, 0);
  const Vec3 shift = vm.block<3, 1>(0, 3);

  // Rasterize once: the nearest surface point seen through each texel's centre.
  const size_t nt = static_cast<size_t>(g_) * static_cast<size_t>(g_);
  face_.assign(nt, -1);
  bary_.assign(nt, Eigen::Vector3f::Zero());
  std::vector<float> depth(nt, std::numeric_limits<float>::infinity());
  {
    const int nv = mesh.num_vertices();
    std::vector<Vec3> screen(static_cast<size_t>(nv));  // texel x, texel y (down), depth
    for (int v = 0; v < nv; ++v) {
      const Vec3 e = rot_ * mesh.position(v) + shift;
      const double d = -e.z();
      screen[static_cast<size_t>(v)] = Vec3(0.5 * g_ + focal_ * e.x() / d, 0.5 * g_ - focal_ * e.y() / d, d);
    }
    for (int f = 0; f < mesh.num_faces(); ++f) {
      const Face& fc = mesh.face(f);
      const Vec3& a = screen[static_cast<size_t>(fc[0])];
      const Vec3& b = screen[static_cast<size_t>(fc[1])];
      const Vec3& c = screen[static_cast<size_t>(fc[2])];
      if (a.z() <= 0 || b.z() <= 0 || c.z() <= 0) continue;  // behind the eye (framing avoids it)
      const double area = (b.x() - a.x()) * (c.y() - a.y()) - (b.y() - a.y()) * (c.x() - a.x());
      if (std::abs(area) < 1e-12) continue;
      const int x0 = std::max(0, static_cast<int>(std::floor(std::min({a.x(), b.x(), c.x()}) - 0.5)));
      const int x1 = std::min(g_ - 1, static_cast<int>(std::ceil(std::max({a.x(), b.x(), c.x()}) - 0.5)));
      const int y0 = std::max(0, static_cast<int>(std::floor(std::min({a.y(), b.y(), c.y()}) - 0.5)));
      const int y1 = std::min(g_ - 1, static_cast<int>(std::ceil(std::max({a.y(), b.y(), c.y()}) - 0.5)));
      for (int y = y0; y <= y1; ++y)
        for (int x = x0; x <= x1; ++x) {
          const double px = x + 0.5, py = y + 0.5;
          const double l0 = ((b.x() - px) * (c.y() - py) - (b.y() - py) * (c.x() - px)) / area;
          const double l1 = ((c.x() - px) * (a.y() - py) - (c.y() - py) * (a.x() - px)) / area;
          const double l2 = 1 - l0 - l1;
          constexpr double eps = -1e-7;  // shared edges are covered by one face or the other
          if (l0 < eps || l1 < eps || l2 < eps) continue;
          // Perspective-correct: barycentric coordinates ∝ λ_i / depth_i.
          const double m0 = l0 / a.z(), m1 = l1 / b.z(), m2 = l2 / c.z(), sum = m0 + m1 + m2;
          const double z = 1 / sum;
          const size_t k = static_cast<size_t>(y) * static_cast<size_t>(g_) + static_cast<size_t>(x);
          if (z >= depth[k]) continue;
          depth[k] = static_cast<float>(z);
          face_[k] = f;
          bary_[k] = Eigen::Vector3f(static_cast<float>(m0 * z), static_cast<float>(m1 * z), static_cast<float>(m2 * z));
        }
    }
  }
  pos_.assign(nt, Eigen::Vector3f::Zero());
  eye_.assign(nt, Eigen::Vector3f::Zero());
  for (size_t k = 0; k < nt; ++k) {
    if (face_[k] < 0) continue;
    const Vec3 x = surface_position(mesh, SurfacePoint{face_[k], bary_[k].cast<double>()});
    pos_[k] = x.cast<float>();
    eye_[k] = (rot_ * x + shift).cast<float>();
  }

  std::tie(p90_, time_scale_) =
      speed_scale(field, (o_.pixels_per_frame > 0 ? o_.pixels_per_frame : o_.size / 128.0) / ppu_);
  cell_ = (o_.noise_scale > 0 ? o_.noise_scale : std::max(view_.spacing, o_.size / 512.0)) / ppu_;
  tex_.assign(nt, 0.5f);
  next_.assign(nt, 0.5f);
  vel_.assign(2 * nt, 0.0f);
  dir_.assign(2 * nt, 0.0f);
  step_len_.assign(nt, 0.0f);
  seed_hash_ = splitmix(o_.seed);
  // The noise cells: each texel's cell of world space (cell_ units) and its random phase,
  // hashed once; and how many cells a texel of the picture spans there.
  phase_.assign(nt, 0.0f);
  cell_texels_.assign(nt, 0.0f);
  for (size_t k = 0; k < nt; ++k) {
    if (face_[k] < 0) continue;
    const Eigen::Vector3f c = pos_[k] / static_cast<float>(cell_);
    const std::uint64_t h =
        splitmix(splitmix(splitmix(seed_hash_ ^ static_cast<std::uint64_t>(static_cast<long>(std::floor(c.x())))) ^
                          static_cast<std::uint64_t>(static_cast<long>(std::floor(c.y())))) ^
                 static_cast<std::uint64_t>(static_cast<long>(std::floor(c.z()))));
    phase_[k] = static_cast<float>(static_cast<double>(h >> 11) * 0x1.0p-53);
    cell_texels_[k] = static_cast<float>(-eye_[k].z() / focal_ / cell_);
  }
}

template <class Get>
bool SurfaceImageAnimator::bilinear(double x, double y, Get&& get, float& out) const {
  // Texel centres at (i + ½, j + ½); only texels that see the surface count.
  const double fx = x - 0.5, fy = y - 0.5;
  const int i = static_cast<int>(std::floor(fx)), j = static_cast<int>(std::floor(fy));
  const double u = fx - i, v = fy - j;
  double sum = 0, weight = 0;
  for (int dj = 0; dj < 2; ++dj)
    for (int di = 0; di < 2; ++di) {
      const int a = i + di, b = j + dj;
      if (a < 0 || b < 0 || a >= g_ || b >= g_) continue;
      const size_t k = static_cast<size_t>(b) * static_cast<size_t>(g_) + static_cast<size_t>(a);
      if (face_[k] < 0) continue;
      const double w = (di ? u : 1 - u) * (dj ? v : 1 - v);
      sum += w * get(k);
      weight += w;
    }
  if (weight <= 1e-6) return false;
  out = static_cast<float>(sum / weight);
  return true;
}

void SurfaceImageAnimator::velocities(double t, double dt) {
  // The field at t in world coordinates per vertex, then per texel in the plane of the
  // face it sees, projected on the texel grid: the displacement of one step (texels) and
  // the step of the line integral convolution (lic/steps pixels of world length).
  const Mesh& mesh = bundle_.mesh();
  const std::vector<cplx> values = values_at(field_, t);
  world_.resize(values.size());
  for (size_t v = 0; v < values.size(); ++v)
    world_[v] = bundle_.vertex_to_world(static_cast<int>(v), values[v]).cast<float>();
  const bool uniform = o_.speed == TextureSpeed::uniform;
  const double s = dt * time_scale_, floor = 1e-12 * p90_;
  const int lic_steps = std::max(1, std::min(o_.lic, 6));
  const double h = o_.lic > 0 ? static_cast<double>(o_.lic) / lic_steps / ppu_ : 0.0;
  const size_t nt = face_.size();
  tbb::parallel_for(tbb::blocked_range<size_t>(0, nt, 4096), [&](const tbb::blocked_range<size_t>& r) {
    for (size_t k = r.begin(); k < r.end(); ++k) {
      vel_[2 * k] = vel_[2 * k + 1] = dir_[2 * k] = dir_[2 * k + 1] = step_len_[k] = 0.0f;
      const int f = face_[k];
      if (f < 0) continue;
      const Face& fc = mesh.face(f);
      const Eigen::Vector3f& b = bary_[k];
      Vec3 w = (b[0] * world_[static_cast<size_t>(fc[0])] + b[1] * world_[static_cast<size_t>(fc[1])] +
                b[2] * world_[static_cast<size_t>(fc[2])]).cast<double>();
      const Vec3& n = bundle_.face_normal(f);
      w -= w.dot(n) * n;
      const double m = w.norm();
      if (m <= floor) continue;
      // Screen image of a world displacement d at this texel (the projection's Jacobian).
      const Vec3 e = eye_[k].cast<double>();
      const double depth = -e.z();
      auto to_screen = [&](const Vec3& d) {
        const Vec3 de = rot_ * d;
        return Vec2(focal_ / depth * (de.x() + e.x() / depth * de.z()),
                    -focal_ / depth * (de.y() + e.y() / depth * de.z()));
      };
      const Vec3 d = uniform ? Vec3(w * (s * p90_ / m)) : Vec3(w * s);
      const Vec2 sd = to_screen(d), sh = to_screen(w * (h / m));
      vel_[2 * k] = static_cast<float>(sd.x());
      vel_[2 * k + 1] = static_cast<float>(sd.y());
      dir_[2 * k] = static_cast<float>(sh.x());
      dir_[2 * k + 1] = static_cast<float>(sh.y());
      step_len_[k] = static_cast<float>(d.norm());
    }
  });
}

bool SurfaceImageAnimator::bilinear2(double x, double y, const std::vector<float>& v, Vec2& out) const {
  const double fx = x - 0.5, fy = y - 0.5;
  const int i = static_cast<int>(std::floor(fx)), j = static_cast<int>(std::floor(fy));
  const double u = fx - i, w = fy - j;
  double sx = 0, sy = 0, weight = 0;
  for (int dj = 0; dj < 2; ++dj)
    for (int di = 0; di < 2; ++di) {
      const int a = i + di, b = j + dj;
      if (a < 0 || b < 0 || a >= g_ || b >= g_) continue;
      const size_t k = static_cast<size_t>(b) * static_cast<size_t>(g_) + static_cast<size_t>(a);
      if (face_[k] < 0) continue;
      const double c = (di ? u : 1 - u) * (dj ? w : 1 - w);
      sx += c * v[2 * k];
      sy += c * v[2 * k + 1];
      weight += c;
    }
  if (weight <= 1e-6) return false;
  out = Vec2(sx / weight, sy / weight);
  return true;
}

void SurfaceImageAnimator::advance(double t) {
  const TimeSampling& ts = field_.time();
  const double frame_dt = ts.frames > 1 ? (ts.t1 - ts.t0) / (ts.frames - 1) : 1.0;
  const float a = static_cast<float>(o_.alpha);
  const size_t g = static_cast<size_t>(g_);
  // World size of one texel at depth 1 (lateral), for the occlusion test.
  const double texel_at_unit_depth = 1.0 / focal_;
  auto step = [&]() {
    const long k = step_++ % (1L << 30);
    const float clock = static_cast<float>(k % o_.noise_period) / static_cast<float>(o_.noise_period);
    tbb::parallel_for(tbb::blocked_range<size_t>(0, g, 8), [&](const tbb::blocked_range<size_t>& rows) {
      for (size_t y = rows.begin(); y < rows.end(); ++y)
        for (size_t x = 0; x < g; ++x) {
          const size_t q = y * g + x;
          if (face_[q] < 0) continue;
          const double cx = static_cast<double>(x) + 0.5, cy = static_cast<double>(y) + 0.5;
          const double vx = vel_[2 * q], vy = vel_[2 * q + 1];
          float old = tex_[q];
          const float len = step_len_[q];
          double sx = cx, sy = cy;  // where the texture comes from (the texel itself when off the sheet)
          if (len > 0) {
            // Midpoint rule on the picture plane.
            Vec2 mid;
            const double hx = cx - 0.5 * vx, hy = cy - 0.5 * vy;
            double tx = cx - vx, ty = cy - vy;
            if (bilinear2(hx, hy, vel_, mid)) tx = cx - mid.x(), ty = cy - mid.y();
            const int ix = static_cast<int>(std::floor(tx)), iy = static_cast<int>(std::floor(ty));
            float value = 0;
            if (ix >= 0 && iy >= 0 && ix < g_ && iy < g_) {
              const size_t s = static_cast<size_t>(iy) * g + static_cast<size_t>(ix);
              // The source must see the same sheet of surface: about one step away in the world.
              const double slack = 2.0 * texel_at_unit_depth * std::max(-static_cast<double>(eye_[q].z()), 0.0);
              if (face_[s] >= 0 && (pos_[s] - pos_[q]).norm() <= 1.5 * len + slack &&
                  bilinear(tx, ty, [&](size_t i) { return tex_[i]; }, value)) {
                old = value;
                sx = tx, sy = ty;
              }
            }
          }
          // The noise: the mean of the world cells (their phases cached per texel) met along
          // the step, as SurfaceTextureAnimator's, sampled at the texels on the way.
          const int samples = std::clamp(static_cast<int>(std::hypot(cx - sx, cy - sy) * cell_texels_[q]) + 1, 1, 4);
          float sum = 0;
          for (int m = 0; m < samples; ++m) {
            const double w = (m + 0.5) / samples;
            const int ix = static_cast<int>(sx + w * (cx - sx)), iy = static_cast<int>(sy + w * (cy - sy));
            size_t at = q;
            if (ix >= 0 && iy >= 0 && ix < g_ && iy < g_) {
              const size_t c = static_cast<size_t>(iy) * g + static_cast<size_t>(ix);
              if (face_[c] >= 0) at = c;
            }
            float u = phase_[at] + clock;
            u -= std::floor(u);
            sum += u < 0.5f ? 1.0f : 0.0f;
          }
          next_[q] = (1.0f - a) * old + a * (sum / static_cast<float>(samples));
        }
    });
    tex_.swap(next_);
  };
  if (!started_) {
    velocities(t, frame_dt);
    const int warm = o_.warmup > 0 ? o_.warmup : static_cast<int>(std::ceil(3.0 / o_.alpha));
    for (int k = 0; k < warm; ++k) step();
    started_ = true;
    t_ = t;
    return;
  }
  velocities(0.5 * (t + t_), t - t_);
  step();
  t_ = t;
}

std::vector<float> SurfaceImageAnimator::shown() const {
  const size_t g = static_cast<size_t>(g_), nt = face_.size();
  std::vector<float> out(nt, 0.0f);
  const double texel_at_unit_depth = 1.0 / focal_;
  const int steps = std::max(1, std::min(o_.lic, 6));
  tbb::parallel_for(tbb::blocked_range<size_t>(0, g, 8), [&](const tbb::blocked_range<size_t>& rows) {
    for (size_t y = rows.begin(); y < rows.end(); ++y)
      for (size_t x = 0; x < g; ++x) {
        const size_t q = y * g + x;
        if (face_[q] < 0) continue;
        if (o_.lic <= 0) {
          out[q] = tex_[q];
          continue;
        }
        double sum = tex_[q];
        int count = 1;
        for (const double sign : {1.0, -1.0}) {
          double px = static_cast<double>(x) + 0.5, py = static_cast<double>(y) + 0.5;
          size_t at = q;
          for (int k = 0; k < steps; ++k) {
            const double dx = dir_[2 * at], dy = dir_[2 * at + 1];
            if (dx == 0 && dy == 0) break;
            px += sign * dx;
            py += sign * dy;
            const int ix = static_cast<int>(std::floor(px)), iy = static_cast<int>(std::floor(py));
            if (ix < 0 || iy < 0 || ix >= g_ || iy >= g_) break;
            const size_t next = static_cast<size_t>(iy) * g + static_cast<size_t>(ix);
            if (face_[next] < 0) break;
            // Stay on the sheet the walk is on (not across an occluding contour).
            const double slack = 2.0 * texel_at_unit_depth * std::max(-static_cast<double>(eye_[at].z()), 0.0);
            const double hw = static_cast<double>(o_.lic) / steps / ppu_;
            if ((pos_[next] - pos_[at]).norm() > 1.5 * hw + slack) break;
            float v = 0;
            if (!bilinear(px, py, [&](size_t i) { return tex_[i]; }, v)) break;
            sum += v;
            ++count;
            at = next;
          }
        }
        out[q] = static_cast<float>(sum / count);
      }
  });
  double sum = 0, sum2 = 0, n = 0;
  for (size_t q = 0; q < nt; ++q) {
    if (face_[q] < 0) continue;
    sum += out[q];
    sum2 += static_cast<double>(out[q]) * out[q];
    n += 1;
  }
  n = std::max(1.0, n);
  const double mean = sum / n;
  const double sd = std::max(1e-3, std::sqrt(std::max(0.0, sum2 / n - mean * mean)));
  const float gain = static_cast<float>(o_.contrast / (4.4 * sd)), m0 = static_cast<float>(mean);
  for (size_t q = 0; q < nt; ++q)
    if (face_[q] >= 0) out[q] = std::clamp(0.5f + (out[q] - m0) * gain, 0.0f, 1.0f);
  // Texels that see no surface: the mean of their seeing neighbours (for the renderer's
  // anti-aliased silhouette), 0.5 when none.
  const std::vector<float> seen = out;
  for (size_t y = 0; y < g; ++y)
    for (size_t x = 0; x < g; ++x) {
      const size_t q = y * g + x;
      if (face_[q] >= 0) continue;
      double s = 0;
      int c = 0;
      for (int dy = -1; dy <= 1; ++dy)
        for (int dx = -1; dx <= 1; ++dx) {
          const long xx = static_cast<long>(x) + dx, yy = static_cast<long>(y) + dy;
          if (xx < 0 || yy < 0 || xx >= g_ || yy >= g_) continue;
          const size_t r = static_cast<size_t>(yy) * g + static_cast<size_t>(xx);
          if (face_[r] >= 0) s += seen[r], ++c;
        }
      out[q] = c > 0 ? static_cast<float>(s / c) : 0.5f;
    }
  return out;
}

Image SurfaceImageAnimator::composite(const Image& lit, const Image& dark) const {
  if (lit.width != size_ || lit.height != size_ || dark.width != size_ || dark.height != size_)
    throw Error(fmt::format("surface texture: pictures of {}×{} and {}×{} pixels for a {}-pixel animation", lit.width,
                            lit.height, dark.width, dark.height, size_));
  const std::vector<float> v = shown();
  Image img(size_, size_);
  const double scale = static_cast<double>(g_) / size_;
  const size_t g = static_cast<size_t>(g_);
  tbb::parallel_for(tbb::blocked_range<int>(0, size_, 16), [&](const tbb::blocked_range<int>& rows) {
    for (int y = rows.begin(); y < rows.end(); ++y)
      for (int x = 0; x < size_; ++x) {
        float gv;
        if (g_ == size_) {
          gv = v[static_cast<size_t>(y) * g + static_cast<size_t>(x)];
        } else {
          // Bilinear over all texels (the unseen ones hold their neighbours' mean).
          const double fx = std::clamp((x + 0.5) * scale - 0.5, 0.0, g_ - 1.0);
          const double fy = std::clamp((y + 0.5) * scale - 0.5, 0.0, g_ - 1.0);
          const int i = std::min(static_cast<int>(fx), g_ - 2), j = std::min(static_cast<int>(fy), g_ - 2);
          const double u = fx - i, w = fy - j;
          auto at = [&](int a, int b) { return v[static_cast<size_t>(b) * g + static_cast<size_t>(a)]; };
          gv = static_cast<float>((1 - u) * (1 - w) * at(i, j) + u * (1 - w) * at(i + 1, j) + (1 - u) * w * at(i, j + 1) +
                                  u * w * at(i + 1, j + 1));
        }
        const std::uint32_t l = lit.at(x, y), d = dark.at(x, y);
        auto ch = [&](int shift) {
          const float lo = static_cast<float>((d >> shift) & 0xFFu), hi = static_cast<float>((l >> shift) & 0xFFu);
          return static_cast<std::uint8_t>(std::clamp(std::lround(lo + gv * (hi - lo)), 0L, 255L));
        };
        img.at(x, y) = rgb(ch(16), ch(8), ch(0));
      }
  });
  return img;
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
  // The texture in image space (SurfaceImageAnimator); the renderer draws the mesh once in
  // white and once in black (shading and anti-aliased silhouettes, composited with the
  // texture), and per frame only when overlays are asked for.
  const std::optional<Field> dye_field = texture_dye_field(field, options);
  std::optional<DyeInjector> dye =
      texture_dye(bundle, dye_field ? *dye_field : field, options, total);  // refuses bad seeds first
  SurfaceImageAnimator animator(bundle, field, options.texture, options.surface);
  MeshRenderer renderer;
  renderer.set_mesh(bundle.mesh());
  RenderOptions ro;
  ro.width = animator.width();
  ro.height = animator.height();
  ro.background = options.texture.background;
  ro.lighting = options.surface.lighting;
  ro.ambient = 0.5;
  const size_t nv = static_cast<size_t>(bundle.mesh().num_vertices());
  renderer.set_colors(std::vector<std::uint32_t>(nv, 0x000000u));
  const Image dark = renderer.render(animator.camera(), ro);
  renderer.set_colors(std::vector<std::uint32_t>(nv, 0xFFFFFFu));
  const Image lit = renderer.render(animator.camera(), ro);
  const bool overlays =
      options.overlay_streamlines || options.overlay_paths || options.overlay_singularities || dye.has_value();
  Topology topology;
  if (options.overlay_paths) topology = analyze_topology(bundle, field);
  FrameOutput out(options.frames_dir, options.video, ro.width, ro.height, options.fps, options.on_picture);

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
        check_render_cancelled(options);
        const double t = time_of(k);
        const auto t0 = clock::now();
        animator.advance(t);
        Image img = animator.composite(lit, dark);
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
        if (dye) {
          dye->advance(t);
          dye_overlay(*dye, texture_dye_style(animator.width(), animator.height(), animator.pixels_per_unit()), lines, markers);
        }
        if (overlays && (!lines.empty() || !markers.empty())) {
          // The overlays drawn over the white mesh: wherever that picture differs from the
          // plain white one, it is an overlay's pixel.
          const Image over = renderer.render(animator.camera(), ro, lines, markers);
          for (size_t q = 0; q < img.pixels.size(); ++q)
            if (over.pixels[q] != lit.pixels[q]) img.pixels[q] = over.pixels[q];
        }
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
  if (dye) report.timelines = dye->timeline_records();
  report.seconds = std::chrono::duration<double>(clock::now() - start).count();
  return report;
}

}  // namespace tvf
