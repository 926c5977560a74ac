#include "tvf/synth/planar_synthesis.h"

#include "tvf/core/atomic_output.h"
#include "tvf/core/error.h"
#include "tvf/field/field_sampler.h"
#include "tvf/mesh/mesh_io.h"
#include "tvf/render/frame_output.h"
#include "tvf/synth/terrain.h"

#include <fmt/format.h>
#include <tbb/blocked_range.h>
#include <tbb/parallel_for.h>

#include <algorithm>
#include <atomic>
#include <chrono>
#include <cmath>
#include <filesystem>
#include <limits>
#include <random>

namespace tvf {

void build_exemplar_pyramid(const Exemplar& e, const SynthesisOptions& o, std::vector<Exemplar>& exemplars,
                            std::vector<std::unique_ptr<ExemplarIndex>>& indices) {
  exemplars.push_back(e);
  for (int l = 1; l < o.levels; ++l) exemplars.push_back(downsample(exemplars.back()));
  ExemplarIndexOptions io;
  io.size = o.neighbourhood;
  io.pca_dimensions = o.pca_dimensions;
  io.candidates = o.candidates;
  io.search_eps = o.search_eps;
  for (int l = 0; l < o.levels; ++l) {
    const Exemplar& ex = exemplars[static_cast<size_t>(l)];
    if (ex.width < o.neighbourhood || ex.height < o.neighbourhood)
      throw Error(fmt::format("the exemplar ({}×{} pixels) is too small for {} levels of {}×{} neighbourhoods: "
                              "level {} would be {}×{}; use fewer levels or a larger exemplar",
                              e.width, e.height, o.levels, o.neighbourhood, o.neighbourhood, l, ex.width, ex.height));
    indices.push_back(std::make_unique<ExemplarIndex>(ex, io));
  }
}

namespace fs = std::filesystem;

namespace {

void check_option(bool ok, const char* name, const std::string& why) {
  if (!ok) throw Error(fmt::format("synthesis option {}: {}", name, why));
}

// Bilinear read of a grid (w × h × C) at a position in pixel-index coordinates (pixel i's
// centre at i), clamped to the edges.
inline void bilinear_taps(double px, double py, int w, int h, Tap& tap) {
  const double fx0 = std::floor(px), fy0 = std::floor(py);
  const float fx = static_cast<float>(px - fx0), fy = static_cast<float>(py - fy0);
  const int x0 = std::clamp(static_cast<int>(fx0), 0, w - 1), x1 = std::clamp(static_cast<int>(fx0) + 1, 0, w - 1);
  const int y0 = std::clamp(static_cast<int>(fy0), 0, h - 1), y1 = std::clamp(static_cast<int>(fy0) + 1, 0, h - 1);
  tap.sample = {y0 * w + x0, y0 * w + x1, y1 * w + x0, y1 * w + x1};
  tap.weight = {(1 - fx) * (1 - fy), fx * (1 - fy), (1 - fx) * fy, fx * fy};
}

inline float bilinear(const std::vector<float>& g, int w, int h, int C, int c, double px, double py) {
  Tap t;
  bilinear_taps(px, py, w, h, t);
  float s = 0;
  for (size_t i = 0; i < 4; ++i) s += t.weight[i] * g[static_cast<size_t>(t.sample[i]) * static_cast<size_t>(C) + static_cast<size_t>(c)];
  return s;
}

}  // namespace

struct PlanarSynthesizer::Impl {
  struct Level {
    int w = 0, h = 0;
    double ppu = 1;
    std::vector<int> face;
    std::vector<float> bary;
    std::vector<float> dir;  // 2 per pixel, image coordinates, unit (or 0)
    std::vector<float> vel;  // 2 per pixel: pixels of this level per unit of time
    Neighbourhoods nb;
    std::vector<float> x;
    std::vector<float> target;
    std::vector<int> match;  // the last matches of the neighbourhoods (search hints)
    std::vector<float> target_weight;  // per pixel: factor of the temporal weight
  };

  const TangentBundle& bundle;
  const Field& field;
  SynthesisOptions o;
  int C = 3;
  std::vector<Exemplar> exemplars;
  std::vector<std::unique_ptr<ExemplarIndex>> indices;
  std::vector<Level> levels;
  Vec2 lo, hi;
  double p90 = 0, time_scale = 0;  // finest-level pixels per (unit speed × unit time)
  double t = 0;
  bool started = false;
  SynthesisFrameReport report;

  Impl(const TangentBundle& b, const Field& f, const Exemplar& e, const SynthesisOptions& options)
      : bundle(b), field(f), o(options), C(e.channels) {
    const Mesh& mesh = bundle.mesh();
    if (!mesh.is_planar_xy())
      throw_input_error(mesh.source(), "", "planar texture synthesis needs a planar domain (use the surface synthesis)");
    check_option(o.size >= 16 && o.size <= 8192, "size", fmt::format("{} is outside [16, 8192]", o.size));
    check_option(o.levels >= 1 && o.levels <= 8, "levels", fmt::format("{} is outside [1, 8]", o.levels));
    check_option(o.frame_levels >= 1 && o.frame_levels <= o.levels, "frame_levels",
                 fmt::format("{} is outside [1, levels = {}]", o.frame_levels, o.levels));
    check_option(o.neighbourhood >= 3 && o.neighbourhood <= 21 && o.neighbourhood % 2 == 1, "neighbourhood",
                 fmt::format("{} must be odd, in [3, 21]", o.neighbourhood));
    check_option(o.stride >= 1 && o.stride <= o.neighbourhood / 2 + 1, "stride",
                 fmt::format("{} is outside [1, neighbourhood/2 + 1]", o.stride));
    check_option(o.iterations_first >= 1 && o.iterations_first <= 100, "iterations_first",
                 fmt::format("{} is outside [1, 100]", o.iterations_first));
    check_option(o.iterations >= 1 && o.iterations <= 100, "iterations", fmt::format("{} is outside [1, 100]", o.iterations));
    check_option(std::isfinite(o.temporal_weight) && o.temporal_weight >= 0 && o.temporal_weight <= 100, "temporal_weight",
                 fmt::format("{} is outside [0, 100]", o.temporal_weight));
    check_option(std::isfinite(o.pixels_per_frame) && o.pixels_per_frame >= 0 && o.pixels_per_frame <= 1000,
                 "pixels_per_frame", fmt::format("{} is outside [0, 1000]", o.pixels_per_frame));
    check_option(o.max_distortion == 0 || (std::isfinite(o.max_distortion) && o.max_distortion > 1 && o.max_distortion <= 100),
                 "max_distortion", fmt::format("{} must be 0 (never renew) or in (1, 100]", o.max_distortion));
    check_option(o.renew_frames >= 1 && o.renew_frames <= 1000, "renew_frames",
                 fmt::format("{} is outside [1, 1000]", o.renew_frames));
    check_option(o.pca_dimensions >= 1 && o.pca_dimensions <= 256, "pca_dimensions",
                 fmt::format("{} is outside [1, 256]", o.pca_dimensions));
    check_option(o.candidates >= 1 && o.candidates <= 16, "candidates", fmt::format("{} is outside [1, 16]", o.candidates));
    for (const cplx& z : field.data())
      if (!std::isfinite(z.real()) || !std::isfinite(z.imag()))
        throw_input_error(mesh.source(), "", "the field has a value that is not a finite number");

    build_exemplar_pyramid(e, o, exemplars, indices);

    // Grid pyramid.
    lo = mesh.bbox_min().head<2>();
    hi = mesh.bbox_max().head<2>();
    const Vec2 ext = hi - lo;
    const double ppu = o.size / std::max(ext.x(), ext.y());
    levels.resize(static_cast<size_t>(o.levels));
    levels[0].w = std::max(1, static_cast<int>(std::lround(ext.x() * ppu)));
    levels[0].h = std::max(1, static_cast<int>(std::lround(ext.y() * ppu)));
    levels[0].ppu = ppu;
    for (size_t l = 1; l < levels.size(); ++l) {
      levels[l].w = (levels[l - 1].w + 1) / 2;
      levels[l].h = (levels[l - 1].h + 1) / 2;
      levels[l].ppu = levels[l - 1].ppu / 2;
    }
    for (auto& L : levels) locate_pixels(L);

    // Speed scale (as render/texture_animation.h): the 90th-percentile |V| moves
    // pixels_per_frame finest pixels per frame of the field.
    std::vector<double> speeds;
    const size_t total = field.data().size();
    const size_t step = std::max<size_t>(1, total / 1'000'000);
    for (size_t k = 0; k < total; k += step) speeds.push_back(std::abs(field.data()[k]));
    if (!speeds.empty()) {
      auto mid = speeds.begin() + static_cast<long>(0.9 * static_cast<double>(speeds.size() - 1));
      std::nth_element(speeds.begin(), mid, speeds.end());
      p90 = *mid;
    }
    const TimeSampling& ts = field.time();
    const double frame_dt = ts.frames > 1 ? std::abs(ts.t1 - ts.t0) / (ts.frames - 1) : 1.0;
    const double ppf = o.pixels_per_frame > 0 ? o.pixels_per_frame : o.size / 256.0;
    time_scale = p90 > 0 && frame_dt > 0 ? ppf / (p90 * frame_dt) : 0.0;
  }

  // Which face holds each pixel centre of a level, and where.
  void locate_pixels(Level& L) const {
    const Mesh& mesh = bundle.mesh();
    const size_t n = static_cast<size_t>(L.w) * static_cast<size_t>(L.h);
    L.face.assign(n, -1);
    L.bary.assign(3 * n, 0.f);
    L.dir.assign(2 * n, 0.f);
    L.vel.assign(2 * n, 0.f);
    auto to_pixel = [&](const Vec3& p) {  // pixel-index coordinates (centre of pixel i at i)
      return Vec2((p.x() - lo.x()) * L.ppu - 0.5, (hi.y() - p.y()) * L.ppu - 0.5);
    };
    for (int f = 0; f < mesh.num_faces(); ++f) {
      const Face& tri = mesh.face(f);
      const Vec2 p0 = to_pixel(mesh.position(tri[0])), p1 = to_pixel(mesh.position(tri[1])), p2 = to_pixel(mesh.position(tri[2]));
      const int i0 = std::max(0, static_cast<int>(std::floor(std::min({p0.x(), p1.x(), p2.x()}))));
      const int i1 = std::min(L.w - 1, static_cast<int>(std::ceil(std::max({p0.x(), p1.x(), p2.x()}))));
      const int j0 = std::max(0, static_cast<int>(std::floor(std::min({p0.y(), p1.y(), p2.y()}))));
      const int j1 = std::min(L.h - 1, static_cast<int>(std::ceil(std::max({p0.y(), p1.y(), p2.y()}))));
      const Vec2 a = p1 - p0, b = p2 - p0;
      const double det = a.x() * b.y() - a.y() * b.x();
      if (det == 0) continue;
      for (int j = j0; j <= j1; ++j)
        for (int i = i0; i <= i1; ++i) {
          const size_t k = static_cast<size_t>(j) * static_cast<size_t>(L.w) + static_cast<size_t>(i);
          if (L.face[k] >= 0) continue;
          const Vec2 d = Vec2(i, j) - p0;
          const double l1 = (d.x() * b.y() - d.y() * b.x()) / det;
          const double l2 = (a.x() * d.y() - a.y() * d.x()) / det;
          const double l0 = 1 - l1 - l2;
          constexpr double eps = -1e-9;
          if (l0 < eps || l1 < eps || l2 < eps) continue;
          L.face[k] = f;
          L.bary[3 * k] = static_cast<float>(l0);
          L.bary[3 * k + 1] = static_cast<float>(l1);
          L.bary[3 * k + 2] = static_cast<float>(l2);
        }
    }
  }

  // Direction and velocity of every pixel of a level at time tt.
  void update_field(Level& L, const std::vector<cplx>& values) const {
    const Mesh& mesh = bundle.mesh();
    const double floor = 1e-12 * std::max(p90, 1e-300);
    const double scale = time_scale * L.ppu / levels[0].ppu;
    const size_t n = static_cast<size_t>(L.w) * static_cast<size_t>(L.h);
    for (size_t k = 0; k < n; ++k) {
      const int f = L.face[k];
      if (f < 0) {
        L.dir[2 * k] = L.dir[2 * k + 1] = 0.f;
        L.vel[2 * k] = L.vel[2 * k + 1] = 0.f;
        continue;
      }
      const Face& tri = mesh.face(f);
      const cplx z = static_cast<double>(L.bary[3 * k]) * values[static_cast<size_t>(tri[0])] +
                     static_cast<double>(L.bary[3 * k + 1]) * values[static_cast<size_t>(tri[1])] +
                     static_cast<double>(L.bary[3 * k + 2]) * values[static_cast<size_t>(tri[2])];
      const double m = std::abs(z);
      // Image coordinates: y down.
      if (m > floor) {
        L.dir[2 * k] = static_cast<float>(z.real() / m);
        L.dir[2 * k + 1] = static_cast<float>(-z.imag() / m);
      } else {
        L.dir[2 * k] = L.dir[2 * k + 1] = 0.f;
      }
      L.vel[2 * k] = static_cast<float>(z.real() * scale);
      L.vel[2 * k + 1] = static_cast<float>(-z.imag() * scale);
    }
  }

  void build_neighbourhoods(Level& L) const {
    const int w = o.neighbourhood, R = w / 2;
    const int stride = static_cast<long>(L.w) * L.h <= 128 * 128 ? 1 : o.stride;
    const int cx = (L.w + stride - 1) / stride, cy = (L.h + stride - 1) / stride;
    L.nb.size = w;
    L.nb.taps.resize(static_cast<size_t>(cx) * static_cast<size_t>(cy) * static_cast<size_t>(w * w));
    tbb::parallel_for(tbb::blocked_range<int>(0, cy), [&](const tbb::blocked_range<int>& rows) {
      for (int b = rows.begin(); b < rows.end(); ++b)
        for (int a = 0; a < cx; ++a) {
          const int i = std::min(a * stride, L.w - 1), j = std::min(b * stride, L.h - 1);
          const size_t k = static_cast<size_t>(j) * static_cast<size_t>(L.w) + static_cast<size_t>(i);
          double ux = L.dir[2 * k], uy = L.dir[2 * k + 1];
          if (ux == 0 && uy == 0) ux = 1;
          const double vx = -uy, vy = ux;
          Tap* taps = L.nb.taps.data() + (static_cast<size_t>(b) * static_cast<size_t>(cx) + static_cast<size_t>(a)) * static_cast<size_t>(w * w);
          for (int r = 0; r < w; ++r)
            for (int c = 0; c < w; ++c)
              bilinear_taps(i + (c - R) * ux + (r - R) * vx, j + (c - R) * uy + (r - R) * vy, L.w, L.h, taps[r * w + c]);
        }
    });
  }

  std::vector<cplx> vertex_values(double tt) const {
    const FieldSampler sampler(bundle, field);
    std::vector<cplx> values(static_cast<size_t>(bundle.mesh().num_vertices()));
    for (size_t v = 0; v < values.size(); ++v) values[v] = sampler.at_vertex(static_cast<int>(v), tt);
    return values;
  }

  std::vector<float> upsample(const Level& coarse, const std::vector<float>& g, const Level& fine) const {
    std::vector<float> out(static_cast<size_t>(fine.w) * static_cast<size_t>(fine.h) * static_cast<size_t>(C));
    for (int j = 0; j < fine.h; ++j)
      for (int i = 0; i < fine.w; ++i)
        for (int c = 0; c < C; ++c)
          out[(static_cast<size_t>(j) * static_cast<size_t>(fine.w) + static_cast<size_t>(i)) * static_cast<size_t>(C) + static_cast<size_t>(c)] =
              bilinear(g, coarse.w, coarse.h, C, c, (i + 0.5) / 2 - 0.5, (j + 0.5) / 2 - 0.5);
    return out;
  }

  // Renewal of deformed texture. Kwatra et al. 2007 leave deformation to the optimization;
  // with 2 iterations per frame a vortex's differential rotation shears pebbles into rings,
  // a source inflates them and a sink squeezes them into spokes, and 7×7 neighbourhoods
  // cannot see that a smooth patch is too large or a ring too long. So the deformation of
  // the carried texture is tracked: per pixel the 2×2 Jacobian F of the map from where the
  // texture was formed to where it is now, carried with the texture (bilinear) and
  // multiplied each frame by exp(∇v·dt) (to second order). Its singular values σ1 ≥ σ2 say
  // how far elements were stretched and squeezed, whatever the rotation (a rigid turn has
  // σ1 = σ2 = 1). Where, over a cell of `cell` pixels, at least a quarter of the pixels
  // have σ1 > k or σ2 < 1/k (k = max_distortion), the cell starts renewing: each of its
  // pixels gets fresh exemplar content — the exemplar laid flat over the cell with its x
  // axis along the field at the cell's centre, placed where it best continues the texture
  // round the cell — a coherent piece of real texture, not noise — and the temporal target
  // moves from the carried texture to the fresh one over renew_frames frames (fewer where
  // the flow strains fast) while both move with the flow: each pixel fades over about a
  // third of that, at a time set by a smooth noise, so that only blobs of a cell are half-way
  // at any time (a cross-fade of two textures is a grey mush), and with a lowered temporal
  // weight, so that the optimization turns mix and seams into texture. At the end the
  // pixel's F is the fresh layer's, which started at I. Nothing switches in one frame, so
  // renewing cells do not flash. Texture that flows in across the picture's edge (a smear
  // of the edge) counts as deformed.
  struct Renewal {
    std::vector<float> F;        // 4 per pixel, row-major: deformation of the carried texture
    std::vector<float> fresh_F;  // 4 per pixel: deformation of the fresh layer (renewing pixels)
    std::vector<float> uv;       // 2 per pixel: exemplar position of the fresh layer
    std::vector<float> map;      // 4 per pixel: image offset → exemplar offset when it started
    std::vector<int> age;        // frames since renewal started; −1: not renewing
    std::vector<float> phase;    // frame of the renewal at which the pixel's own fade begins
    std::vector<int> length;     // frames of the pixel's renewal
  } renewal;
  std::vector<float> renew_weight;  // per pixel: factor of the temporal weight this frame
  static constexpr int kPlacements = 24;
  static constexpr float kFadeWeight = 0.25f;
  std::uint64_t frame_count = 0;
  double started_fraction = 0, renewing_fraction = 0, distortion90 = 1;

  static void singular_values(const float* F, double& s1, double& s2) {
    const double e = 0.5 * (F[0] + F[3]), f = 0.5 * (F[0] - F[3]), g = 0.5 * (F[2] + F[1]), h = 0.5 * (F[2] - F[1]);
    const double q = std::hypot(e, h), r = std::hypot(f, g);
    s1 = q + r;
    s2 = std::abs(q - r);
  }

  // Where each finest pixel's texture was one frame ago (pixel-index coordinates): the
  // backward semi-Lagrangian trace by the midpoint rule.
  std::vector<float> backtrace(const Level& L, double dt) const {
    std::vector<float> q(2 * static_cast<size_t>(L.w) * static_cast<size_t>(L.h));
    tbb::parallel_for(tbb::blocked_range<int>(0, L.h), [&](const tbb::blocked_range<int>& rows) {
      for (int j = rows.begin(); j < rows.end(); ++j)
        for (int i = 0; i < L.w; ++i) {
          const size_t k = static_cast<size_t>(j) * static_cast<size_t>(L.w) + static_cast<size_t>(i);
          const double mx = i - 0.5 * L.vel[2 * k] * dt, my = j - 0.5 * L.vel[2 * k + 1] * dt;
          q[2 * k] = static_cast<float>(i - bilinear(L.vel, L.w, L.h, 2, 0, mx, my) * dt);
          q[2 * k + 1] = static_cast<float>(j - bilinear(L.vel, L.w, L.h, 2, 1, mx, my) * dt);
        }
    });
    return q;
  }

  // g (nc values per pixel) read at the traced positions, bilinearly.
  std::vector<float> resample(const Level& L, const std::vector<float>& g, const std::vector<float>& q, int nc) const {
    std::vector<float> out(g.size());
    tbb::parallel_for(tbb::blocked_range<int>(0, L.h), [&](const tbb::blocked_range<int>& rows) {
      for (int j = rows.begin(); j < rows.end(); ++j)
        for (int i = 0; i < L.w; ++i) {
          const size_t k = static_cast<size_t>(j) * static_cast<size_t>(L.w) + static_cast<size_t>(i);
          for (int c = 0; c < nc; ++c)
            out[k * static_cast<size_t>(nc) + static_cast<size_t>(c)] = bilinear(g, L.w, L.h, nc, c, q[2 * k], q[2 * k + 1]);
        }
    });
    return out;
  }

  // The exemplar (finest level) at a real position, wrapping round a tileable one and
  // mirrored at the edges of another.
  float exemplar_value(double u, double v, int c) const {
    const Exemplar& e = exemplars[0];
    auto index = [&](long a, int n) {
      if (e.tileable) return static_cast<int>(((a % n) + n) % n);
      const long period = 2L * n;
      long m = ((a % period) + period) % period;
      return static_cast<int>(m < n ? m : period - 1 - m);
    };
    const double fu = std::floor(u), fv = std::floor(v);
    const double au = u - fu, av = v - fv;
    const long iu = static_cast<long>(fu), iv = static_cast<long>(fv);
    const int x0 = index(iu, e.width), x1 = index(iu + 1, e.width), y0 = index(iv, e.height), y1 = index(iv + 1, e.height);
    return static_cast<float>((1 - au) * (1 - av) * e.at(x0, y0, c) + au * (1 - av) * e.at(x1, y0, c) +
                              (1 - au) * av * e.at(x0, y1, c) + au * av * e.at(x1, y1, c));
  }

  // Carries the renewal state to the new frame, starts renewing the cells that are too
  // deformed, and blends the fresh layer into `advected` (the temporal target).
  void renew_deformed(const Level& L, const std::vector<float>& q, std::vector<float>& advected, double dt) {
    const size_t n = static_cast<size_t>(L.w) * static_cast<size_t>(L.h);
    Renewal& R = renewal;
    if (R.age.size() != n) {
      R.F.assign(4 * n, 0.f);
      for (size_t k = 0; k < n; ++k) R.F[4 * k] = R.F[4 * k + 3] = 1.f;
      R.fresh_F = R.F;
      R.uv.assign(2 * n, 0.f);
      R.map.assign(4 * n, 0.f);
      R.age.assign(n, -1);
      R.phase.assign(n, 0.f);
      R.length.assign(n, 1);
    }
    ++frame_count;
    const bool active = o.max_distortion > 0;
    // Carry: F and fresh F bilinearly (then times exp(∇v dt)); the fresh layer's exemplar
    // position, map and age from the nearest pixel (they jump between cells), the position
    // moved on by the map over the sub-pixel offset.
    std::vector<float> F = resample(L, R.F, q, 4), fresh_F = resample(L, R.fresh_F, q, 4);
    std::vector<float> uv(2 * n), map(4 * n);
    std::vector<int> age(n);
    std::vector<float> phase(n), strain(n);
    std::vector<int> length(n);
    std::vector<char> inflow(n, 0);
    tbb::parallel_for(tbb::blocked_range<int>(0, L.h), [&](const tbb::blocked_range<int>& rows) {
      auto vel = [&](int a, int b, int c) {
        return L.vel[2 * (static_cast<size_t>(std::clamp(b, 0, L.h - 1)) * static_cast<size_t>(L.w) +
                          static_cast<size_t>(std::clamp(a, 0, L.w - 1))) + static_cast<size_t>(c)];
      };
      for (int j = rows.begin(); j < rows.end(); ++j)
        for (int i = 0; i < L.w; ++i) {
          const size_t k = static_cast<size_t>(j) * static_cast<size_t>(L.w) + static_cast<size_t>(i);
          // Velocity gradient (central differences, one-sided at the edges), times dt.
          const int il = std::max(i - 1, 0), ir = std::min(i + 1, L.w - 1), jl = std::max(j - 1, 0), jr = std::min(j + 1, L.h - 1);
          const double di = std::max(1, ir - il), dj = std::max(1, jr - jl);
          const double g00 = (vel(ir, j, 0) - vel(il, j, 0)) / di * dt, g01 = (vel(i, jr, 0) - vel(i, jl, 0)) / dj * dt;
          const double g10 = (vel(ir, j, 1) - vel(il, j, 1)) / di * dt, g11 = (vel(i, jr, 1) - vel(i, jl, 1)) / dj * dt;
          // M = I + G + G²/2.
          const double m00 = 1 + g00 + 0.5 * (g00 * g00 + g01 * g10), m01 = g01 + 0.5 * (g00 * g01 + g01 * g11);
          const double m10 = g10 + 0.5 * (g10 * g00 + g11 * g10), m11 = 1 + g11 + 0.5 * (g10 * g01 + g11 * g11);
          // Strain per frame: the largest |eigenvalue| of G's symmetric part.
          strain[k] = static_cast<float>(std::hypot(0.5 * (g00 - g11), 0.5 * (g01 + g10)) + std::abs(0.5 * (g00 + g11)));
          for (std::vector<float>* G : {&F, &fresh_F}) {
            float* a = G->data() + 4 * k;
            const double a0 = a[0], a1 = a[1], a2 = a[2], a3 = a[3];
            a[0] = static_cast<float>(m00 * a0 + m01 * a2);
            a[1] = static_cast<float>(m00 * a1 + m01 * a3);
            a[2] = static_cast<float>(m10 * a0 + m11 * a2);
            a[3] = static_cast<float>(m10 * a1 + m11 * a3);
          }
          // Texture that comes in across the edge of the picture is a smear of the edge:
          // it counts as deformed.
          inflow[k] = q[2 * k] < -0.5f || q[2 * k] > static_cast<float>(L.w) - 0.5f || q[2 * k + 1] < -0.5f ||
                      q[2 * k + 1] > static_cast<float>(L.h) - 0.5f;
          const int ni = std::clamp(static_cast<int>(std::lround(q[2 * k])), 0, L.w - 1);
          const int nj = std::clamp(static_cast<int>(std::lround(q[2 * k + 1])), 0, L.h - 1);
          const size_t s = static_cast<size_t>(nj) * static_cast<size_t>(L.w) + static_cast<size_t>(ni);
          age[k] = R.age[s] >= 0 ? R.age[s] + 1 : -1;
          phase[k] = R.phase[s];
          length[k] = R.length[s];
          const float* A = R.map.data() + 4 * s;
          const double ox = q[2 * k] - ni, oy = q[2 * k + 1] - nj;
          uv[2 * k] = static_cast<float>(R.uv[2 * s] + A[0] * ox + A[1] * oy);
          uv[2 * k + 1] = static_cast<float>(R.uv[2 * s + 1] + A[2] * ox + A[3] * oy);
          for (size_t c = 0; c < 4; ++c) map[4 * k + c] = A[c];
        }
    });
    // Each pixel of a renewing cell fades over `fade` frames, starting at its phase: a smooth
    // noise (lattice `blob` pixels, about an element) over [0, frames − fade], so that at any
    // time only parts of a cell are half-way (a cross-fade of two textures is a grey mush)
    // and the rest is one texture or the other.
    // A renewal lasts renew_frames, or less where the flow strains fast: at most half the
    // frames the flow needs to deform fresh texture past the limit (log k / strain), so
    // that the fresh layer is not itself worn out by the time it has faded in.
    auto fade_of = [](int frames) { return std::max(1, static_cast<int>(std::lround(0.35 * frames))); };
    const double blob = std::max(3, o.neighbourhood);
    auto lattice = [&](long a, long b) {
      std::uint64_t h = o.seed * 0x9e3779b97f4a7c15ULL ^ (frame_count * 0xbf58476d1ce4e5b9ULL) ^
                        (static_cast<std::uint64_t>(a) * 0x94d049bb133111ebULL) ^ (static_cast<std::uint64_t>(b) << 29);
      h ^= h >> 31;
      h *= 0xd6e8feb86659fd93ULL;
      h ^= h >> 32;
      return static_cast<double>(h >> 11) * 0x1.0p-53;
    };
    auto noise = [&](double x, double y) {
      const double fx = std::floor(x / blob), fy = std::floor(y / blob);
      double ax = x / blob - fx, ay = y / blob - fy;
      ax = ax * ax * (3 - 2 * ax), ay = ay * ay * (3 - 2 * ay);
      const long ix = static_cast<long>(fx), iy = static_cast<long>(fy);
      const double m = (1 - ax) * (1 - ay) * lattice(ix, iy) + ax * (1 - ay) * lattice(ix + 1, iy) +
                       (1 - ax) * ay * lattice(ix, iy + 1) + ax * ay * lattice(ix + 1, iy + 1);
      return std::clamp(0.5 + 1.8 * (m - 0.5), 0.0, 1.0);  // the bilinear mix bunches near ½
    };
    // Start renewing the cells that are too deformed.
    const int cell = std::max(8, 3 * o.neighbourhood);
    const int cx = (L.w + cell - 1) / cell, cy = (L.h + cell - 1) / cell;
    const double k_max = o.max_distortion;
    std::atomic<size_t> started_count{0};
    tbb::parallel_for(tbb::blocked_range<int>(0, cx * cy), [&](const tbb::blocked_range<int>& cells) {
      for (int id = cells.begin(); id < cells.end(); ++id) {
        const int i0 = (id % cx) * cell, j0 = (id / cx) * cell;
        const int i1 = std::min(L.w, i0 + cell), j1 = std::min(L.h, j0 + cell);
        int candidates = 0, deformed = 0;
        for (int j = j0; j < j1; ++j)
          for (int i = i0; i < i1; ++i) {
            const size_t k = static_cast<size_t>(j) * static_cast<size_t>(L.w) + static_cast<size_t>(i);
            if (L.face[k] < 0 || age[k] >= 0) continue;
            double s1 = 1, s2 = 1;
            singular_values(F.data() + 4 * k, s1, s2);
            ++candidates;
            if (inflow[k] || s1 > k_max || s2 < 1 / k_max) ++deformed;
          }
        if (!active || candidates == 0 || 4 * deformed < candidates) continue;
        // The exemplar laid over the cell: x along the field at its centre.
        const int ci = (i0 + i1) / 2, cj = (j0 + j1) / 2;
        const size_t kc = static_cast<size_t>(cj) * static_cast<size_t>(L.w) + static_cast<size_t>(ci);
        double ux = L.dir[2 * kc], uy = L.dir[2 * kc + 1];
        if (ux == 0 && uy == 0) ux = 1;
        const double vx = -uy, vy = ux;
        // Of a few random placements, the one that best continues the texture round the
        // cell (the carried values on its outer two rows and columns): the seam with the
        // cells that are not renewing is then mostly hidden, as in image quilting.
        std::mt19937_64 rng(o.seed ^ (0x9e3779b97f4a7c15ULL * (frame_count + 1)) ^ (static_cast<std::uint64_t>(id) << 32));
        std::uniform_real_distribution<double> offset(0, std::max(exemplars[0].width, exemplars[0].height));
        double ou = 0, ov = 0, best = std::numeric_limits<double>::max();
        for (int trial = 0; trial < kPlacements; ++trial) {
          const double tu = offset(rng), tv = offset(rng);
          double d = 0;
          for (int j = j0; j < j1; ++j)
            for (int i = i0; i < i1; ++i) {
              if (j >= j0 + 2 && j < j1 - 2 && i >= i0 + 2 && i < i1 - 2) continue;
              const size_t k = static_cast<size_t>(j) * static_cast<size_t>(L.w) + static_cast<size_t>(i);
              if (L.face[k] < 0) continue;
              const double dx = i - ci, dy = j - cj;
              for (int c = 0; c < C; ++c) {
                const double e = exemplar_value(tu + dx * ux + dy * uy, tv + dx * vx + dy * vy, c) -
                                 advected[k * static_cast<size_t>(C) + static_cast<size_t>(c)];
                d += e * e;
              }
            }
          if (d < best) best = d, ou = tu, ov = tv;
        }
        double cell_strain = 0;
        int strained = 0;
        for (int j = j0; j < j1; ++j)
          for (int i = i0; i < i1; ++i) {
            const size_t k = static_cast<size_t>(j) * static_cast<size_t>(L.w) + static_cast<size_t>(i);
            if (L.face[k] >= 0) cell_strain += strain[k], ++strained;
          }
        cell_strain /= std::max(1, strained);
        const double allowed = 0.5 * std::log(k_max) / std::max(cell_strain, 1e-9);
        const int frames = static_cast<int>(std::clamp(allowed, 1.0, static_cast<double>(o.renew_frames)));
        const int fade = fade_of(frames);
        size_t local = 0;
        for (int j = j0; j < j1; ++j)
          for (int i = i0; i < i1; ++i) {
            const size_t k = static_cast<size_t>(j) * static_cast<size_t>(L.w) + static_cast<size_t>(i);
            if (L.face[k] < 0 || age[k] >= 0) continue;
            age[k] = 0;
            length[k] = frames;
            phase[k] = static_cast<float>(noise(i, j) * (frames - fade));
            const double dx = i - ci, dy = j - cj;
            uv[2 * k] = static_cast<float>(ou + dx * ux + dy * uy);
            uv[2 * k + 1] = static_cast<float>(ov + dx * vx + dy * vy);
            float* A = map.data() + 4 * k;
            A[0] = static_cast<float>(ux), A[1] = static_cast<float>(uy), A[2] = static_cast<float>(vx), A[3] = static_cast<float>(vy);
            float* G = fresh_F.data() + 4 * k;
            G[0] = G[3] = 1.f, G[1] = G[2] = 0.f;
            ++local;
          }
        started_count += local;
      }
    });
    // Cross-fade the renewing pixels' targets; finish those at the end of their fade.
    renew_weight.assign(n, 1.f);
    std::atomic<size_t> renewing{0};
    tbb::parallel_for(tbb::blocked_range<int>(0, L.h), [&](const tbb::blocked_range<int>& rows) {
      size_t local = 0;
      for (int j = rows.begin(); j < rows.end(); ++j)
        for (int i = 0; i < L.w; ++i) {
          const size_t k = static_cast<size_t>(j) * static_cast<size_t>(L.w) + static_cast<size_t>(i);
          if (age[k] < 0) continue;
          ++local;
          // The fresh share of the original texture: s(a) after frame a of the renewal; of
          // what is carried now (fresh share s(a − 1)), (s(a) − s(a − 1))/(1 − s(a − 1)) is
          // replaced. While a pixel fades its temporal weight is lowered (kFadeWeight), so
          // that the optimization is freer to turn the mix and the seams into texture.
          const int frames = length[k], fade = fade_of(frames);
          auto share = [&](int a) { return std::clamp((a + 1 - phase[k]) / static_cast<float>(fade), 0.f, 1.f); };
          const float before = share(age[k] - 1), after = share(age[k]);
          const float beta = before < 1 ? (after - before) / (1 - before) : 0.f;
          if (after > 0 && before < 1) renew_weight[k] = kFadeWeight;
          for (int c = 0; c < C; ++c) {
            float& a = advected[k * static_cast<size_t>(C) + static_cast<size_t>(c)];
            a = (1 - beta) * a + beta * exemplar_value(uv[2 * k], uv[2 * k + 1], c);
          }
          if (age[k] + 1 >= frames) {
            age[k] = -1;
            for (size_t c = 0; c < 4; ++c) F[4 * k + c] = fresh_F[4 * k + c];
          }
        }
      renewing += local;
    });
    R.F = std::move(F);
    R.fresh_F = std::move(fresh_F);
    R.uv = std::move(uv);
    R.map = std::move(map);
    R.age = std::move(age);
    R.phase = std::move(phase);
    R.length = std::move(length);
    started_fraction = static_cast<double>(started_count.load()) / static_cast<double>(n);
    renewing_fraction = static_cast<double>(renewing.load()) / static_cast<double>(n);
    // The 90th percentile of the carried texture's distortion max(σ1, 1/σ2).
    std::vector<float> distortion;
    distortion.reserve(n);
    for (size_t k = 0; k < n; ++k) {
      if (L.face[k] < 0) continue;
      double s1 = 1, s2 = 1;
      singular_values(R.F.data() + 4 * k, s1, s2);
      distortion.push_back(static_cast<float>(std::max(s1, 1 / std::max(s2, 1e-9))));
    }
    if (!distortion.empty()) {
      auto mid = distortion.begin() + static_cast<long>(0.9 * static_cast<double>(distortion.size() - 1));
      std::nth_element(distortion.begin(), mid, distortion.end());
      distortion90 = *mid;
    }
  }

  std::vector<float> downsample_grid(const Level& fine, const std::vector<float>& g, const Level& coarse,
                                     int channels = 0) const {
    const int nc = channels > 0 ? channels : C;
    std::vector<float> out(static_cast<size_t>(coarse.w) * static_cast<size_t>(coarse.h) * static_cast<size_t>(nc));
    for (int j = 0; j < coarse.h; ++j)
      for (int i = 0; i < coarse.w; ++i)
        for (int c = 0; c < nc; ++c) {
          float s = 0;
          for (int dj = 0; dj < 2; ++dj)
            for (int di = 0; di < 2; ++di) {
              const int x = std::min(2 * i + di, fine.w - 1), y = std::min(2 * j + dj, fine.h - 1);
              s += g[(static_cast<size_t>(y) * static_cast<size_t>(fine.w) + static_cast<size_t>(x)) * static_cast<size_t>(nc) + static_cast<size_t>(c)];
            }
          out[(static_cast<size_t>(j) * static_cast<size_t>(coarse.w) + static_cast<size_t>(i)) * static_cast<size_t>(nc) + static_cast<size_t>(c)] = 0.25f * s;
        }
    return out;
  }

  const SynthesisFrameReport& advance(double tt) {
    const auto start = std::chrono::steady_clock::now();
    const std::vector<cplx> values = vertex_values(tt);
    OptimizeOptions opt;
    OptimizeReport last;
    if (!started) {
      opt.iterations = o.iterations_first;
      for (int l = o.levels - 1; l >= 0; --l) {
        Level& L = levels[static_cast<size_t>(l)];
        if (l == o.levels - 1)
          random_exemplar_pixels(exemplars[static_cast<size_t>(l)], L.w * L.h, o.seed, L.x);
        else
          L.x = upsample(levels[static_cast<size_t>(l) + 1], levels[static_cast<size_t>(l) + 1].x, L);
        update_field(L, values);
        build_neighbourhoods(L);
        last = optimize_texture(L.nb, *indices[static_cast<size_t>(l)], L.x, {}, opt, &L.match);
      }
      report.levels = o.levels;
      started = true;
    } else {
      // Carry the last frame along the field (velocities of the new time), then optimize
      // the finest levels against it.
      Level& L0 = levels[0];
      update_field(L0, values);
      const std::vector<float> q = backtrace(L0, tt - t);
      std::vector<float> advected = resample(L0, L0.x, q, C);
      renew_deformed(L0, q, advected, tt - t);
      const int F = o.frame_levels;
      levels[0].target = std::move(advected);
      levels[0].target_weight = renew_weight;
      for (int l = 1; l < F; ++l) {
        Level& fine = levels[static_cast<size_t>(l) - 1];
        Level& coarse = levels[static_cast<size_t>(l)];
        coarse.target = downsample_grid(fine, fine.target, coarse);
        coarse.target_weight = downsample_grid(fine, fine.target_weight, coarse, 1);
      }
      opt.iterations = o.iterations;
      opt.temporal_weight = o.temporal_weight;
      for (int l = F - 1; l >= 0; --l) {
        Level& L = levels[static_cast<size_t>(l)];
        opt.target_weights = L.target_weight;
        if (l == F - 1) {
          L.x = L.target;
        } else {
          const Level& Lc = levels[static_cast<size_t>(l) + 1];
          std::vector<float> change(Lc.x.size());
          for (size_t i = 0; i < change.size(); ++i) change[i] = Lc.x[i] - Lc.target[i];
          L.x = upsample(Lc, change, L);
          for (size_t i = 0; i < L.x.size(); ++i) L.x[i] += L.target[i];
        }
        if (l > 0) update_field(L, values);
        build_neighbourhoods(L);
        last = optimize_texture(L.nb, *indices[static_cast<size_t>(l)], L.x, L.target, opt, &L.match);
      }
      report.levels = F;
      report.reseeded = started_fraction;
      report.renewing = renewing_fraction;
      report.distortion = distortion90;
    }
    t = tt;
    report.patch_distance = last.patch_distance;
    report.uncovered = last.uncovered;
    report.seconds = std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
    return report;
  }
};

PlanarSynthesizer::PlanarSynthesizer(const TangentBundle& bundle, const Field& field, const Exemplar& exemplar,
                                     const SynthesisOptions& options)
    : impl_(std::make_unique<Impl>(bundle, field, exemplar, options)) {}
PlanarSynthesizer::~PlanarSynthesizer() = default;
int PlanarSynthesizer::width() const { return impl_->levels[0].w; }
int PlanarSynthesizer::height() const { return impl_->levels[0].h; }
int PlanarSynthesizer::channels() const { return impl_->C; }
double PlanarSynthesizer::pixels_per_unit() const { return impl_->levels[0].ppu; }
const SynthesisFrameReport& PlanarSynthesizer::advance(double t) { return impl_->advance(t); }
double PlanarSynthesizer::time() const { return impl_->t; }
const std::vector<float>& PlanarSynthesizer::texture() const { return impl_->levels[0].x; }
bool PlanarSynthesizer::inside(int i, int j) const {
  const auto& L = impl_->levels[0];
  return L.face[static_cast<size_t>(j) * static_cast<size_t>(L.w) + static_cast<size_t>(i)] >= 0;
}
std::array<float, 2> PlanarSynthesizer::direction(int i, int j) const {
  const auto& L = impl_->levels[0];
  const size_t k = static_cast<size_t>(j) * static_cast<size_t>(L.w) + static_cast<size_t>(i);
  return {L.dir[2 * k], L.dir[2 * k + 1]};
}

Image PlanarSynthesizer::picture() const {
  const auto& L = impl_->levels[0];
  const int C = impl_->C;
  Image image(L.w, L.h);
  auto byte = [](float v) { return static_cast<std::uint8_t>(std::lround(std::clamp(v, 0.f, 1.f) * 255.f)); };
  for (int j = 0; j < L.h; ++j)
    for (int i = 0; i < L.w; ++i) {
      const size_t k = static_cast<size_t>(j) * static_cast<size_t>(L.w) + static_cast<size_t>(i);
      if (L.face[k] < 0) {
        image.at(i, j) = impl_->o.background;
        continue;
      }
      const float* p = L.x.data() + k * static_cast<size_t>(C);
      image.at(i, j) = C == 1 ? gray(byte(p[0])) : rgb(byte(p[0]), byte(p[1]), byte(p[2]));
    }
  return image;
}

Image hillshade(const std::vector<float>& h, int w, int hp, double relief) {
  TVF_CHECK(h.size() == static_cast<size_t>(w) * static_cast<size_t>(hp), "height field size");
  Image image(w, hp);
  const Vec3 light = Vec3(-1, -1, 1.2).normalized();  // from the north-west (image up-left)
  auto at = [&](int i, int j) {
    return static_cast<double>(h[static_cast<size_t>(std::clamp(j, 0, hp - 1)) * static_cast<size_t>(w) + static_cast<size_t>(std::clamp(i, 0, w - 1))]);
  };
  for (int j = 0; j < hp; ++j)
    for (int i = 0; i < w; ++i) {
      const double dx = 0.5 * (at(i + 1, j) - at(i - 1, j)) * relief;
      const double dy = 0.5 * (at(i, j + 1) - at(i, j - 1)) * relief;
      const Vec3 n = Vec3(-dx, -dy, 1).normalized();
      const double shade = std::clamp(0.25 + 0.75 * n.dot(light), 0.0, 1.0);
      const double e = std::clamp(at(i, j), 0.0, 1.0);
      // Low ground green-brown, high ground light sand.
      const double r = (0.35 + 0.5 * e) * shade, g = (0.33 + 0.4 * e) * shade, b = (0.22 + 0.3 * e) * shade;
      auto byte = [](double v) { return static_cast<std::uint8_t>(std::lround(std::clamp(v, 0.0, 1.0) * 255)); };
      image.at(i, j) = rgb(byte(r), byte(g), byte(b));
    }
  return image;
}

SynthesisAnimationReport write_planar_synthesis(const TangentBundle& bundle, const Field& field,
                                                const Exemplar& exemplar, const SynthesisAnimationOptions& options) {
  const auto start = std::chrono::steady_clock::now();
  if (options.frames_dir.empty() && options.video.empty() && options.meshes_dir.empty())
    throw Error("texture synthesis: give a frames folder, a video or (terrain) a meshes folder to write");
  if (options.frames < 0 || options.frames > 100000)
    throw Error(fmt::format("frames {}: must be in [1, 100000] (or 0: the field's frames)", options.frames));
  if (!options.meshes_dir.empty() && !options.terrain)
    throw Error("meshes per frame are written for terrain (a height-map exemplar) only");
  if (options.terrain && exemplar.channels != 1) throw Error("terrain needs a 1-channel (height) exemplar");
  check_option(std::isfinite(options.relief) && options.relief >= 0, "relief", fmt::format("{} must be at least 0", options.relief));
  check_option(std::isfinite(options.height_scale) && options.height_scale >= 0 && options.height_scale <= 10,
               "height_scale", fmt::format("{} is outside [0, 10]", options.height_scale));
  check_option(options.mesh_resolution >= 2 && options.mesh_resolution <= 4096, "mesh_resolution",
               fmt::format("{} is outside [2, 4096]", options.mesh_resolution));
  PlanarSynthesizer synth(bundle, field, exemplar, options.synthesis);
  const int frames = options.frames > 0 ? options.frames : field.frames();
  const TimeSampling& ts = field.time();
  std::unique_ptr<FrameOutput> out;
  if (!options.frames_dir.empty() || !options.video.empty())
    out = std::make_unique<FrameOutput>(options.frames_dir, options.video, synth.width(), synth.height(), options.fps);
  std::unique_ptr<TerrainMeshWriter> meshes;
  if (!options.meshes_dir.empty()) {
    TerrainMeshOptions mo;
    mo.format = options.mesh_format;
    mo.resolution = options.mesh_resolution;
    mo.height_scale = options.height_scale;
    meshes = std::make_unique<TerrainMeshWriter>(options.meshes_dir, bundle.mesh(), mo);
  }
  SynthesisAnimationReport report;
  report.width = synth.width();
  report.height = synth.height();
  double later = 0, distance = 0;
  const double relief = options.relief > 0 ? options.relief : synth.width() / 8.0;
  for (int k = 0; k < frames; ++k) {
    const double t = frames > 1 ? ts.t0 + (ts.t1 - ts.t0) * k / (frames - 1) : ts.t0;
    const SynthesisFrameReport& fr = synth.advance(t);
    if (k == 0) report.first_frame_seconds = fr.seconds; else later += fr.seconds;
    distance += fr.patch_distance;
    if (out) out->add(options.terrain ? hillshade(synth.texture(), synth.width(), synth.height(), relief) : synth.picture());
    if (meshes) meshes->add_grid(synth.texture(), synth.width(), synth.height());
    if (options.progress) options.progress(k + 1, frames);
  }
  if (out) report.files = out->finish();
  if (meshes) {
    meshes->finish();
    report.files.push_back(options.meshes_dir);
  }
  report.frames = frames;
  report.mean_frame_seconds = frames > 1 ? later / (frames - 1) : report.first_frame_seconds;
  report.mean_patch_distance = distance / frames;
  report.seconds = std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
  return report;
}

}  // namespace tvf
