#include "tvf/render/grass.h"

#include "planar_view.h"

#include "tvf/core/error.h"
#include "tvf/field/field_sampler.h"
#include "tvf/render/frame_output.h"

#include <cairo.h>
#include <fmt/format.h>
#include <tbb/parallel_for.h>

#include <algorithm>
#include <chrono>
#include <cmath>
#include <numeric>
#include <random>

namespace tvf {

namespace {

void check_option(bool ok, const std::string& name, const std::string& what) {
  if (!ok) throw Error(fmt::format("grass option {}: {}", name, what));
}

constexpr double kDeg = kPi / 180.0;

// The unit vector from a to b, or `fallback` when they coincide.
Vec3 direction(const Vec3& from, const Vec3& to, const Vec3& fallback) {
  const Vec3 d = to - from;
  const double n = d.norm();
  return n > 0 ? Vec3(d / n) : fallback;
}

}  // namespace

IkResult solve_fabrik(std::span<Vec3> joints, double segment_length, const Vec3& target, int max_iterations,
                      double tolerance) {
  TVF_CHECK(joints.size() >= 2, "a chain needs two joints, got {}", joints.size());
  const size_t n = joints.size();
  const Vec3 root = joints[0];
  const Vec3 up(0, 0, 1);
  IkResult r;
  r.tip_error = (joints[n - 1] - target).norm();
  while (r.tip_error > tolerance && r.iterations < max_iterations) {
    // Backward: the tip onto the target, every joint toward its old place.
    joints[n - 1] = target;
    for (size_t i = n - 1; i-- > 0;) joints[i] = joints[i + 1] + segment_length * direction(joints[i + 1], joints[i], -up);
    // Forward: the root back in place, every joint at its segment's length from the previous.
    joints[0] = root;
    for (size_t i = 1; i < n; ++i) joints[i] = joints[i - 1] + segment_length * direction(joints[i - 1], joints[i], up);
    ++r.iterations;
    r.tip_error = (joints[n - 1] - target).norm();
  }
  return r;
}

struct Meadow::Impl {
  const TangentBundle& bundle;
  const Field& field;
  GrassOptions o;
  FieldSampler sampler;
  int joints = 0;
  std::vector<SurfacePoint> where;
  std::vector<Vec3> roots, targets, pose;  // pose: strands × joints, strand-major
  std::vector<double> seglen;
  std::vector<Vec2> lean;  // random lean (radians, as a horizontal vector)
  double wind = 1.0;

  Impl(const TangentBundle& b, const Field& f, const GrassOptions& opt)
      : bundle(b), field(f), o(opt), sampler(b, f), joints(opt.segments + 1) {
    const Mesh& mesh = b.mesh();
    const Vec3 lo = mesh.bbox_min(), hi = mesh.bbox_max();
    const double extent = std::max(hi.x() - lo.x(), hi.y() - lo.y());
    // Roots uniform over the ground: a face by area, then a uniform point in it.
    std::vector<double> cdf(static_cast<size_t>(mesh.num_faces()));
    double acc = 0;
    for (int fi = 0; fi < mesh.num_faces(); ++fi) cdf[static_cast<size_t>(fi)] = acc += mesh.face_area(fi);
    std::mt19937_64 rng(o.seed);
    std::uniform_real_distribution<double> u(0.0, 1.0);
    const auto n = static_cast<size_t>(o.count);
    where.resize(n);
    roots.resize(n);
    seglen.resize(n);
    lean.resize(n);
    for (size_t k = 0; k < n; ++k) {
      const auto it = std::upper_bound(cdf.begin(), cdf.end(), u(rng) * acc);
      const int face = static_cast<int>(std::min<std::ptrdiff_t>(it - cdf.begin(), mesh.num_faces() - 1));
      const double a = u(rng), c = u(rng), s = std::sqrt(a);
      where[k] = SurfacePoint{face, Vec3(1 - s, s * (1 - c), s * c)};
      roots[k] = surface_position(mesh, where[k]);
      const double len = o.length * extent * (1 + o.length_variation * (u(rng) - 0.5));
      seglen[k] = len / o.segments;
      const double angle = 2 * kPi * u(rng), amount = o.lean * kDeg * std::sqrt(u(rng));
      lean[k] = amount * Vec2(std::cos(angle), std::sin(angle));
    }
    // Straight up to begin with.
    pose.resize(n * static_cast<size_t>(joints));
    for (size_t k = 0; k < n; ++k)
      for (int i = 0; i < joints; ++i) pose[k * static_cast<size_t>(joints) + static_cast<size_t>(i)] = roots[k] + Vec3(0, 0, i * seglen[k]);
    targets.assign(n, Vec3::Zero());
    // The speed that bends fully.
    if (o.wind_speed > 0) {
      wind = o.wind_speed;
    } else {
      const auto& data = f.data();
      const size_t stride = std::max<size_t>(1, data.size() / 1'000'000);
      std::vector<double> speeds;
      speeds.reserve(data.size() / stride + 1);
      for (size_t i = 0; i < data.size(); i += stride) speeds.push_back(std::abs(data[i]));
      if (!speeds.empty()) {
        const auto q = speeds.begin() + static_cast<std::ptrdiff_t>(0.99 * static_cast<double>(speeds.size() - 1));
        std::nth_element(speeds.begin(), q, speeds.end());
        wind = *q;
      }
      if (!(wind > 0)) wind = 1.0;
    }
  }

  Vec3 target_of(size_t k, double t) const {
    const Vec3 v = sampler.world(where[k], t);
    const double speed = v.head<2>().norm();
    // Bend as a horizontal vector of angle: toward V by s·bend, plus the strand's lean.
    Vec2 b = lean[k];
    if (speed > 0)
      b += std::pow(std::min(1.0, speed / wind), o.response) * o.bend * kDeg * Vec2(v.x() / speed, v.y() / speed);
    const double theta = b.norm();
    const double len = seglen[k] * o.segments;
    if (theta == 0) return roots[k] + Vec3(0, 0, len);
    const double half = 0.5 * theta;
    const double chord = len * std::sin(half) / half;
    const Vec2 dir = b / theta;
    return roots[k] + chord * Vec3(std::sin(half) * dir.x(), std::sin(half) * dir.y(), std::cos(half));
  }

  void pose_all(double t) {
    tbb::parallel_for(tbb::blocked_range<size_t>(0, roots.size(), 256), [&](const tbb::blocked_range<size_t>& r) {
      for (size_t k = r.begin(); k != r.end(); ++k) {
        targets[k] = target_of(k, t);
        const std::span<Vec3> chain(pose.data() + k * static_cast<size_t>(joints), static_cast<size_t>(joints));
        solve_fabrik(chain, seglen[k], targets[k], o.ik_iterations, o.ik_tolerance * seglen[k] * o.segments);
      }
    });
  }
};

Meadow::Meadow(const TangentBundle& bundle, const Field& field, const GrassOptions& o) {
  detail::require_planar(bundle, "grass");
  check_option(o.count >= 1 && o.count <= 10'000'000, "count", fmt::format("{} is outside [1, 10000000]", o.count));
  check_option(o.segments >= 1 && o.segments <= 64, "segments", fmt::format("{} is outside [1, 64]", o.segments));
  check_option(std::isfinite(o.length) && o.length > 0 && o.length <= 1, "length",
               fmt::format("{} is outside (0, 1] (a fraction of the domain's longer side)", o.length));
  check_option(std::isfinite(o.length_variation) && o.length_variation >= 0 && o.length_variation < 2,
               "length variation", fmt::format("{} is outside [0, 2)", o.length_variation));
  check_option(std::isfinite(o.bend) && o.bend >= 0 && o.bend <= 120, "bend",
               fmt::format("{} degrees is outside [0, 120]", o.bend));
  check_option(std::isfinite(o.lean) && o.lean >= 0 && o.lean <= 45, "lean",
               fmt::format("{} degrees is outside [0, 45]", o.lean));
  check_option(std::isfinite(o.wind_speed) && o.wind_speed >= 0, "wind speed",
               fmt::format("{} must be ≥ 0 (0: automatic)", o.wind_speed));
  check_option(std::isfinite(o.response) && o.response >= 0.1 && o.response <= 10, "response",
               fmt::format("{} is outside [0.1, 10]", o.response));
  check_option(o.ik_iterations >= 1 && o.ik_iterations <= 1000, "IK iterations",
               fmt::format("{} is outside [1, 1000]", o.ik_iterations));
  check_option(std::isfinite(o.ik_tolerance) && o.ik_tolerance > 0, "IK tolerance",
               fmt::format("{} must be > 0", o.ik_tolerance));
  if (field.num_vertices() != bundle.mesh().num_vertices() || field.frames() < 1)
    throw Error("grass: the field does not belong to this domain");
  impl_ = std::make_unique<Impl>(bundle, field, o);
}

Meadow::~Meadow() = default;
void Meadow::pose(double t) {
  const TimeSampling& ts = impl_->field.time();
  check_option(std::isfinite(t) && t >= std::min(ts.t0, ts.t1) && t <= std::max(ts.t0, ts.t1), "time",
               fmt::format("{} is outside the field's time range", t));
  impl_->pose_all(t);
}
int Meadow::strands() const { return static_cast<int>(impl_->roots.size()); }
int Meadow::joints_per_strand() const { return impl_->joints; }
std::span<const Vec3> Meadow::strand(int k) const {
  return {impl_->pose.data() + static_cast<size_t>(k) * static_cast<size_t>(impl_->joints),
          static_cast<size_t>(impl_->joints)};
}
const Vec3& Meadow::root(int k) const { return impl_->roots[static_cast<size_t>(k)]; }
double Meadow::segment_length(int k) const { return impl_->seglen[static_cast<size_t>(k)]; }
const Vec3& Meadow::target(int k) const { return impl_->targets[static_cast<size_t>(k)]; }
double Meadow::wind_speed() const { return impl_->wind; }
const GrassOptions& Meadow::options() const { return impl_->o; }
const Mesh& Meadow::mesh() const { return impl_->bundle.mesh(); }

// ---------------------------------------------------------------------------------------

struct GrassRenderer::Impl {
  const Meadow& meadow;
  GrassRenderOptions o;
  Vec3 eye, right, up, forward;
  double scale = 1, min_x = 0, max_y = 0, margin = 0;
  int width = 0, height = 0;
  std::vector<int> order;  // far to near
  std::vector<Vec3> colour;  // per strand base colour (r, g, b)
  Vec3 light;

  Impl(const Meadow& m, const GrassRenderOptions& opt) : meadow(m), o(opt) {
    const Mesh& mesh = m.mesh();
    const Vec3 lo = mesh.bbox_min(), hi = mesh.bbox_max();
    const double extent = std::max(hi.x() - lo.x(), hi.y() - lo.y());
    const Vec3 centre(0.5 * (lo.x() + hi.x()), 0.5 * (lo.y() + hi.y()), 0);
    const double e = o.elevation * kDeg;
    forward = Vec3(0, std::cos(e), -std::sin(e));
    right = Vec3(1, 0, 0);
    up = right.cross(forward);
    const double distance = 0.75 * extent / std::tan(0.5 * o.field_of_view * kDeg);
    eye = centre - distance * forward;
    // Fit the ground and the tallest strands into the picture.
    double len = 0;
    for (int k = 0; k < m.strands(); ++k) len = std::max(len, m.segment_length(k) * m.options().segments);
    double x0 = 1e300, x1 = -1e300, y0 = 1e300, y1 = -1e300;
    for (double x : {lo.x(), hi.x()})
      for (double y : {lo.y(), hi.y()})
        for (double z : {0.0, len}) {
          const Vec2 p = project(Vec3(x, y, z));
          x0 = std::min(x0, p.x()), x1 = std::max(x1, p.x()), y0 = std::min(y0, p.y()), y1 = std::max(y1, p.y());
        }
    const double span = std::max(x1 - x0, y1 - y0);
    margin = 0.02 * o.image_size;
    scale = (o.image_size - 2 * margin) / span;
    width = std::max(1, static_cast<int>(std::lround((x1 - x0) * scale + 2 * margin)));
    height = std::max(1, static_cast<int>(std::lround((y1 - y0) * scale + 2 * margin)));
    min_x = x0;
    max_y = y1;
    // Far to near.
    order.resize(static_cast<size_t>(m.strands()));
    std::iota(order.begin(), order.end(), 0);
    std::vector<double> depth(order.size());
    for (size_t k = 0; k < order.size(); ++k) depth[k] = (m.root(static_cast<int>(k)) - eye).dot(forward);
    std::stable_sort(order.begin(), order.end(),
                     [&](int a, int b) { return depth[static_cast<size_t>(a)] > depth[static_cast<size_t>(b)]; });
    // A green per strand, from yellowish to bluish.
    std::mt19937_64 rng(m.options().seed + 7);
    std::uniform_real_distribution<double> u(0.0, 1.0);
    colour.resize(order.size());
    for (auto& c : colour) {
      const double h = u(rng), v = 0.8 + 0.4 * u(rng);
      c = v * Vec3(0.22 + 0.18 * h, 0.50 + 0.08 * u(rng), 0.10 + 0.06 * (1 - h));
    }
    light = Vec3(0.1, -0.15, 1.0).normalized();
  }

  Vec2 project(const Vec3& x) const {
    const Vec3 p = x - eye;
    const double z = p.dot(forward);
    return {p.dot(right) / z, p.dot(up) / z};
  }
  Vec2 to_pixel(const Vec2& s) const { return {(s.x() - min_x) * scale + margin, (max_y - s.y()) * scale + margin}; }

  Image picture() const {
    Image image(width, height);
    std::fill(image.pixels.begin(), image.pixels.end(), o.sky);
    cairo_surface_t* surface = cairo_image_surface_create_for_data(
        reinterpret_cast<unsigned char*>(image.pixels.data()), CAIRO_FORMAT_RGB24, image.width, image.height,
        image.width * 4);
    cairo_t* cr = cairo_create(surface);
    auto set_rgb = [&](std::uint32_t c) {
      cairo_set_source_rgb(cr, ((c >> 16) & 255) / 255.0, ((c >> 8) & 255) / 255.0, (c & 255) / 255.0);
    };
    // The ground.
    const Mesh& mesh = meadow.mesh();
    const Vec3 lo = mesh.bbox_min(), hi = mesh.bbox_max();
    cairo_new_path(cr);
    for (const Vec3& corner : {Vec3(lo.x(), lo.y(), 0), Vec3(hi.x(), lo.y(), 0), Vec3(hi.x(), hi.y(), 0),
                               Vec3(lo.x(), hi.y(), 0)}) {
      const Vec2 p = to_pixel(project(corner));
      cairo_line_to(cr, p.x(), p.y());
    }
    cairo_close_path(cr);
    set_rgb(o.ground);
    cairo_fill(cr);

    cairo_set_line_cap(cr, CAIRO_LINE_CAP_ROUND);
    const int segments = meadow.joints_per_strand() - 1;
    for (const int k : order) {
      const std::span<const Vec3> joints = meadow.strand(k);
      const double len = meadow.segment_length(k) * segments;
      const Vec3& base = colour[static_cast<size_t>(k)];
      for (int i = 0; i < segments; ++i) {
        const Vec3& a = joints[static_cast<size_t>(i)];
        const Vec3& b = joints[static_cast<size_t>(i + 1)];
        const Vec3 tangent = direction(a, b, Vec3(0, 0, 1));
        const Vec3 mid = 0.5 * (a + b);
        const Vec3 to_eye = direction(mid, eye, -forward);
        // Kajiya–Kay: lines lit by their tangent.
        const double tl = tangent.dot(light), te = tangent.dot(to_eye);
        const double sl = std::sqrt(std::max(0.0, 1 - tl * tl)), se = std::sqrt(std::max(0.0, 1 - te * te));
        const double spec = std::pow(std::max(0.0, sl * se - tl * te), 16.0);
        const double h = (i + 0.5) / segments;  // height along the strand
        const double shade = (0.25 + 0.95 * sl) * (0.35 + 0.65 * std::pow(h, 0.7));
        const Vec3 c = (shade * base + 0.35 * spec * Vec3(1.0, 0.95, 0.7)).cwiseMin(1.0);
        cairo_set_source_rgb(cr, c.x(), c.y(), c.z());
        const double depth = (mid - eye).dot(forward);
        cairo_set_line_width(cr, std::max(0.6, o.width * len * (1 - 0.75 * h) * scale / depth));
        const Vec2 pa = to_pixel(project(a)), pb = to_pixel(project(b));
        cairo_move_to(cr, pa.x(), pa.y());
        cairo_line_to(cr, pb.x(), pb.y());
        cairo_stroke(cr);
      }
    }
    cairo_destroy(cr);
    cairo_surface_flush(surface);
    cairo_surface_destroy(surface);
    return image;
  }
};

GrassRenderer::GrassRenderer(const Meadow& meadow, const GrassRenderOptions& o) {
  check_option(o.image_size >= 16 && o.image_size <= 16384, "image size",
               fmt::format("{} pixels is outside [16, 16384]", o.image_size));
  check_option(std::isfinite(o.elevation) && o.elevation >= 10 && o.elevation <= 90, "elevation",
               fmt::format("{} degrees is outside [10, 90]", o.elevation));
  check_option(std::isfinite(o.field_of_view) && o.field_of_view >= 5 && o.field_of_view <= 120, "field of view",
               fmt::format("{} degrees is outside [5, 120]", o.field_of_view));
  check_option(std::isfinite(o.width) && o.width > 0 && o.width <= 1, "width",
               fmt::format("{} is outside (0, 1] (a fraction of the strand length)", o.width));
  impl_ = std::make_unique<Impl>(meadow, o);
}
GrassRenderer::~GrassRenderer() = default;
int GrassRenderer::width() const { return impl_->width; }
int GrassRenderer::height() const { return impl_->height; }
Image GrassRenderer::picture() const { return impl_->picture(); }

AnimationReport write_grass_animation(const TangentBundle& bundle, const Field& field,
                                      const GrassAnimationOptions& options) {
  const auto start = std::chrono::steady_clock::now();
  const int total = options.frames > 0 ? options.frames : field.frames();
  check_option(total >= 1 && total <= 1'000'000, "frames", fmt::format("{} is outside [1, 1000000]", total));
  Meadow meadow(bundle, field, options.grass);
  GrassRenderer renderer(meadow, options.render);
  FrameOutput out(options.frames_dir, options.video, renderer.width(), renderer.height(), options.fps);
  const TimeSampling& ts = field.time();
  for (int k = 0; k < total; ++k) {
    meadow.pose(total > 1 ? ts.t0 + (ts.t1 - ts.t0) * k / (total - 1) : ts.t0);
    out.add(renderer.picture());
    if (options.progress) options.progress(k + 1, total);
  }
  AnimationReport report;
  report.files = out.finish();
  report.frames = total;
  report.width = renderer.width();
  report.height = renderer.height();
  report.seconds = std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
  return report;
}

}  // namespace tvf
