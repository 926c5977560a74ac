#include "tvf/render/dye_pictures.h"

#include "tvf/core/error.h"

#include <cairo.h>
#include <fmt/format.h>

#include <algorithm>
#include <cmath>

namespace tvf {

namespace {

constexpr std::uint32_t kDyeColours[] = {0xE8402A, 0x2A62E8, 0x1E9A46, 0x8E36C8, 0xF08C00, 0x0A9A9A};
constexpr std::uint32_t kTimelineColour = 0x0EA5E9;  // the designer's timelines' light blue

void check_style(const DyeStyle& s) {
  if (!(std::isfinite(s.width) && s.width > 0 && s.width <= 1000))
    throw Error(fmt::format("dye line width {} is outside (0, 1000] pixels", s.width));
  if (!(s.fade >= 0 && s.fade <= 1)) throw Error(fmt::format("dye fade {} is outside [0, 1]", s.fade));
  if (!(std::isfinite(s.fade_age) && s.fade_age > 0))
    throw Error(fmt::format("dye fade age {} must be a positive time", s.fade_age));
  if (!(std::isfinite(s.max_gap) && s.max_gap >= 0))
    throw Error(fmt::format("dye gap {} must be a positive length (or 0 for none)", s.max_gap));
}

// A piece of one seed's streakline whose segments fade alike.
struct Run {
  std::vector<Vec3> points;
  double opacity = 1;
  std::uint32_t colour = 0;
};

// Each seed's streakline cut where particles left the domain, where neighbours are more
// than max_gap apart, and where the (16-step) opacity changes; consecutive runs share
// their end point. Particles on no segment go to `dots` (when given).
std::vector<Run> runs_of(const DyeInjector& dye, const DyeStyle& style, std::vector<Run>* dots = nullptr) {
  std::vector<Run> runs;
  const double t = dye.time();
  for (size_t s = 0; s < dye.num_seeds(); ++s) {
    const Streakline line = dye.streakline(s);
    Run run;
    run.colour = dye_colour(s);
    auto flush = [&] {
      if (run.points.size() >= 2) runs.push_back(run);
      run.points.clear();
    };
    auto opacity_at = [&](double age) {
      return std::round(16.0 * (1.0 - style.fade * std::clamp(age / style.fade_age, 0.0, 1.0))) / 16.0;
    };
    const size_t n = line.points.size();
    std::vector<char> joined(n, 0);  // joined[i]: the segment from point i − 1 to i is drawn
    for (size_t i = 1; i < n; ++i)
      joined[i] = !line.points[i].gap_before &&
                  (style.max_gap <= 0 || (line.points[i].position - line.points[i - 1].position).norm() <= style.max_gap);
    if (dots)
      for (size_t i = 0; i < n; ++i)
        if (!joined[i] && (i + 1 == n || !joined[i + 1]))
          dots->push_back({{line.points[i].position}, opacity_at(t - line.points[i].release), run.colour});
    for (size_t i = 1; i < n; ++i) {
      const StreakPoint& a = line.points[i - 1];
      const StreakPoint& b = line.points[i];
      if (!joined[i]) {
        flush();
        continue;
      }
      const double opacity = opacity_at(t - 0.5 * (a.release + b.release));
      if (run.points.empty() || opacity != run.opacity) {
        flush();
        run.opacity = opacity;
        run.points.push_back(a.position);
      }
      run.points.push_back(b.position);
    }
    flush();
  }
  // The timelines: unfaded, in light blue, broken where particles left or parted.
  for (size_t l = 0; l < dye.num_timelines(); ++l) {
    Run run;
    run.colour = kTimelineColour;
    const Streakline& line = dye.timeline(l);
    for (size_t i = 0; i < line.points.size(); ++i) {
      const bool joined = i > 0 && !line.points[i].gap_before &&
                          (style.max_gap <= 0 ||
                           (line.points[i].position - line.points[i - 1].position).norm() <= style.max_gap);
      if (!joined) {
        if (run.points.size() >= 2) runs.push_back(run);
        run.points.clear();
      }
      run.points.push_back(line.points[i].position);
    }
    if (run.points.size() >= 2) runs.push_back(run);
  }
  return runs;
}

double channel(std::uint32_t c, int shift) { return ((c >> shift) & 0xFF) / 255.0; }

}  // namespace

std::uint32_t dye_colour(size_t s) { return kDyeColours[s % std::size(kDyeColours)]; }

void draw_dye(Image& image, const DyeInjector& dye, const std::function<Vec2(const Vec2&)>& to_pixel,
              const DyeStyle& style) {
  check_style(style);
  std::vector<Run> dots;
  const std::vector<Run> runs = runs_of(dye, style, &dots);
  cairo_surface_t* surface = cairo_image_surface_create_for_data(
      reinterpret_cast<unsigned char*>(image.pixels.data()), CAIRO_FORMAT_RGB24, image.width, image.height,
      image.width * 4);
  cairo_t* cr = cairo_create(surface);
  cairo_set_line_join(cr, CAIRO_LINE_JOIN_ROUND);
  cairo_set_line_cap(cr, CAIRO_LINE_CAP_BUTT);
  auto trace = [&](const Run& run) {
    cairo_new_path(cr);
    for (size_t k = 0; k < run.points.size(); ++k) {
      const Vec2 p = to_pixel(run.points[k].head<2>());
      if (k == 0) cairo_move_to(cr, p.x(), p.y());
      else cairo_line_to(cr, p.x(), p.y());
    }
  };
  // Under the dye first (every run's), so that no casing or halo covers a neighbour's core.
  if (style.halo)
    for (const Run& run : runs) {
      trace(run);
      cairo_set_source_rgba(cr, channel(run.colour, 16), channel(run.colour, 8), channel(run.colour, 0),
                            0.22 * run.opacity);
      cairo_set_line_width(cr, 3.2 * style.width);
      cairo_stroke(cr);
    }
  if (style.casing)
    for (const Run& run : runs) {
      trace(run);
      cairo_set_source_rgba(cr, 0, 0, 0, run.opacity);
      cairo_set_line_width(cr, 2.2 * style.width);
      cairo_stroke(cr);
    }
  for (const Run& run : runs) {
    trace(run);
    cairo_set_source_rgba(cr, channel(run.colour, 16), channel(run.colour, 8), channel(run.colour, 0), run.opacity);
    cairo_set_line_width(cr, style.width);
    cairo_stroke(cr);
  }
  for (const Run& dot : dots) {
    const Vec2 p = to_pixel(dot.points.front().head<2>());
    cairo_new_sub_path(cr);
    cairo_arc(cr, p.x(), p.y(), 0.6 * style.width, 0, 2 * kPi);
    cairo_set_source_rgba(cr, channel(dot.colour, 16), channel(dot.colour, 8), channel(dot.colour, 0), dot.opacity);
    cairo_fill(cr);
  }
  for (size_t s = 0; s < dye.num_seeds(); ++s) {
    const std::uint32_t c = dye_colour(s);
    const Vec2 p = to_pixel(dye.seed_position(s).head<2>());
    cairo_new_sub_path(cr);
    cairo_arc(cr, p.x(), p.y(), 2.5 * style.width, 0, 2 * kPi);
    cairo_set_source_rgb(cr, channel(c, 16), channel(c, 8), channel(c, 0));
    cairo_fill_preserve(cr);
    cairo_set_source_rgb(cr, 0, 0, 0);
    cairo_set_line_width(cr, std::max(1.0, 0.5 * style.width));
    cairo_stroke(cr);
  }
  cairo_destroy(cr);
  cairo_surface_flush(surface);
  cairo_surface_destroy(surface);
}

void dye_overlay(const DyeInjector& dye, const DyeStyle& style, std::vector<RenderLine>& lines,
                 std::vector<RenderMarker>& markers) {
  check_style(style);
  auto mix = [&](std::uint32_t c, double w) {  // w of c, 1 − w of the ground
    std::uint32_t out = 0;
    for (const int shift : {16, 8, 0}) {
      const double v = w * channel(c, shift) + (1 - w) * channel(style.ground, shift);
      out |= static_cast<std::uint32_t>(std::lround(255.0 * std::clamp(v, 0.0, 1.0))) << shift;
    }
    return out;
  };
  for (const Run& run : runs_of(dye, style))
    lines.push_back({run.points, mix(run.colour, run.opacity), style.width, style.casing});
  for (size_t s = 0; s < dye.num_seeds(); ++s)
    markers.push_back({dye.seed_position(s), dye_colour(s), 2.5 * style.width});
}

}  // namespace tvf
