#include "tvf/render/surface_particles.h"

#include "tvf/core/error.h"
#include "tvf/integrate/pathline.h"
#include "tvf/render/dye_pictures.h"
#include "tvf/render/frame_output.h"

#include <fmt/format.h>
#include <tbb/parallel_for.h>

#include <algorithm>
#include <chrono>
#include <cmath>
#include <optional>

namespace tvf {

namespace {

void check_option(bool ok, const std::string& name, const std::string& what) {
  if (!ok) throw Error(fmt::format("particle option {}: {}", name, what));
}

constexpr std::uint32_t kLeafColours[] = {0x00C8501E, 0x00E0A020, 0x00A0281E, 0x00D27828, 0x008C5A1E, 0x00B4B428};

}  // namespace

SurfaceParticleSystem::SurfaceParticleSystem(const TangentBundle& bundle, const Field& field,
                                             const ParticleOptions& options, const SurfaceView& view)
    : bundle_(bundle), field_(field), o_(options), sampler_(bundle, field), rng_(options.seed) {
  if (bundle.is_flat()) throw Error("surface particles: the domain is planar (ParticleSystem draws planar domains)");
  check_option(o_.count >= 1 && o_.count <= 10'000'000, "count", fmt::format("{} is outside [1, 10000000]", o_.count));
  check_option(std::isfinite(o_.size) && o_.size > 0 && o_.size <= 1000, "size",
               fmt::format("{} pixels is outside (0, 1000]", o_.size));
  check_option(std::isnan(o_.spin) || std::isfinite(o_.spin), "spin", "must be a finite angle");
  check_option(o_.image_size >= 16 && o_.image_size <= 16384, "image size",
               fmt::format("{} pixels is outside [16, 16384]", o_.image_size));
  check_option(view.direction.allFinite() && view.direction.norm() > 0, "view", "the view direction must be a non-zero vector");
  check_option(view.up.allFinite() && view.up.norm() > 0, "up", "the up direction must be a non-zero vector");
  check_option(std::isfinite(view.fov) && view.fov >= 1 && view.fov <= 120, "fov",
               fmt::format("{}° is outside [1, 120]", view.fov));
  const Mesh& mesh = bundle.mesh();
  if (field.num_vertices() != mesh.num_vertices() || field.frames() < 1)
    throw Error("surface particles: the field does not belong to this domain");
  double top = 0;
  for (const cplx& v : field.data()) top = std::max(top, std::abs(v));
  zero_speed_ = 1e-12 * top;
  camera_ = Camera::framing(mesh.positions(), view.direction, view.up, 1.0, view.fov, 1.08);
  ppu_ = 0.5 * o_.image_size / ((camera_.eye - camera_.target).norm() * std::tan(0.5 * view.fov * kPi / 180.0));
  cumulative_area_.resize(static_cast<size_t>(mesh.num_faces()));
  double total = 0;
  for (int f = 0; f < mesh.num_faces(); ++f) cumulative_area_[static_cast<size_t>(f)] = total += mesh.face_area(f);
  if (!(total > 0)) throw Error("surface particles: the mesh has no area to place leaves on");
}

void SurfaceParticleSystem::orient(SurfaceLeaf& leaf, double t) const {
  Vec3 v = sampler_.world(leaf.where, t);
  const Vec3& n = bundle_.face_normal(leaf.where.face);
  v -= v.dot(n) * n;
  const double m = v.norm();
  if (m > zero_speed_) {
    const Vec3 d = v / m;
    leaf.up = std::cos(leaf.angle) * d + std::sin(leaf.angle) * n.cross(d);
  } else {
    // Keep the last up, laid into this face's plane.
    Vec3 u = leaf.up - leaf.up.dot(n) * n;
    leaf.up = u.norm() > 1e-12 ? Vec3(u.normalized()) : Vec3(bundle_.face_e1(leaf.where.face));
  }
}

SurfaceLeaf SurfaceParticleSystem::spawn(double t) {
  std::uniform_real_distribution<double> u(0.0, 1.0);
  SurfaceLeaf leaf;
  leaf.id = next_id_++;
  const double r = u(rng_) * cumulative_area_.back();
  const int f = static_cast<int>(std::min<size_t>(
      static_cast<size_t>(std::lower_bound(cumulative_area_.begin(), cumulative_area_.end(), r) - cumulative_area_.begin()),
      cumulative_area_.size() - 1));
  double a = u(rng_), b = u(rng_);
  if (a + b > 1) a = 1 - a, b = 1 - b;
  leaf.where = SurfacePoint{f, Vec3(1 - a - b, a, b)};
  leaf.position = surface_position(bundle_.mesh(), leaf.where);
  leaf.angle = std::isnan(o_.spin) ? 2 * kPi * u(rng_) : o_.spin;
  leaf.colour = kLeafColours[std::uniform_int_distribution<size_t>(0, std::size(kLeafColours) - 1)(rng_)];
  leaf.up = bundle_.face_e1(f);
  orient(leaf, t);
  return leaf;
}

void SurfaceParticleSystem::advance(double t) {
  const TimeSampling& ts = field_.time();
  check_option(std::isfinite(t) && t >= std::min(ts.t0, ts.t1) && t <= std::max(ts.t0, ts.t1), "time",
               fmt::format("{} is outside the field's time range", t));
  if (!started_) {
    for (int k = 0; k < o_.count; ++k) leaves_.push_back(spawn(t));
  } else if (t != t_) {
    std::vector<char> lost(leaves_.size(), 0);
    tbb::parallel_for(size_t{0}, leaves_.size(), [&](size_t k) {
      SurfaceLeaf& leaf = leaves_[k];
      PathlineOptions po;
      po.t_start = t_;
      po.t_end = t;
      po.stop_at_singular_faces = false;
      po.stop_speed = 0;
      const Pathline line = trace_pathline(bundle_, field_, leaf.where, po);
      if (line.stop == StopReason::boundary) lost[k] = 1;
      if (line.where.empty()) return;
      leaf.where = line.where.back();
      leaf.position = surface_position(bundle_.mesh(), leaf.where);
      orient(leaf, t);
    });
    for (size_t k = 0; k < leaves_.size(); ++k)
      if (lost[k]) {
        leaves_[k] = spawn(t);
        ++respawned_;
      }
  }
  t_ = t;
  started_ = true;
}

std::vector<RenderLine> SurfaceParticleSystem::leaf_lines() const {
  // A leaf along its up direction, L long: three pieces of decreasing width towards the tip
  // (a tapered blade) and a thin dark stem behind it.
  const double L = o_.size / ppu_;
  std::vector<RenderLine> lines;
  lines.reserve(4 * leaves_.size());
  for (const SurfaceLeaf& leaf : leaves_) {
    auto at = [&](double s) { return Vec3(leaf.position + s * L * leaf.up); };
    const std::uint32_t dark = scale_color(leaf.colour, 0.55);
    lines.push_back({{at(-0.62), at(-0.42)}, dark, std::max(1.0, 0.07 * o_.size), false});
    lines.push_back({{at(-0.45), at(-0.2)}, leaf.colour, std::max(1.0, 0.24 * o_.size), false});
    lines.push_back({{at(-0.2), at(0.2)}, leaf.colour, std::max(1.0, 0.36 * o_.size), false});
    lines.push_back({{at(0.2), at(0.5)}, leaf.colour, std::max(1.0, 0.18 * o_.size), false});
  }
  return lines;
}

AnimationReport write_surface_particle_animation(const TangentBundle& bundle, const Field& field,
                                                 const ParticleAnimationOptions& options) {
  const auto start = std::chrono::steady_clock::now();
  const int total = options.frames > 0 ? options.frames : field.frames();
  check_option(total >= 1 && total <= 1'000'000, "frames", fmt::format("{} is outside [1, 1000000]", total));
  check_option(std::isfinite(options.time_scale) && options.time_scale > 0, "time scale",
               fmt::format("{} is not a positive number", options.time_scale));
  std::optional<Field> scaled;
  if (options.time_scale != 1.0) {
    scaled.emplace(field);
    for (cplx& z : scaled->data()) z *= options.time_scale;
  }
  SurfaceParticleSystem system(bundle, scaled ? *scaled : field, options.particles, options.surface);
  std::optional<DyeInjector> dye = particle_dye(bundle, scaled ? *scaled : field, options, total);
  MeshRenderer renderer;
  renderer.set_mesh(bundle.mesh());
  // The ground: the particles' background colour, lit by the headlight.
  renderer.set_colors(
      std::vector<std::uint32_t>(static_cast<size_t>(bundle.mesh().num_vertices()), options.particles.background));
  RenderOptions ro;
  ro.width = ro.height = options.particles.image_size;
  ro.background = 0xFFFFFF;
  ro.lighting = options.surface.lighting;
  ro.ambient = 0.5;
  FrameOutput out(options.frames_dir, options.video, ro.width, ro.height, options.fps);
  const TimeSampling& ts = field.time();
  DyeStyle style;
  style.width = std::max(2.0, options.particles.image_size / 300.0);
  style.fade = 0.7;
  style.fade_age = ts.t1 > ts.t0 ? ts.t1 - ts.t0 : 1.0;
  style.ground = options.particles.background;
  style.max_gap = 24.0 / system.pixels_per_unit();  // 24 pixels at the framed distance
  for (int k = 0; k < total; ++k) {
    const double t = total > 1 ? ts.t0 + (ts.t1 - ts.t0) * k / (total - 1) : ts.t0;
    system.advance(t);
    std::vector<RenderLine> lines = system.leaf_lines();
    std::vector<RenderMarker> markers;
    if (dye) {
      dye->advance(t);
      dye_overlay(*dye, style, lines, markers);
    }
    out.add(renderer.render(system.camera(), ro, lines, markers));
    if (options.progress) options.progress(k + 1, total);
  }
  AnimationReport report;
  report.files = out.finish();
  report.frames = total;
  if (dye) report.timelines = dye->timeline_records();
  report.width = ro.width;
  report.height = ro.height;
  report.seconds = std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
  return report;
}

}  // namespace tvf
