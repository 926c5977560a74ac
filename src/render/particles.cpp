#include "tvf/render/particles.h"

#include "planar_view.h"

#include "tvf/core/error.h"
#include "tvf/integrate/pathline.h"
#include "tvf/render/dye_pictures.h"
#include "tvf/render/frame_output.h"
#include "tvf/render/surface_particles.h"

#include <cairo.h>
#include <fmt/format.h>
#include <tbb/parallel_for.h>

#include <algorithm>
#include <optional>
#include <chrono>
#include <cmath>
#include <random>

namespace tvf {

namespace {

void check_option(bool ok, const std::string& name, const std::string& what) {
  if (!ok) throw Error(fmt::format("particle option {}: {}", name, what));
}

constexpr std::uint32_t kLeafColours[] = {0x00C8501E, 0x00E0A020, 0x00A0281E, 0x00D27828, 0x008C5A1E, 0x00B4B428};

}  // namespace

struct ParticleSystem::Impl {
  const TangentBundle& bundle;
  const Field& field;
  ParticleOptions o;
  detail::PlanarView view;
  detail::PlanarLocator locator;
  FieldSampler sampler;
  std::vector<Particle> particles;
  std::mt19937_64 rng;
  double zero_speed = 0;
  double t = 0;
  bool started = false;
  long next_id = 0, respawned = 0;

  Impl(const TangentBundle& b, const Field& f, const ParticleOptions& opt)
      : bundle(b), field(f), o(opt), view(detail::PlanarView::fit(b.mesh(), opt.image_size)), locator(b.mesh()),
        sampler(b, f), rng(opt.seed) {
    double top = 0;
    for (const cplx& v : f.data()) top = std::max(top, std::abs(v));
    zero_speed = 1e-12 * top;
  }

  // up = R(angle)·V/|V| at the particle's place and time t; unchanged where V vanishes.
  void orient(Particle& p, double time) const {
    const Vec3 v = sampler.world(p.where, time);
    const double n = v.head<2>().norm();
    if (!(n > zero_speed)) return;
    const Vec2 d = v.head<2>() / n;
    const double c = std::cos(p.angle), s = std::sin(p.angle);
    p.up = Vec2(c * d.x() - s * d.y(), s * d.x() + c * d.y());
  }

  // A new particle at a random place of the box [lo, hi] inside the domain.
  Particle spawn(double time, const Vec2& lo, const Vec2& hi) {
    std::uniform_real_distribution<double> u(0.0, 1.0);
    Particle p;
    p.id = next_id++;
    for (int attempt = 0; attempt < 1000; ++attempt) {
      const Vec2 x(lo.x() + u(rng) * (hi.x() - lo.x()), lo.y() + u(rng) * (hi.y() - lo.y()));
      if (const auto sp = locator.locate(x)) {
        p.where = *sp;
        p.position = x;
        break;
      }
      if (attempt == 999) {
        if (lo != view.lo || hi != view.hi) return spawn(time, view.lo, view.hi);
        throw Error("particles: found no place inside the domain");
      }
    }
    p.angle = std::isnan(o.spin) ? 2 * kPi * u(rng) : o.spin;
    p.colour = kLeafColours[std::uniform_int_distribution<size_t>(0, std::size(kLeafColours) - 1)(rng)];
    const double a = 2 * kPi * u(rng);
    p.up = Vec2(std::cos(a), std::sin(a));
    orient(p, time);
    return p;
  }

  void advance(double t_new) {
    const TimeSampling& ts = field.time();
    check_option(std::isfinite(t_new) && t_new >= std::min(ts.t0, ts.t1) && t_new <= std::max(ts.t0, ts.t1), "time",
                 fmt::format("{} is outside the field's time range", t_new));
    if (!started) {
      for (int k = 0; k < o.count; ++k) particles.push_back(spawn(t_new, view.lo, view.hi));
    } else if (t_new != t) {
      std::vector<char> lost(particles.size(), 0);
      tbb::parallel_for(size_t{0}, particles.size(), [&](size_t k) {
        Particle& p = particles[k];
        PathlineOptions po;
        po.t_start = t;
        po.t_end = t_new;
        po.stop_at_singular_faces = false;
        po.stop_speed = 0;
        const Pathline line = trace_pathline(bundle, field, p.where, po);
        if (line.stop == StopReason::boundary) lost[k] = 1;
        if (line.where.empty()) return;
        p.where = line.where.back();
        p.position = line.points.back().head<2>();
        orient(p, t_new);
      });
      // Lost particles come back where the particles are sparsest: in a random one of the
      // least occupied cells of a coarse grid (about 8 particles a cell), so that the
      // picture stays evenly covered where the flow spreads them out.
      const int cells = std::max(1, static_cast<int>(std::sqrt(o.count / 8.0)));
      const int cx = cells, cy = std::max(1, static_cast<int>(std::lround(cells * (view.hi.y() - view.lo.y()) /
                                                                            (view.hi.x() - view.lo.x()))));
      const Vec2 csize((view.hi.x() - view.lo.x()) / cx, (view.hi.y() - view.lo.y()) / cy);
      std::vector<int> count(static_cast<size_t>(cx * cy), 0);
      auto cell_of = [&](const Vec2& x) {
        const int i = std::clamp(static_cast<int>((x.x() - view.lo.x()) / csize.x()), 0, cx - 1);
        const int j = std::clamp(static_cast<int>((x.y() - view.lo.y()) / csize.y()), 0, cy - 1);
        return static_cast<size_t>(j * cx + i);
      };
      for (size_t k = 0; k < particles.size(); ++k)
        if (!lost[k]) ++count[cell_of(particles[k].position)];
      for (size_t k = 0; k < particles.size(); ++k)
        if (lost[k]) {
          const int least = *std::min_element(count.begin(), count.end());
          std::vector<size_t> candidates;
          for (size_t c = 0; c < count.size(); ++c)
            if (count[c] == least) candidates.push_back(c);
          const size_t c = candidates[std::uniform_int_distribution<size_t>(0, candidates.size() - 1)(rng)];
          const Vec2 lo = view.lo + Vec2(static_cast<double>(c % static_cast<size_t>(cx)) * csize.x(),
                                         static_cast<double>(c / static_cast<size_t>(cx)) * csize.y());
          particles[k] = spawn(t_new, lo, lo + csize);
          ++count[cell_of(particles[k].position)];
          ++respawned;
        }
    }
    t = t_new;
    started = true;
  }

  Image picture() const {
    Image image(view.width, view.height);
    std::fill(image.pixels.begin(), image.pixels.end(), o.background);
    cairo_surface_t* surface = cairo_image_surface_create_for_data(
        reinterpret_cast<unsigned char*>(image.pixels.data()), CAIRO_FORMAT_RGB24, image.width, image.height,
        image.width * 4);
    cairo_t* cr = cairo_create(surface);
    const double L = o.size;
    for (const Particle& p : particles) {
      const Vec2 c = view.to_pixel(p.position);
      const Vec2 u = view.vector_to_pixel(p.up);
      auto rgb = [&](std::uint32_t col, double f) {
        cairo_set_source_rgb(cr, std::min(1.0, f * ((col >> 16) & 255) / 255.0),
                             std::min(1.0, f * ((col >> 8) & 255) / 255.0), std::min(1.0, f * (col & 255) / 255.0));
      };
      cairo_save(cr);
      cairo_translate(cr, c.x(), c.y());
      cairo_rotate(cr, std::atan2(u.y(), u.x()));
      // A leaf along +x (its up direction): two curved sides meeting at the tip and at the
      // stem, a midrib and a short stem.
      cairo_new_path(cr);
      cairo_move_to(cr, -0.5 * L, 0);
      cairo_curve_to(cr, -0.25 * L, -0.38 * L, 0.3 * L, -0.3 * L, 0.5 * L, 0);
      cairo_curve_to(cr, 0.3 * L, 0.3 * L, -0.25 * L, 0.38 * L, -0.5 * L, 0);
      cairo_close_path(cr);
      rgb(p.colour, 1.0);
      cairo_fill_preserve(cr);
      cairo_set_line_width(cr, std::max(0.5, 0.06 * L));
      rgb(p.colour, 0.6);
      cairo_stroke(cr);
      cairo_move_to(cr, -0.65 * L, 0);
      cairo_line_to(cr, 0.4 * L, 0);
      cairo_stroke(cr);
      cairo_restore(cr);
    }
    cairo_destroy(cr);
    cairo_surface_flush(surface);
    cairo_surface_destroy(surface);
    return image;
  }
};

ParticleSystem::ParticleSystem(const TangentBundle& bundle, const Field& field, const ParticleOptions& o) {
  detail::require_planar(bundle, "particles");
  check_option(o.count >= 1 && o.count <= 10'000'000, "count", fmt::format("{} is outside [1, 10000000]", o.count));
  check_option(std::isfinite(o.size) && o.size > 0 && o.size <= 1000, "size",
               fmt::format("{} pixels is outside (0, 1000]", o.size));
  check_option(std::isnan(o.spin) || std::isfinite(o.spin), "spin", "must be a finite angle");
  check_option(o.image_size >= 16 && o.image_size <= 16384, "image size",
               fmt::format("{} pixels is outside [16, 16384]", o.image_size));
  if (field.num_vertices() != bundle.mesh().num_vertices() || field.frames() < 1)
    throw Error("particles: the field does not belong to this domain");
  impl_ = std::make_unique<Impl>(bundle, field, o);
}

ParticleSystem::~ParticleSystem() = default;
void ParticleSystem::advance(double t) { impl_->advance(t); }
double ParticleSystem::time() const { return impl_->t; }
const std::vector<Particle>& ParticleSystem::particles() const { return impl_->particles; }
long ParticleSystem::respawned() const { return impl_->respawned; }
int ParticleSystem::width() const { return impl_->view.width; }
int ParticleSystem::height() const { return impl_->view.height; }
Image ParticleSystem::picture() const { return impl_->picture(); }

std::optional<DyeInjector> particle_dye(const TangentBundle& bundle, const Field& carried,
                                        const ParticleAnimationOptions& options, int pictures) {
  std::optional<DyeInjector> dye;
  if (options.dye_seeds.empty() && options.timelines.empty()) return dye;
  const TimeSampling& ts = carried.time();
  DyeOptions o;
  o.timelines = options.timelines;
  o.release_spacing = options.dye_release_spacing != 0.0 ? options.dye_release_spacing
                      : pictures > 1                     ? 0.25 * (ts.t1 - ts.t0) / (pictures - 1)
                                                         : 0.0;
  dye.emplace(bundle, carried, options.dye_seeds, ts.t0, o);
  return dye;
}

AnimationReport write_particle_animation(const TangentBundle& bundle, const Field& field,
                                         const ParticleAnimationOptions& options) {
  if (!bundle.is_flat()) return write_surface_particle_animation(bundle, field, options);
  const auto start = std::chrono::steady_clock::now();
  const int total = options.frames > 0 ? options.frames : field.frames();
  check_option(total >= 1 && total <= 1'000'000, "frames", fmt::format("{} is outside [1, 1000000]", total));
  check_option(std::isfinite(options.time_scale) && options.time_scale > 0, "time scale",
               fmt::format("{} is not a positive number", options.time_scale));
  // The time scale multiplies the velocities: pathlines of s·V over the time range are those
  // of V over s times it, with the field changing at its own pace.
  std::optional<Field> scaled;
  if (options.time_scale != 1.0) {
    scaled.emplace(field);
    for (cplx& z : scaled->data()) z *= options.time_scale;
  }
  ParticleSystem system(bundle, scaled ? *scaled : field, options.particles);
  std::optional<DyeInjector> dye = particle_dye(bundle, scaled ? *scaled : field, options, total);
  const detail::PlanarView view = detail::PlanarView::fit(bundle.mesh(), options.particles.image_size);
  const TimeSampling& ts = field.time();
  DyeStyle style;
  style.width = std::max(2.0, options.particles.image_size / 300.0);
  style.fade = 0.7;
  style.fade_age = ts.t1 > ts.t0 ? ts.t1 - ts.t0 : 1.0;
  style.halo = true;
  style.max_gap = 24.0 / std::min(view.sx(), view.sy());  // 24 pixels
  FrameOutput out(options.frames_dir, options.video, system.width(), system.height(), options.fps);
  for (int k = 0; k < total; ++k) {
    const double t = total > 1 ? ts.t0 + (ts.t1 - ts.t0) * k / (total - 1) : ts.t0;
    system.advance(t);
    Image picture = system.picture();
    if (dye) {
      dye->advance(t);
      draw_dye(picture, *dye, [&](const Vec2& x) { return view.to_pixel(x); }, style);
    }
    out.add(picture);
    if (options.progress) options.progress(k + 1, total);
  }
  AnimationReport report;
  report.files = out.finish();
  report.frames = total;
  if (dye) report.timelines = dye->timeline_records();
  report.width = system.width();
  report.height = system.height();
  report.seconds = std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
  return report;
}

}  // namespace tvf
