#include "tvf/render/painterly.h"

#include "planar_view.h"

#include "tvf/core/error.h"
#include "tvf/integrate/pathline.h"
#include "tvf/integrate/streamline.h"
#include "tvf/render/frame_output.h"

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
  if (!ok) throw Error(fmt::format("painterly option {}: {}", name, what));
}

std::uint32_t sample(const Image& image, const Vec2& p) {
  const int i = std::clamp(static_cast<int>(std::floor(p.x())), 0, image.width - 1);
  const int j = std::clamp(static_cast<int>(std::floor(p.y())), 0, image.height - 1);
  return image.at(i, j);
}

}  // namespace

struct PainterlyAnimator::Impl {
  const TangentBundle& bundle;
  const Field& field;
  Image image, mask;
  PainterlyOptions o;
  detail::PlanarView view;
  detail::PlanarLocator locator;
  double cell = 1;
  int cells_x = 1, cells_y = 1;
  std::vector<BrushStroke> strokes;
  std::vector<SurfacePoint> where;  // per stroke, valid where moving
  std::mt19937_64 rng;
  long next_id = 0, added = 0, removed = 0;
  double t = 0;
  bool started = false;

  Impl(const TangentBundle& b, const Field& f, Image img, Image m, const PainterlyOptions& opt)
      : bundle(b), field(f), image(std::move(img)), mask(std::move(m)), o(opt),
        view(b.mesh(), image.width, image.height), locator(b.mesh()), rng(opt.seed) {}

  // Whether p is on the picture where the mask says the field does not apply.
  bool masked_at(const Vec2& p) const {
    if (mask.width == 0 || p.x() < 0 || p.y() < 0 || p.x() >= image.width || p.y() >= image.height) return false;
    const Vec2 q(p.x() * mask.width / image.width, p.y() * mask.height / image.height);
    const std::uint32_t c = sample(mask, q);
    const double lum = 0.299 * ((c >> 16) & 255) + 0.587 * ((c >> 8) & 255) + 0.114 * (c & 255);
    return lum <= 127.5;
  }

  bool moves_at(const Vec2& p) const {
    if (p.x() < 0 || p.y() < 0 || p.x() >= image.width || p.y() >= image.height) return false;
    if (masked_at(p)) return false;
    return locator.locate(view.to_domain(p)).has_value();
  }

  void add_stroke(const Vec2& centre, std::vector<SurfacePoint>& w) {
    BrushStroke s;
    s.id = next_id++;
    s.depth = std::uniform_real_distribution<float>(0.f, 1.f)(rng);
    s.centre = centre;
    s.shade = 1.0f + static_cast<float>(o.jitter) * std::uniform_real_distribution<float>(-1.f, 1.f)(rng);
    s.moving = moves_at(centre);
    SurfacePoint sp;
    if (s.moving) sp = *locator.locate(view.to_domain(centre));
    strokes.push_back(std::move(s));
    w.push_back(sp);
  }

  int cell_of(const Vec2& p) const {
    const int i = std::clamp(static_cast<int>(p.x() / cell), 0, cells_x - 1);
    const int j = std::clamp(static_cast<int>(p.y() / cell), 0, cells_y - 1);
    return j * cells_x + i;
  }

  Vec2 random_in_cell(int c) {
    std::uniform_real_distribution<double> u(0.0, 1.0);
    const double x = std::min((c % cells_x + u(rng)) * cell, image.width - 1e-6);
    const double y = std::min((c / cells_x + u(rng)) * cell, image.height - 1e-6);
    return {x, y};
  }

  // Keeps one to max_per_cell stroke centres in every cell.
  void rebalance(bool initial) {
    std::vector<std::vector<size_t>> in(static_cast<size_t>(cells_x * cells_y));
    for (size_t k = 0; k < strokes.size(); ++k) in[static_cast<size_t>(cell_of(strokes[k].centre))].push_back(k);
    std::vector<char> drop(strokes.size(), 0);
    for (auto& list : in)
      if (static_cast<int>(list.size()) > o.max_per_cell) {
        // ids grow with age: drop the oldest
        std::sort(list.begin(), list.end(), [&](size_t a, size_t b) { return strokes[a].id < strokes[b].id; });
        for (size_t q = 0; q + static_cast<size_t>(o.max_per_cell) < list.size(); ++q) drop[list[q]] = 1;
      }
    std::vector<BrushStroke> kept;
    std::vector<SurfacePoint> kept_where;
    for (size_t k = 0; k < strokes.size(); ++k)
      if (!drop[k]) {
        kept.push_back(std::move(strokes[k]));
        kept_where.push_back(where[k]);
      } else {
        ++removed;
      }
    strokes = std::move(kept);
    where = std::move(kept_where);
    for (size_t c = 0; c < in.size(); ++c)
      if (in[c].empty()) {
        add_stroke(random_in_cell(static_cast<int>(c)), where);
        if (!initial) ++added;
      }
  }

  double luminance(int i, int j) const {
    const std::uint32_t c = image.at(std::clamp(i, 0, image.width - 1), std::clamp(j, 0, image.height - 1));
    return 0.299 * ((c >> 16) & 255) + 0.587 * ((c >> 8) & 255) + 0.114 * (c & 255);
  }

  // Unit direction along the picture's edges at p: perpendicular to the luminance gradient
  // (central differences over the stroke's width); (1, 0) where the picture is flat.
  Vec2 edge_direction(const Vec2& p) const {
    const int r = std::max(1, static_cast<int>(std::lround(o.stroke_width)));
    const int i = static_cast<int>(p.x()), j = static_cast<int>(p.y());
    Vec2 g(0, 0);
    for (int q = -r; q <= r; ++q) {
      g.x() += luminance(i + r, j + q) - luminance(i - r, j + q);
      g.y() += luminance(i + q, j + r) - luminance(i + q, j - r);
    }
    const double n = g.norm();
    return n > 4.0 * (2 * r + 1) ? Vec2(-g.y() / n, g.x() / n) : Vec2(1, 0);
  }

  // The stroke's curve: the streamline of the frame at t through its centre.
  void shape(BrushStroke& s, const SurfacePoint& sp, const std::vector<cplx>& values) const {
    const double unit = 2.0 / (view.sx() + view.sy());  // domain length of one pixel
    StreamlineOptions so;
    so.max_length = 0.5 * o.stroke_length * unit;
    so.step = std::max(so.max_length / 6.0, 1e-12);
    so.stop_at_singular_faces = false;
    so.stop_speed = 1e-12;
    const Streamline line = trace_streamline(bundle, values, sp, so);
    s.path.clear();
    for (const auto& p : line.points) s.path.push_back(view.to_pixel(p.head<2>()));
    if (s.path.empty()) s.path.push_back(s.centre);
  }

  void advance(double t_new) {
    const TimeSampling& ts = field.time();
    check_option(std::isfinite(t_new) && t_new >= std::min(ts.t0, ts.t1) && t_new <= std::max(ts.t0, ts.t1), "time",
                 fmt::format("{} is outside the field's time range", t_new));
    const bool first = !started;
    if (first) {
      rebalance(true);
    } else if (t_new != t) {
      // Carry moving strokes along their pathlines.
      tbb::parallel_for(size_t{0}, strokes.size(), [&](size_t k) {
        BrushStroke& s = strokes[k];
        if (!s.moving) return;
        PathlineOptions po;
        po.t_start = t;
        po.t_end = t_new;
        po.stop_at_singular_faces = false;
        po.stop_speed = 0;
        const Pathline p = trace_pathline(bundle, field, where[k], po);
        if (p.where.empty()) return;
        // The whole way is checked against the mask, not only where it ends: a stroke
        // carried across a band where the field does not apply (thinner than a frame's
        // travel) stops in it, at the first point of the band (every half pixel of the
        // pathline is looked at), instead of moving on beyond it.
        Vec2 prev = s.centre;
        for (const Vec3& point : p.points) {
          const Vec2 q = view.to_pixel(point.head<2>());
          const int n = std::clamp(static_cast<int>(std::ceil((q - prev).norm() / 0.5)), 1, 10000);
          for (int m = 1; m <= n; ++m) {
            const Vec2 r = prev + (q - prev) * (static_cast<double>(m) / n);
            if (masked_at(r)) {
              s.centre = r;  // no longer moving (moves_at below)
              return;
            }
          }
          prev = q;
        }
        where[k] = p.where.back();
        s.centre = view.to_pixel(p.points.back().head<2>());
      });
      for (auto& s : strokes) {
        const bool m = s.moving;
        s.moving = moves_at(s.centre);
        if (m && !s.moving) s.path.clear();  // left the field: take its last shape below once
      }
      rebalance(false);
    }
    t = t_new;
    started = true;
    const std::vector<cplx> values = values_at(field, t);
    tbb::parallel_for(size_t{0}, strokes.size(), [&](size_t k) {
      BrushStroke& s = strokes[k];
      s.colour = sample(image, s.centre);
      if (s.moving) {
        shape(s, where[k], values);
      } else if (s.path.empty()) {
        // Strokes where the field does not apply stay put: straight, along the picture's
        // edges (across its luminance gradient), horizontal where the picture is flat.
        const Vec2 d = edge_direction(s.centre);
        s.path = {s.centre - 0.5 * o.stroke_length * d, s.centre + 0.5 * o.stroke_length * d};
      }
    });
  }

  Image picture() const {
    Image out = image;
    cairo_surface_t* surface = cairo_image_surface_create_for_data(
        reinterpret_cast<unsigned char*>(out.pixels.data()), CAIRO_FORMAT_RGB24, out.width, out.height, out.width * 4);
    cairo_t* cr = cairo_create(surface);
    cairo_set_line_cap(cr, CAIRO_LINE_CAP_ROUND);
    cairo_set_line_join(cr, CAIRO_LINE_JOIN_ROUND);
    std::vector<const BrushStroke*> order;
    order.reserve(strokes.size());
    for (const auto& s : strokes) order.push_back(&s);
    std::sort(order.begin(), order.end(), [](const BrushStroke* a, const BrushStroke* b) {
      return a->depth != b->depth ? a->depth < b->depth : a->id < b->id;
    });
    for (const BrushStroke* s : order) {
      auto channel = [&](int shift) { return std::clamp(((s->colour >> shift) & 255) * s->shade / 255.0, 0.0, 1.0); };
      const double r = channel(16), g = channel(8), b = channel(0);
      cairo_new_path(cr);
      const auto& p = s->path;
      cairo_move_to(cr, p[0].x(), p[0].y());
      if (p.size() == 1) cairo_line_to(cr, p[0].x() + 0.01, p[0].y());
      // A smooth curve through the points (Catmull-Rom as cubic Béziers).
      for (size_t k = 0; k + 1 < p.size(); ++k) {
        const Vec2 a = k > 0 ? p[k - 1] : p[k], b0 = p[k], c = p[k + 1], d = k + 2 < p.size() ? p[k + 2] : p[k + 1];
        const Vec2 c1 = b0 + (c - a) / 6.0, c2 = c - (d - b0) / 6.0;
        cairo_curve_to(cr, c1.x(), c1.y(), c2.x(), c2.y(), c.x(), c.y());
      }
      // A darker rim under the body gives each stroke an edge, as a loaded brush does.
      cairo_set_line_width(cr, o.stroke_width);
      cairo_set_source_rgb(cr, 0.8 * r, 0.8 * g, 0.8 * b);
      cairo_stroke_preserve(cr);
      cairo_set_line_width(cr, 0.6 * o.stroke_width);
      cairo_set_source_rgb(cr, std::min(1.0, r * 1.05), std::min(1.0, g * 1.05), std::min(1.0, b * 1.05));
      cairo_stroke(cr);
    }
    cairo_destroy(cr);
    cairo_surface_flush(surface);
    cairo_surface_destroy(surface);
    return out;
  }
};

PainterlyAnimator::PainterlyAnimator(const TangentBundle& bundle, const Field& field, Image picture, Image mask,
                                     const PainterlyOptions& o) {
  detail::require_planar(bundle, "painterly animation");
  check_option(picture.width >= 8 && picture.height >= 8 && picture.width <= 16384 && picture.height <= 16384,
               "image", fmt::format("{}×{} pixels is outside 8 to 16384 on a side", picture.width, picture.height));
  check_option(std::isfinite(o.stroke_width) && o.stroke_width >= 0.5 && o.stroke_width <= 500, "stroke width",
               fmt::format("{} pixels is outside [0.5, 500]", o.stroke_width));
  check_option(std::isfinite(o.stroke_length) && o.stroke_length >= 0 && o.stroke_length <= 5000, "stroke length",
               fmt::format("{} pixels is outside [0, 5000]", o.stroke_length));
  check_option(std::isfinite(o.density) && o.density > 0 && o.density <= 50, "density",
               fmt::format("{} is outside (0, 50]", o.density));
  check_option(o.max_per_cell >= 1 && o.max_per_cell <= 1000, "max per cell",
               fmt::format("{} is outside [1, 1000]", o.max_per_cell));
  check_option(std::isfinite(o.jitter) && o.jitter >= 0 && o.jitter <= 1, "jitter",
               fmt::format("{} is outside [0, 1]", o.jitter));
  if (field.num_vertices() != bundle.mesh().num_vertices() || field.frames() < 1)
    throw Error("painterly animation: the field does not belong to this domain");
  impl_ = std::make_unique<Impl>(bundle, field, std::move(picture), std::move(mask), o);
  Impl& m = *impl_;
  m.cell = std::sqrt(std::max(o.stroke_width, 1.0) * std::max(o.stroke_length, o.stroke_width) / o.density);
  m.cells_x = std::max(1, static_cast<int>(std::ceil(m.image.width / m.cell)));
  m.cells_y = std::max(1, static_cast<int>(std::ceil(m.image.height / m.cell)));
  check_option(static_cast<double>(m.cells_x) * m.cells_y <= 4e6, "density",
               "too many strokes (more than 4 million); use wider or longer strokes or a lower density");
}

PainterlyAnimator::~PainterlyAnimator() = default;
int PainterlyAnimator::width() const { return impl_->image.width; }
int PainterlyAnimator::height() const { return impl_->image.height; }
void PainterlyAnimator::advance(double t) { impl_->advance(t); }
double PainterlyAnimator::time() const { return impl_->t; }
const std::vector<BrushStroke>& PainterlyAnimator::strokes() const { return impl_->strokes; }
long PainterlyAnimator::added() const { return impl_->added; }
long PainterlyAnimator::removed() const { return impl_->removed; }
bool PainterlyAnimator::moves_at(const Vec2& p) const { return impl_->moves_at(p); }
Image PainterlyAnimator::picture() const { return impl_->picture(); }

AnimationReport write_painterly_animation(const TangentBundle& bundle, const Field& field, const Image& picture,
                                          const Image& mask, const PainterlyAnimationOptions& options) {
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
  PainterlyAnimator animator(bundle, scaled ? *scaled : field, picture, mask, options.painterly);
  FrameOutput out(options.frames_dir, options.video, animator.width(), animator.height(), options.fps);
  const TimeSampling& ts = field.time();
  for (int k = 0; k < total; ++k) {
    animator.advance(total > 1 ? ts.t0 + (ts.t1 - ts.t0) * k / (total - 1) : ts.t0);
    out.add(animator.picture());
    if (options.progress) options.progress(k + 1, total);
  }
  AnimationReport report;
  report.files = out.finish();
  report.frames = total;
  report.width = animator.width();
  report.height = animator.height();
  report.seconds = std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
  return report;
}

}  // namespace tvf
