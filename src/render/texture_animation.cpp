#include "tvf/render/texture_animation.h"

#include "tvf/analysis/singularities.h"
#include "tvf/core/atomic_output.h"
#include "tvf/core/error.h"
#include "tvf/integrate/evenly_spaced.h"
#include "tvf/integrate/periodic_orbits.h"
#include "tvf/integrate/streamline.h"
#include "tvf/render/lcs_pictures.h"
#include "tvf/render/frame_output.h"
#include "tvf/render/plots.h"
#include "tvf/render/surface_texture.h"
#include "tvf/render/video.h"

#include <cairo.h>
#include <tbb/blocked_range.h>
#include <tbb/parallel_for.h>
#include <tbb/parallel_reduce.h>

#include <algorithm>
#include <chrono>
#include <cmath>
#include <filesystem>
#include <memory>
#include <optional>
#include <random>

namespace tvf {

namespace fs = std::filesystem;

namespace {

void check_option(bool ok, const std::string& name, const std::string& what) {
  if (!ok) throw Error(fmt::format("texture option {}: {}", name, what));
}

}  // namespace

void check_texture_options(TextureOptions& o, int max_size) {
  check_option(o.size >= 16 && o.size <= max_size, "size",
               fmt::format("{} pixels is outside [16, {}]", o.size, max_size));
  check_option(o.alpha > 0 && o.alpha <= 1, "alpha", fmt::format("{} is outside (0, 1]", o.alpha));
  check_option(std::isfinite(o.noise_scale) && o.noise_scale >= 0 && o.noise_scale <= o.size / 4.0, "noise_scale",
               fmt::format("{} pixels is outside [0, size/4]", o.noise_scale));
  check_option(o.noise_period >= 2 && o.noise_period <= 100000, "noise_period",
               fmt::format("{} frames is outside [2, 100000]", o.noise_period));
  check_option(std::isfinite(o.pixels_per_frame) && o.pixels_per_frame >= 0 && o.pixels_per_frame <= o.size,
               "pixels_per_frame", fmt::format("{} is outside [0, size]", o.pixels_per_frame));
  check_option(o.lic >= -1 && o.lic <= 1000, "lic", fmt::format("{} pixels is outside [0, 1000] (or -1: automatic)", o.lic));
  if (o.lic < 0) o.lic = std::max(1, static_cast<int>(std::lround(o.size / 64.0)));
  check_option(o.warmup >= 0 && o.warmup <= 100000, "warmup", fmt::format("{} is outside [0, 100000]", o.warmup));
  check_option(std::isfinite(o.contrast) && o.contrast > 0 && o.contrast <= 100, "contrast",
               fmt::format("{} is outside (0, 100]", o.contrast));
}

namespace {

// The cell and weights of a bilinear sample of a w × h row-major image at (x, y) in
// pixel-centre coordinates (pixel (i, j) is at (i, j)); clamped to the edge.
struct BilinearCell {
  size_t i00, i01, i10, i11;  // the corners' indices (row y0 or y1, column x0 or x1)
  float fx, fy;
};
inline BilinearCell bilinear_cell(int w, int h, float x, float y) {
  x = std::clamp(x, 0.0f, static_cast<float>(w - 1));
  y = std::clamp(y, 0.0f, static_cast<float>(h - 1));
  const int x0 = std::min(static_cast<int>(x), w - 2 < 0 ? 0 : w - 2);
  const int y0 = std::min(static_cast<int>(y), h - 2 < 0 ? 0 : h - 2);
  const int x1 = std::min(x0 + 1, w - 1), y1 = std::min(y0 + 1, h - 1);
  const size_t r0 = static_cast<size_t>(y0) * static_cast<size_t>(w);
  const size_t r1 = static_cast<size_t>(y1) * static_cast<size_t>(w);
  return {r0 + static_cast<size_t>(x0), r0 + static_cast<size_t>(x1), r1 + static_cast<size_t>(x0),
          r1 + static_cast<size_t>(x1), x - static_cast<float>(x0), y - static_cast<float>(y0)};
}
inline float bilinear_at(const float* img, const BilinearCell& c) {
  const float a = img[c.i00] + c.fx * (img[c.i01] - img[c.i00]);
  const float b = img[c.i10] + c.fx * (img[c.i11] - img[c.i10]);
  return a + c.fy * (b - a);
}

// Bilinear sample of one image.
inline float bilinear(const float* img, int w, int h, float x, float y) {
  return bilinear_at(img, bilinear_cell(w, h, x, y));
}

// The same bilinear sample of two images of the same size (the two velocity components):
// the weights and addresses computed once.
inline void bilinear2(const float* a, const float* b, int w, int h, float x, float y, float& va, float& vb) {
  const BilinearCell c = bilinear_cell(w, h, x, y);
  va = bilinear_at(a, c);
  vb = bilinear_at(b, c);
}

// The LIC's walks: at most 6 Euler steps each way, of lic / steps pixels.
inline int lic_steps(int lic) { return std::min(lic, 6); }
inline float lic_step(int lic) {
  return lic > 0 ? static_cast<float>(lic) / static_cast<float>(lic_steps(lic)) : 1.0f;
}

}  // namespace

TextureAnimator::TextureAnimator(const TangentBundle& bundle, const Field& field, const TextureOptions& options)
    : bundle_(bundle), field_(field), o_(options) {
  const Mesh& mesh = bundle.mesh();
  if (!bundle.is_flat())
    throw_input_error(mesh.source(), "",
                      "TextureAnimator draws planar domains; surfaces have SurfaceTextureAnimator "
                      "(render/surface_texture.h)");
  TVF_CHECK(field.num_vertices() == mesh.num_vertices(), "field of {} vertices on a mesh of {}",
            field.num_vertices(), mesh.num_vertices());
  check_texture_options(o_, 16384);
  for (const cplx& z : field.data())
    if (!std::isfinite(z.real()) || !std::isfinite(z.imag()))
      throw_input_error(mesh.source(), "", "the field has a value that is not a finite number");

  lo_ = mesh.bbox_min().head<2>();
  hi_ = mesh.bbox_max().head<2>();
  const Vec2 ext = hi_ - lo_;
  ppu_ = o_.size / std::max(ext.x(), ext.y());
  width_ = std::max(1, static_cast<int>(std::lround(ext.x() * ppu_)));
  height_ = std::max(1, static_cast<int>(std::lround(ext.y() * ppu_)));
  const size_t n = static_cast<size_t>(width_) * static_cast<size_t>(height_);

  // Which face holds each pixel centre, and where: scan each face's pixel box.
  face_.assign(n, -1);
  bary_.assign(3 * n, 0.0f);
  for (int f = 0; f < mesh.num_faces(); ++f) {
    const Face& t = mesh.face(f);
    Vec2 p[3];
    for (size_t c = 0; c < 3; ++c) p[c] = to_pixel(mesh.position(t[c]).head<2>());
    const double x0 = std::min({p[0].x(), p[1].x(), p[2].x()}), x1 = std::max({p[0].x(), p[1].x(), p[2].x()});
    const double y0 = std::min({p[0].y(), p[1].y(), p[2].y()}), y1 = std::max({p[0].y(), p[1].y(), p[2].y()});
    const int i0 = std::max(0, static_cast<int>(std::floor(x0 - 0.5))), i1 = std::min(width_ - 1, static_cast<int>(std::ceil(x1 - 0.5)));
    const int j0 = std::max(0, static_cast<int>(std::floor(y0 - 0.5))), j1 = std::min(height_ - 1, static_cast<int>(std::ceil(y1 - 0.5)));
    const Vec2 a = p[1] - p[0], b = p[2] - p[0];
    const double det = a.x() * b.y() - a.y() * b.x();
    if (det == 0) continue;
    for (int j = j0; j <= j1; ++j)
      for (int i = i0; i <= i1; ++i) {
        const size_t k = static_cast<size_t>(j) * static_cast<size_t>(width_) + static_cast<size_t>(i);
        if (face_[k] >= 0) continue;
        const Vec2 d = Vec2(i + 0.5, j + 0.5) - p[0];
        const double l1 = (d.x() * b.y() - d.y() * b.x()) / det;
        const double l2 = (a.x() * d.y() - a.y() * d.x()) / det;
        const double l0 = 1 - l1 - l2;
        constexpr double eps = -1e-9;
        if (l0 < eps || l1 < eps || l2 < eps) continue;
        face_[k] = f;
        bary_[3 * k] = static_cast<float>(l0);
        bary_[3 * k + 1] = static_cast<float>(l1);
        bary_[3 * k + 2] = static_cast<float>(l2);
      }
  }

  // Speed scale: the 90th percentile of |V| over the whole field moves pixels_per_frame
  // pixels in one frame of the field.
  {
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
    const double ppf = o_.pixels_per_frame > 0 ? o_.pixels_per_frame : o_.size / 128.0;
    time_scale_ = p90 > 0 && frame_dt > 0 ? ppf / (p90 * frame_dt) : 0.0;
    p90_ = p90;
  }

  // Noise: cells of noise_scale pixels, each with a random phase.
  cell_ = o_.noise_scale > 0 ? o_.noise_scale : std::max(1.0, o_.size / 256.0);
  cells_x_ = static_cast<int>(std::ceil(width_ / cell_)) + 2;
  cells_y_ = static_cast<int>(std::ceil(height_ / cell_)) + 2;
  phase_.resize(static_cast<size_t>(cells_x_) * static_cast<size_t>(cells_y_));
  std::mt19937_64 rng(o_.seed);
  std::uniform_real_distribution<float> uni(0.0f, 1.0f);
  for (auto& p : phase_) p = uni(rng);
  lattice_.resize(phase_.size());
  vel_.assign(2 * n, 0.0f);  // x displacements, then y displacements
  dir_.assign(2 * n, 0.0f);
  tex_.assign(n, 0.5f);
  next_.assign(n, 0.5f);
}

Vec2 TextureAnimator::to_pixel(const Vec2& x) const {
  return {(x.x() - lo_.x()) * ppu_, (hi_.y() - x.y()) * ppu_};
}

void TextureAnimator::compute_velocity(double t, double dt) {
  const std::vector<cplx> values = values_at(field_, t);
  const Mesh& mesh = bundle_.mesh();
  const double s = dt * time_scale_;
  const size_t n = face_.size();
  // Uniform speed: V/max(|V|, floor) times the typical speed.
  const bool uniform = o_.speed == TextureSpeed::uniform;
  const double floor = 1e-12 * p90_;
  // The unit directions times the LIC's step length: a step of the LIC's walks.
  const float lic_len = lic_step(o_.lic);
  tbb::parallel_for(tbb::blocked_range<int>(0, height_), [&](const tbb::blocked_range<int>& rows) {
    for (int j = rows.begin(); j < rows.end(); ++j)
      for (int i = 0; i < width_; ++i) {
        const size_t k = static_cast<size_t>(j) * static_cast<size_t>(width_) + static_cast<size_t>(i);
        const int f = face_[k];
        if (f < 0) {
          vel_[k] = vel_[n + k] = dir_[k] = dir_[n + k] = 0.0f;
          continue;
        }
        const Face& tri = mesh.face(f);
        // Planar bundle: every frame is the plane's, so corner values add directly.
        const cplx z = static_cast<double>(bary_[3 * k]) * values[static_cast<size_t>(tri[0])] +
                       static_cast<double>(bary_[3 * k + 1]) * values[static_cast<size_t>(tri[1])] +
                       static_cast<double>(bary_[3 * k + 2]) * values[static_cast<size_t>(tri[2])];
        // |z| by sqrt of the squared norm (std::abs is hypot, which guards against
        // overflow these velocities never reach, at several times the cost).
        const double m = std::sqrt(std::norm(z));
        const double g = uniform ? s * p90_ / std::max(m, floor) : s;
        vel_[k] = static_cast<float>(z.real() * g);
        vel_[n + k] = static_cast<float>(-z.imag() * g);  // image y points down
        dir_[k] = m > 0 ? lic_len * static_cast<float>(z.real() / m) : 0.0f;
        dir_[n + k] = m > 0 ? lic_len * static_cast<float>(-z.imag() / m) : 0.0f;
      }
  });
}

void TextureAnimator::blend(int k) {
  // Noise cells switch on for the first half of their cycle and off for the second,
  // each with its own phase (van Wijk 2002).
  const float period = static_cast<float>(o_.noise_period);
  for (size_t c = 0; c < phase_.size(); ++c) {
    float u = static_cast<float>(k % o_.noise_period) / period + phase_[c];
    u -= std::floor(u);
    lattice_[c] = u < 0.5f ? 1.0f : 0.0f;
  }
  const float a = static_cast<float>(o_.alpha);
  const float inv_cell = static_cast<float>(1.0 / cell_);
  const int w = width_, h = height_;
  const float* tex = tex_.data();
  const float* vel = vel_.data();
  const float* lat = lattice_.data();
  float* out = next_.data();
  const size_t n = face_.size();
  const float inflow = static_cast<float>(mean_);
  // The fractions along the step of the noise samples, (q + ½) / samples, by table (the
  // same values; three divisions a pixel fewer).
  float along[5][4] = {};
  for (int m = 1; m <= 4; ++m)
    for (int q = 0; q < m; ++q) along[m][q] = (static_cast<float>(q) + 0.5f) / static_cast<float>(m);
  tbb::parallel_for(tbb::blocked_range<int>(0, h), [&](const tbb::blocked_range<int>& rows) {
    for (int j = rows.begin(); j < rows.end(); ++j)
      for (int i = 0; i < w; ++i) {
        const size_t p = static_cast<size_t>(j) * static_cast<size_t>(w) + static_cast<size_t>(i);
        if (face_[p] < 0) {
          out[p] = 0.5f;
          continue;
        }
        // Backward step with the midpoint rule: where did the texture here come from?
        const float fi = static_cast<float>(i), fj = static_cast<float>(j);
        const float mx = fi - 0.5f * vel[p], my = fj - 0.5f * vel[n + p];
        float dx, dy;
        bilinear2(vel, vel + n, w, h, mx, my, dx, dy);
        const float sx = fi - dx, sy = fj - dy;
        // The noise injected is its mean along the step, not its value at the pixel: a
        // noise cell fixed in space, injected once a frame at the same place, would leave
        // a stripe every step length across the streaks. (The lattice starts one cell
        // left of and above the picture.)
        const float len = std::abs(dx) + std::abs(dy);
        const int samples = std::clamp(static_cast<int>(len * inv_cell) + 1, 1, 4);  // ~one per noise cell
        float noise;
        if (samples == 1) {
          noise = bilinear(lat, cells_x_, cells_y_, (fi - 0.5f * dx) * inv_cell + 1, (fj - 0.5f * dy) * inv_cell + 1);
        } else {
          // Several samples along the step: the nearest cell's value is enough for each.
          noise = 0;
          for (int q = 0; q < samples; ++q) {
            const float u = along[samples][q];
            const int cx = std::clamp(static_cast<int>((fi - u * dx) * inv_cell + 1.5f), 0, cells_x_ - 1);
            const int cy = std::clamp(static_cast<int>((fj - u * dy) * inv_cell + 1.5f), 0, cells_y_ - 1);
            noise += lat[static_cast<size_t>(cy) * static_cast<size_t>(cells_x_) + static_cast<size_t>(cx)];
          }
          noise /= static_cast<float>(samples);
        }
        float old;
        if (sx < -0.5f || sy < -0.5f || sx > static_cast<float>(w) - 0.5f || sy > static_cast<float>(h) - 0.5f)
          old = inflow;  // from outside the picture: the texture's mean, so inflow fades in
        else
          old = bilinear(tex, w, h, sx, sy);
        out[p] = (1.0f - a) * old + a * noise;
      }
  });
  tex_.swap(next_);
}

std::pair<double, double> TextureAnimator::statistics(const std::vector<float>& image) const {
  struct Acc {
    double sum = 0, sum2 = 0, n = 0;
  };
  const Acc acc = tbb::parallel_reduce(
      tbb::blocked_range<size_t>(0, image.size()), Acc{},
      [&](const tbb::blocked_range<size_t>& r, Acc a) {
        for (size_t k = r.begin(); k < r.end(); ++k)
          if (face_[k] >= 0) {
            a.sum += image[k];
            a.sum2 += static_cast<double>(image[k]) * image[k];
            a.n += 1;
          }
        return a;
      },
      [](Acc a, const Acc& b) {
        a.sum += b.sum;
        a.sum2 += b.sum2;
        a.n += b.n;
        return a;
      });
  const double mean = acc.n > 0 ? acc.sum / acc.n : 0.5;
  const double sd = acc.n > 0 ? std::sqrt(std::max(0.0, acc.sum2 / acc.n - mean * mean)) : 0.1;
  return {mean, std::max(sd, 1e-3)};
}

void TextureAnimator::advance(double t) {
  const TimeSampling& ts = field_.time();
  const double frame_dt = ts.frames > 1 ? (ts.t1 - ts.t0) / (ts.frames - 1) : 1.0;
  auto stats = [&] { return statistics(tex_); };
  if (!started_) {
    // Warm up at t: a steady texture before the first picture.
    compute_velocity(t, frame_dt);
    const int warm = o_.warmup > 0 ? o_.warmup : static_cast<int>(std::ceil(3.0 / o_.alpha));
    // Noise starts from uniform gray: start the texture from the noise itself.
    for (int k = 0; k < warm; ++k) blend(static_cast<int>(step_++));
    started_ = true;
    t_ = t;
    std::tie(mean_, sd_) = stats();
    return;
  }
  const double dt = t - t_;
  compute_velocity(0.5 * (t + t_), dt);
  blend(static_cast<int>(step_++ % (1L << 30)));
  t_ = t;
  // The contrast stretch follows the texture's statistics slowly (no flicker).
  const auto [m, s] = stats();
  mean_ = 0.8 * mean_ + 0.2 * m;
  sd_ = 0.8 * sd_ + 0.2 * s;
}

Image TextureAnimator::picture() const {
  Image img(width_, height_);
  const std::vector<float>* shown = &tex_;
  if (o_.lic > 0) {
    // Line integral convolution of the advected texture: its mean along the field's
    // direction, o_.lic pixels each way in at most 6 steps each way (Euler on the
    // frame's unit directions, nearest-pixel directions and texture values).
    lic_.assign(tex_.size(), 0.5f);
    const int w = width_, h = height_;
    const size_t n = tex_.size();
    const float* dir = dir_.data();
    const float* tex = tex_.data();
    const int steps = lic_steps(o_.lic);
    // The walks of kGroup neighbouring pixels, each way, advance side by side: 2·kGroup
    // independent chains of dependent look-ups (direction → position → pixel → direction)
    // keep the core busy where one walk at a time waits on each load. A walk that leaves
    // the picture stops (its later samples are not counted); the samples are summed in
    // the order of one walk at a time (forward, then backward), so the result is the same
    // bit for bit. dir_ holds the steps (unit directions times lic / steps).
    constexpr int kGroup = 4, kChains = 2 * kGroup, kMaxSteps = 6;
    const float xmax = static_cast<float>(w - 1), ymax = static_cast<float>(h - 1);
    tbb::parallel_for(tbb::blocked_range<int>(0, h), [&](const tbb::blocked_range<int>& rows) {
      for (int j = rows.begin(); j < rows.end(); ++j)
        for (int i0 = 0; i0 < w; i0 += kGroup) {
          const size_t p0 = static_cast<size_t>(j) * static_cast<size_t>(w) + static_cast<size_t>(i0);
          float x[kChains], y[kChains], value[kChains][kMaxSteps];
          int k[kChains], count[kChains];
          bool alive[kChains];
          for (int c = 0; c < kChains; ++c) {
            const int g = c / 2;
            const bool inside = i0 + g < w && face_[p0 + static_cast<size_t>(g)] >= 0;
            x[c] = static_cast<float>(i0 + g);
            y[c] = static_cast<float>(j);
            k[c] = inside ? static_cast<int>(p0) + g : 0;
            count[c] = 0;
            alive[c] = inside;
          }
          // One step of chain c to (nx, ny). The new pixel's index is computed before the
          // bounds are known: the position is at most one step outside, well within int
          // (through int: one instruction, where float → size_t is a compare and branch
          // on x86-64 without AVX-512); a walk that has left keeps its last pixel.
          auto advance = [&](int c, int q, float nx, float ny) {
            alive[c] = alive[c] && nx >= 0 && ny >= 0 && nx <= xmax && ny <= ymax;
            const int kn = static_cast<int>(ny + 0.5f) * w + static_cast<int>(nx + 0.5f);
            x[c] = alive[c] ? nx : x[c];
            y[c] = alive[c] ? ny : y[c];
            k[c] = alive[c] ? kn : k[c];
            value[c][q] = tex[static_cast<size_t>(k[c])];  // nearest pixel: the texture is smooth
            count[c] += alive[c] ? 1 : 0;
          };
          for (int q = 0; q < steps; ++q)
            for (int g = 0; g < kGroup; ++g) {
              const size_t kf = static_cast<size_t>(k[2 * g]), kb = static_cast<size_t>(k[2 * g + 1]);
              advance(2 * g, q, x[2 * g] + dir[kf], y[2 * g] + dir[n + kf]);
              advance(2 * g + 1, q, x[2 * g + 1] - dir[kb], y[2 * g + 1] - dir[n + kb]);
            }
          for (int g = 0; g < kGroup && i0 + g < w; ++g) {
            const size_t p = p0 + static_cast<size_t>(g);
            if (face_[p] < 0) continue;
            float sum = tex[p];
            for (int q = 0; q < count[2 * g]; ++q) sum += value[2 * g][q];
            for (int q = 0; q < count[2 * g + 1]; ++q) sum += value[2 * g + 1][q];
            lic_[p] = sum / static_cast<float>(1 + count[2 * g] + count[2 * g + 1]);
          }
        }
    });
    shown = &lic_;
  }
  // Statistics of what is shown (the convolution narrows the spread).
  double mean = mean_, sd = sd_;
  if (o_.lic > 0) std::tie(mean, sd) = statistics(lic_);
  const float gain = static_cast<float>(o_.contrast / (4.4 * sd));
  const float m0 = static_cast<float>(mean);
  const std::vector<float>& src = *shown;
  tbb::parallel_for(tbb::blocked_range<size_t>(0, tex_.size()), [&](const tbb::blocked_range<size_t>& r) {
    for (size_t k = r.begin(); k < r.end(); ++k) {
      if (face_[k] < 0) {
        img.pixels[k] = o_.background;
        continue;
      }
      const float v = std::clamp(0.5f + (src[k] - m0) * gain, 0.0f, 1.0f);
      img.pixels[k] = gray(static_cast<std::uint8_t>(v * 255.0f + 0.5f));  // rounded (v ≥ 0)
    }
  });
  return img;
}

void draw_singularities(Image& image, const TextureAnimator& animator, const TangentBundle& bundle,
                        const Field& field, double t) {
  const std::vector<cplx> values = values_at(field, t);
  const auto sing = find_singularities(bundle, values);
  cairo_surface_t* surface = cairo_image_surface_create_for_data(
      reinterpret_cast<unsigned char*>(image.pixels.data()), CAIRO_FORMAT_RGB24, image.width, image.height,
      image.width * 4);
  cairo_t* cr = cairo_create(surface);
  const double r = std::max(3.5, std::max(image.width, image.height) / 110.0);
  cairo_set_line_width(cr, std::max(1.0, r / 4));
  for (const Singularity& s : sing) {
    const Vec2 p = animator.to_pixel(s.position.head<2>());
    const auto c = type_color(s.type);
    cairo_new_sub_path(cr);
    cairo_arc(cr, p.x(), p.y(), r, 0, 2 * kPi);
    cairo_set_source_rgb(cr, c[0], c[1], c[2]);
    cairo_fill_preserve(cr);
    cairo_set_source_rgb(cr, 0, 0, 0);
    cairo_stroke(cr);
  }
  cairo_destroy(cr);
  cairo_surface_flush(surface);
  cairo_surface_destroy(surface);
}

void draw_singularity_paths(Image& image, const TextureAnimator& animator, const Topology& topology, double t) {
  cairo_surface_t* surface = cairo_image_surface_create_for_data(
      reinterpret_cast<unsigned char*>(image.pixels.data()), CAIRO_FORMAT_RGB24, image.width, image.height,
      image.width * 4);
  cairo_t* cr = cairo_create(surface);
  const double width = std::max(1.5, std::max(image.width, image.height) / 300.0);
  cairo_set_line_cap(cr, CAIRO_LINE_CAP_ROUND);
  cairo_set_line_join(cr, CAIRO_LINE_JOIN_ROUND);
  for (const SingularityPath& path : topology.paths) {
    if (path.points.empty() || path.points.front().t > t) continue;
    cairo_new_path(cr);
    for (size_t k = 0; k < path.points.size(); ++k) {
      const PathSample& s = path.points[k];
      Vec2 p = animator.to_pixel(s.position.head<2>());
      if (s.t > t) {
        // The trail ends at t: between the last sample before t and this one.
        const PathSample& a = path.points[k - 1];
        const double w = s.t > a.t ? (t - a.t) / (s.t - a.t) : 1.0;
        p = animator.to_pixel(((1 - w) * a.position + w * s.position).head<2>());
        cairo_line_to(cr, p.x(), p.y());
        break;
      }
      if (k == 0) cairo_move_to(cr, p.x(), p.y());
      else cairo_line_to(cr, p.x(), p.y());
    }
    // A dark casing under the coloured line keeps it readable on the texture.
    cairo_set_source_rgb(cr, 0, 0, 0);
    cairo_set_line_width(cr, 2.2 * width);
    cairo_stroke_preserve(cr);
    const auto c = type_color(path.type);
    cairo_set_source_rgb(cr, c[0], c[1], c[2]);
    cairo_set_line_width(cr, width);
    cairo_stroke(cr);
  }
  cairo_destroy(cr);
  cairo_surface_flush(surface);
  cairo_surface_destroy(surface);
}

void draw_orbits(Image& image, const TextureAnimator& animator, const PeriodicOrbits& orbits, const Field& field,
                 double t) {
  const TimeSampling& ts = field.time();
  int j = 0;
  double w = 0;
  ts.locate(t, j, w);
  if (w > 0.5) ++j;
  const double dt = ts.frames > 1 ? (ts.t1 - ts.t0) / (ts.frames - 1) : 1.0;
  cairo_surface_t* surface = cairo_image_surface_create_for_data(
      reinterpret_cast<unsigned char*>(image.pixels.data()), CAIRO_FORMAT_RGB24, image.width, image.height,
      image.width * 4);
  cairo_t* cr = cairo_create(surface);
  const double width = std::max(1.5, std::max(image.width, image.height) / 300.0);
  cairo_set_line_join(cr, CAIRO_LINE_JOIN_ROUND);
  for (const PeriodicOrbit& o : orbits.orbits) {
    if (o.frame != j) continue;
    cairo_new_path(cr);
    for (size_t k = 0; k < o.points.size(); ++k) {
      const Vec2 p = animator.to_pixel(o.points[k].head<2>());
      if (k == 0) cairo_move_to(cr, p.x(), p.y());
      else cairo_line_to(cr, p.x(), p.y());
    }
    cairo_close_path(cr);
    cairo_set_source_rgb(cr, 0, 0, 0);
    cairo_set_line_width(cr, 2.2 * width);
    cairo_stroke_preserve(cr);
    if (o.stability == OrbitStability::attracting) cairo_set_source_rgb(cr, 0.93, 0.5, 0.05);
    else cairo_set_source_rgb(cr, 0.0, 0.6, 0.6);
    cairo_set_line_width(cr, width);
    cairo_stroke(cr);
  }
  const double r = std::max(8.0, std::max(image.width, image.height) / 40.0);
  for (const HopfEvent& e : orbits.hopf) {
    if (std::abs(e.t - t) > 2 * dt) continue;
    const Vec2 p = animator.to_pixel(e.position.head<2>());
    cairo_move_to(cr, p.x(), p.y() - r);
    cairo_line_to(cr, p.x() + r, p.y());
    cairo_line_to(cr, p.x(), p.y() + r);
    cairo_line_to(cr, p.x() - r, p.y());
    cairo_close_path(cr);
    cairo_set_source_rgb(cr, 1, 1, 1);  // a white casing under the black outline
    cairo_set_line_width(cr, 2.6 * width);
    cairo_stroke_preserve(cr);
    cairo_set_source_rgb(cr, 0, 0, 0);
    cairo_set_line_width(cr, 1.2 * width);
    cairo_stroke(cr);
  }
  cairo_destroy(cr);
  cairo_surface_flush(surface);
  cairo_surface_destroy(surface);
}

void draw_streamlines(Image& image, const TextureAnimator& animator, const TangentBundle& bundle,
                      const Field& field, double t, double separation) {
  const double sep_px = separation > 0 ? separation : 0.03 * std::max(image.width, image.height);
  EvenlySpacedOptions o;
  o.separation = sep_px / animator.pixels_per_unit();
  const auto lines = evenly_spaced_streamlines(bundle, values_at(field, t), o);
  cairo_surface_t* surface = cairo_image_surface_create_for_data(
      reinterpret_cast<unsigned char*>(image.pixels.data()), CAIRO_FORMAT_RGB24, image.width, image.height,
      image.width * 4);
  cairo_t* cr = cairo_create(surface);
  cairo_set_line_width(cr, std::max(1.0, std::max(image.width, image.height) / 600.0));
  cairo_set_line_join(cr, CAIRO_LINE_JOIN_ROUND);
  cairo_set_source_rgb(cr, 0.05, 0.05, 0.05);
  for (const Streamline& line : lines) {
    cairo_new_path(cr);
    for (size_t k = 0; k < line.points.size(); ++k) {
      const Vec2 p = animator.to_pixel(line.points[k].head<2>());
      if (k == 0) cairo_move_to(cr, p.x(), p.y());
      else cairo_line_to(cr, p.x(), p.y());
    }
    cairo_stroke(cr);
  }
  cairo_destroy(cr);
  cairo_surface_flush(surface);
  cairo_surface_destroy(surface);
}

std::optional<Field> texture_dye_field(const Field& field, const TextureAnimationOptions& options) {
  check_option(std::isfinite(options.dye_time_scale) && options.dye_time_scale > 0, "dye time scale",
               fmt::format("{} is not a positive number", options.dye_time_scale));
  std::optional<Field> scaled;
  if ((options.streakline_seeds.empty() && options.timelines.empty()) || options.dye_time_scale == 1.0) return scaled;
  scaled.emplace(field);
  for (cplx& z : scaled->data()) z *= options.dye_time_scale;
  return scaled;
}

std::optional<DyeInjector> texture_dye(const TangentBundle& bundle, const Field& carried,
                                       const TextureAnimationOptions& options, int pictures) {
  std::optional<DyeInjector> dye;
  if (options.streakline_seeds.empty() && options.timelines.empty()) return dye;
  const TimeSampling& ts = carried.time();
  DyeOptions o;
  o.timelines = options.timelines;
  if (pictures > 1) o.release_spacing = 0.25 * (ts.t1 - ts.t0) / (pictures - 1);
  dye.emplace(bundle, carried, options.streakline_seeds, ts.t0, o);
  return dye;
}

DyeStyle texture_dye_style(int width, int height, double pixels_per_unit) {
  DyeStyle style;
  style.width = std::max(1.5, std::max(width, height) / 300.0);
  style.max_gap = 24.0 / pixels_per_unit;
  style.casing = true;
  return style;
}

TextureAnimationReport write_texture_animation(const TangentBundle& bundle, const Field& field,
                                               const TextureAnimationOptions& options) {
  using clock = std::chrono::steady_clock;
  const auto start = clock::now();
  if (options.frames_dir.empty() && options.video.empty() && !options.on_picture)
    throw Error("texture animation: give a folder for the PNG frames or an MP4 file to write");
  const int total = options.frames > 0 ? options.frames : field.frames();
  check_option(total >= 1 && total <= 1'000'000, "frames", fmt::format("{} is outside [1, 1000000]", total));
  const int first = options.first;
  const int last = options.last < 0 ? total - 1 : options.last;
  check_option(first >= 0 && first < total, "first frame", fmt::format("{} is outside [0, {}]", first, total - 1));
  check_option(last >= first && last < total, "last frame", fmt::format("{} is outside [{}, {}]", last, first, total - 1));
  check_option(std::isfinite(options.fps) && options.fps > 0 && options.fps <= 1000, "fps",
               fmt::format("{} is outside (0, 1000]", options.fps));

  check_option(!options.overlay_orbits || bundle.is_flat(), "overlay",
               "orbits are drawn on planar domains only (their points are in tvf analyze's JSON on surfaces)");
  if (!bundle.is_flat()) return write_surface_texture_animation(bundle, field, options, first, last, total);
  TextureAnimator animator(bundle, field, options.texture);
  const std::optional<Field> dye_field = texture_dye_field(field, options);
  std::optional<DyeInjector> dye = texture_dye(bundle, dye_field ? *dye_field : field, options, total);
  Topology topology;
  if (options.overlay_paths || options.overlay_orbits) topology = analyze_topology(bundle, field);
  PeriodicOrbits orbits;
  if (options.overlay_orbits) orbits = find_periodic_orbits(bundle, field, topology);
  // The video: x264's superfast preset at CRF 14 encodes these noise textures in half the
  // CPU time of veryfast at CRF 18, with a higher PSNR (33.9 against 33.7 dB) and an 11 %
  // larger file (docs/benchmarks.md, "Texture animation"). Without coloured overlays the
  // pictures are gray (the streamlines are dark gray), and ffmpeg is fed one byte a pixel.
  VideoOptions video;
  video.preset = "superfast";
  video.crf = 14;
  const std::uint32_t bg = options.texture.background;
  const bool gray_background = ((bg >> 16) & 0xFF) == ((bg >> 8) & 0xFF) && ((bg >> 8) & 0xFF) == (bg & 0xFF);
  video.gray = gray_background && !options.overlay_paths && !options.overlay_orbits &&
               !options.overlay_singularities && options.streakline_seeds.empty() && options.timelines.empty();
  FrameOutput out(options.frames_dir, options.video, animator.width(), animator.height(), options.fps,
                  options.on_picture, video);

  const TimeSampling& ts = field.time();
  auto time_of = [&](int k) { return total > 1 ? ts.t0 + (ts.t1 - ts.t0) * k / (total - 1) : ts.t0; };
  TextureAnimationReport report;
  report.width = animator.width();
  report.height = animator.height();
  double texture_seconds = 0, warmup_seconds = 0;
  const int count = last - first + 1;
  int done = 0;
  out.add_in_order(
      first, last,
      [&](int k) {
        check_render_cancelled(options);
        const double t = time_of(k);
        const auto t0 = clock::now();
        animator.advance(t);
        Image img = animator.picture();
        (k == first ? warmup_seconds : texture_seconds) += std::chrono::duration<double>(clock::now() - t0).count();
        if (options.overlay_streamlines) draw_streamlines(img, animator, bundle, field, t);
        if (options.overlay_paths) draw_singularity_paths(img, animator, topology, t);
        if (dye) {
          dye->advance(t);
          draw_dye(img, *dye, [&](const Vec2& x) { return animator.to_pixel(x); }, texture_dye_style(img.width, img.height, animator.pixels_per_unit()));
        }
        if (options.overlay_singularities) draw_singularities(img, animator, bundle, field, t);
        if (options.overlay_orbits) draw_orbits(img, animator, orbits, field, t);  // rings round the dots
        return img;
      },
      [&](int n) {
        done = n;
        if (options.progress) options.progress(n, count);
      });
  report.files = out.finish();
  report.frames = done;
  if (dye) report.timelines = dye->timeline_records();
  report.texture_seconds = texture_seconds;
  report.warmup_seconds = warmup_seconds;
  report.seconds = std::chrono::duration<double>(clock::now() - start).count();
  return report;
}

}  // namespace tvf
