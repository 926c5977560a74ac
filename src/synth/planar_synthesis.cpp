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

  // Area stretch of the carried texture (Kwatra et al. 2007 keep it in check by the
  // optimization alone; with few iterations per frame a source inflates pebbles into flat
  // blobs and a sink squeezes them into spokes, which the local neighbourhoods cannot see).
  // `stretch` is the area factor each pixel's texture has gone through since it was
  // synthesized: carried with the texture and multiplied by exp(div v · dt). Where it
  // leaves [1/s_p, s_p] — s_p a fixed random threshold per pixel in [1.6, 2.6], so that a
  // region is not re-seeded all at once — the carried value is replaced by a random
  // exemplar pixel and the pixel's temporal weight set to 0 for this frame (the
  // optimization then synthesizes it afresh), and its stretch starts again at 1.
  std::vector<float> stretch, stretch_limit, reseeded_weight;
  std::uint64_t frame_count = 0;
  double reseeded_fraction = 0;

  void reseed_stretched(const Level& L, std::vector<float>& advected, double dt) {
    const size_t n = static_cast<size_t>(L.w) * static_cast<size_t>(L.h);
    if (stretch.size() != n) {
      stretch.assign(n, 1.f);
      stretch_limit.resize(n);
      std::mt19937_64 rng(o.seed ^ 0x9e3779b97f4a7c15ULL);
      std::uniform_real_distribution<float> u(1.6f, 2.6f);
      for (auto& v : stretch_limit) v = u(rng);
    }
    std::vector<float> carried = advect(L, stretch, dt, 1);
    reseeded_weight.assign(n, 1.f);
    std::vector<float> fresh;
    random_exemplar_pixels(exemplars[0], static_cast<int>(n), o.seed + ++frame_count, fresh);
    std::atomic<size_t> reseeded{0};
    tbb::parallel_for(tbb::blocked_range<int>(0, L.h), [&](const tbb::blocked_range<int>& rows) {
      size_t local = 0;
      for (int j = rows.begin(); j < rows.end(); ++j)
        for (int i = 0; i < L.w; ++i) {
          const size_t k = static_cast<size_t>(j) * static_cast<size_t>(L.w) + static_cast<size_t>(i);
          auto vel = [&](int a, int b, int c) {
            return L.vel[2 * (static_cast<size_t>(std::clamp(b, 0, L.h - 1)) * static_cast<size_t>(L.w) +
                              static_cast<size_t>(std::clamp(a, 0, L.w - 1))) + static_cast<size_t>(c)];
          };
          const double div = 0.5 * (vel(i + 1, j, 0) - vel(i - 1, j, 0)) + 0.5 * (vel(i, j + 1, 1) - vel(i, j - 1, 1));
          float s = carried[k] * static_cast<float>(std::exp(std::clamp(div * dt, -1.0, 1.0)));
          const float limit = stretch_limit[k];
          if (L.face[k] >= 0 && (s > limit || s < 1.f / limit)) {
            for (int c = 0; c < C; ++c)
              advected[k * static_cast<size_t>(C) + static_cast<size_t>(c)] = fresh[k * static_cast<size_t>(C) + static_cast<size_t>(c)];
            reseeded_weight[k] = 0.f;
            s = 1.f;
            ++local;
          }
          stretch[k] = s;
        }
      reseeded += local;
    });
    reseeded_fraction = static_cast<double>(reseeded.load()) / static_cast<double>(n);
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

  // The finest level advected from time t0 to t1 (backward semi-Lagrangian, midpoint rule).
  std::vector<float> advect(const Level& L, const std::vector<float>& g, double dt, int channels = 0) const {
    const int nc = channels > 0 ? channels : C;
    std::vector<float> out(g.size());
    tbb::parallel_for(tbb::blocked_range<int>(0, L.h), [&](const tbb::blocked_range<int>& rows) {
      for (int j = rows.begin(); j < rows.end(); ++j)
        for (int i = 0; i < L.w; ++i) {
          const size_t k = static_cast<size_t>(j) * static_cast<size_t>(L.w) + static_cast<size_t>(i);
          const double v1x = L.vel[2 * k] * dt, v1y = L.vel[2 * k + 1] * dt;
          const double mx = i - 0.5 * v1x, my = j - 0.5 * v1y;
          const double v2x = bilinear(L.vel, L.w, L.h, 2, 0, mx, my) * dt;
          const double v2y = bilinear(L.vel, L.w, L.h, 2, 1, mx, my) * dt;
          for (int c = 0; c < nc; ++c) out[k * static_cast<size_t>(nc) + static_cast<size_t>(c)] = bilinear(g, L.w, L.h, nc, c, i - v2x, j - v2y);
        }
    });
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
      std::vector<float> advected = advect(L0, L0.x, tt - t);
      reseed_stretched(L0, advected, tt - t);
      const int F = o.frame_levels;
      levels[0].target = std::move(advected);
      levels[0].target_weight = reseeded_weight;
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
      report.reseeded = reseeded_fraction;
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
