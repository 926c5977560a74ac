#include "tvf/render/plots.h"

#include "tvf/core/atomic_output.h"
#include "tvf/core/error.h"
#include "tvf/integrate/periodic_orbits.h"

#include <cairo-svg.h>
#include <cairo.h>

#include <algorithm>
#include <cmath>
#include <filesystem>
#include <functional>
#include <map>

namespace tvf {

namespace fs = std::filesystem;

std::array<double, 3> type_color(SingularityType type) {
  switch (type) {
    case SingularityType::source: return {0.10, 0.65, 0.20};
    case SingularityType::sink: return {0.85, 0.10, 0.10};
    case SingularityType::saddle: return {0.10, 0.25, 0.90};
    case SingularityType::center:
    case SingularityType::repelling_focus:
    case SingularityType::attracting_focus: return {0.80, 0.10, 0.80};
  }
  return {0, 0, 0};
}

namespace {

using Painter = std::function<void(cairo_t*, double width, double height)>;

// Renders `paint` to stem.svg and stem.png, each through a temporary name.
std::vector<std::string> render(const std::string& stem, const PlotOptions& o, const Painter& paint) {
  std::vector<std::string> out;
  const fs::path svg = stem + ".svg", png = stem + ".png";
  {
    const fs::path tmp = temporary_sibling(svg);
    cairo_surface_t* surface = cairo_svg_surface_create(tmp.c_str(), o.width, o.height);
    cairo_t* cr = cairo_create(surface);
    paint(cr, o.width, o.height);
    cairo_destroy(cr);
    cairo_surface_finish(surface);
    const cairo_status_t status = cairo_surface_status(surface);
    cairo_surface_destroy(surface);
    std::error_code ec;
    if (status != CAIRO_STATUS_SUCCESS) {
      fs::remove(tmp, ec);
      throw_input_error(svg.string(), "", fmt::format("cannot write the plot ({})", cairo_status_to_string(status)));
    }
    fs::rename(tmp, svg, ec);
    if (ec) throw_input_error(svg.string(), "", "cannot move the finished plot into place");
    out.push_back(svg.string());
  }
  {
    cairo_surface_t* surface = cairo_image_surface_create(CAIRO_FORMAT_RGB24, o.width, o.height);
    cairo_t* cr = cairo_create(surface);
    paint(cr, o.width, o.height);
    cairo_destroy(cr);
    const fs::path tmp = temporary_sibling(png);
    const cairo_status_t status = cairo_surface_write_to_png(surface, tmp.c_str());
    cairo_surface_destroy(surface);
    std::error_code ec;
    if (status != CAIRO_STATUS_SUCCESS) {
      fs::remove(tmp, ec);
      throw_input_error(png.string(), "", fmt::format("cannot write the plot ({})", cairo_status_to_string(status)));
    }
    fs::rename(tmp, png, ec);
    if (ec) throw_input_error(png.string(), "", "cannot move the finished plot into place");
    out.push_back(png.string());
  }
  return out;
}

void background(cairo_t* cr) {
  cairo_set_source_rgb(cr, 1, 1, 1);
  cairo_paint(cr);
  cairo_select_font_face(cr, "sans-serif", CAIRO_FONT_SLANT_NORMAL, CAIRO_FONT_WEIGHT_NORMAL);
}

void text(cairo_t* cr, double x, double y, const std::string& s, double size, double align_x = 0,
          double align_y = 0) {
  cairo_set_font_size(cr, size);
  cairo_text_extents_t e;
  cairo_text_extents(cr, s.c_str(), &e);
  cairo_move_to(cr, x - align_x * e.width - e.x_bearing, y - align_y * e.height - e.y_bearing);
  cairo_show_text(cr, s.c_str());
}

// "Nice" tick spacing for a range.
double tick_step(double span, int wanted) {
  const double raw = span / std::max(1, wanted);
  const double mag = std::pow(10.0, std::floor(std::log10(raw)));
  for (double m : {1.0, 2.0, 5.0, 10.0})
    if (raw <= m * mag) return m * mag;
  return 10 * mag;
}

std::string number(double v) { return fmt::format("{:.3g}", std::abs(v) < 1e-12 ? 0.0 : v); }

}  // namespace

std::vector<std::string> write_coherence_plot(const std::string& stem, const std::vector<double>& times,
                                              const std::vector<double>& coherence,
                                              const PlotOptions& options) {
  TVF_CHECK(times.size() >= coherence.size(), "{} times for {} coherence values", times.size(),
            coherence.size());
  return render(stem, options, [&](cairo_t* cr, double w, double h) {
    background(cr);
    const double left = 80, right = 30, top = 50, bottom = 60;
    const double pw = w - left - right, ph = h - top - bottom;
    const double t0 = times.empty() ? 0 : times.front(), t1 = times.size() > 1 ? times.back() : t0 + 1;
    double ymax = 0;
    for (double y : coherence) ymax = std::max(ymax, y);
    if (ymax <= 0) ymax = 1;
    const double ystep = tick_step(ymax, 5);
    ymax = std::ceil(ymax / ystep) * ystep;
    auto X = [&](double t) { return left + (t - t0) / (t1 - t0) * pw; };
    auto Y = [&](double y) { return top + ph - y / ymax * ph; };
    // Grid and ticks.
    cairo_set_line_width(cr, 1);
    cairo_set_source_rgb(cr, 0.88, 0.88, 0.88);
    for (double y = 0; y <= ymax * (1 + 1e-9); y += ystep) {
      cairo_move_to(cr, left, Y(y));
      cairo_line_to(cr, left + pw, Y(y));
    }
    const double tstep = tick_step(t1 - t0, 8);
    for (double t = std::ceil(t0 / tstep) * tstep; t <= t1 + 1e-9 * tstep; t += tstep) {
      cairo_move_to(cr, X(t), top);
      cairo_line_to(cr, X(t), top + ph);
    }
    cairo_stroke(cr);
    cairo_set_source_rgb(cr, 0.15, 0.15, 0.15);
    for (double y = 0; y <= ymax * (1 + 1e-9); y += ystep) text(cr, left - 8, Y(y), number(y), 13, 1, 0.5);
    for (double t = std::ceil(t0 / tstep) * tstep; t <= t1 + 1e-9 * tstep; t += tstep)
      text(cr, X(t), top + ph + 8, number(t), 13, 0.5, 0);
    cairo_rectangle(cr, left, top, pw, ph);
    cairo_stroke(cr);
    text(cr, left + pw / 2, h - 22, "t", 15, 0.5, 0);
    text(cr, left + pw / 2, 18, options.title.empty() ? "temporal coherence  Σ‖V(t + Δt) − V(t)‖" : options.title,
         16, 0.5, 0);
    // The series.
    cairo_set_source_rgb(cr, 0.10, 0.30, 0.75);
    cairo_set_line_width(cr, 2);
    for (size_t i = 0; i < coherence.size(); ++i) {
      if (i == 0) cairo_move_to(cr, X(times[i]), Y(coherence[i]));
      else cairo_line_to(cr, X(times[i]), Y(coherence[i]));
    }
    cairo_stroke(cr);
  });
}

std::vector<std::string> write_paths_plot(const std::string& stem, const Mesh& mesh,
                                          const Topology& topology, const PlotOptions& options) {
  // Axes u, v: the two widest bounding-box axes.
  const Vec3 lo = mesh.bbox_min(), hi = mesh.bbox_max(), ext = hi - lo;
  std::array<int, 3> axes = {0, 1, 2};
  std::sort(axes.begin(), axes.end(), [&](int a, int b) { return ext[a] > ext[b]; });
  if (mesh.is_planar_xy()) axes = {0, 1, 2};
  const int ua = axes[0], va = axes[1];
  const double t0 = topology.times.empty() ? 0 : topology.times.front();
  const double t1 = topology.times.size() > 1 ? topology.times.back() : t0 + 1;
  return render(stem, options, [&](cairo_t* cr, double w, double h) {
    background(cr);
    // Oblique view: u to the right, t up, v receding at 30° with half length. The legend
    // has the column left of the box to itself (over the box, its last entries were struck
    // through by the box's top edge once cycles and Hopf events joined it).
    const double margin = 70, left = 190;
    const double du = std::max(ext[ua], 1e-12), dv = std::max(ext[va], 1e-12);
    const double depth = 0.5, ang = kPi / 6;
    const double box_w = 1 + depth * std::cos(ang) * dv / du;
    const double scale_u = (w - left - margin) / box_w;
    const double th = (h - 2 * margin - depth * std::sin(ang) * dv / du * scale_u);
    auto P = [&](double u, double v, double t, double& x, double& y) {
      const double uu = (u - lo[ua]) / du, vv = (v - lo[va]) / du, tt = (t - t0) / (t1 - t0);
      x = left + scale_u * (uu + depth * std::cos(ang) * vv);
      y = h - margin - th * tt - scale_u * depth * std::sin(ang) * vv;
    };
    auto line = [&](double u0, double v0, double s0, double u1, double v1, double s1) {
      double x, y;
      P(u0, v0, s0, x, y);
      cairo_move_to(cr, x, y);
      P(u1, v1, s1, x, y);
      cairo_line_to(cr, x, y);
    };
    // The space-time box.
    cairo_set_source_rgb(cr, 0.7, 0.7, 0.7);
    cairo_set_line_width(cr, 1);
    const double U[2] = {lo[ua], hi[ua]}, V[2] = {lo[va], hi[va]}, T[2] = {t0, t1};
    for (int a = 0; a < 2; ++a)
      for (int b = 0; b < 2; ++b) {
        line(U[0], V[a], T[b], U[1], V[a], T[b]);
        line(U[a], V[0], T[b], U[a], V[1], T[b]);
        line(U[a], V[b], T[0], U[a], V[b], T[1]);
      }
    cairo_stroke(cr);
    // Edge labels: the ranges of u and v along the front and side edges at t0, ticks of t
    // up the front left edge, and the axis names at the middle of those edges.
    cairo_set_source_rgb(cr, 0.2, 0.2, 0.2);
    const char* names = "xyz";
    const std::string un(1, names[ua]), vn(1, names[va]);
    double x, y;
    P(lo[ua], lo[va], t0, x, y);
    text(cr, x, y + 8, number(lo[ua]), 12, 0.5, 0);
    P(hi[ua], lo[va], t0, x, y);
    text(cr, x, y + 8, number(hi[ua]), 12, 0.5, 0);
    P(0.5 * (lo[ua] + hi[ua]), lo[va], t0, x, y);
    text(cr, x, y + 8, un, 15, 0.5, 0);
    P(hi[ua], lo[va], t0, x, y);
    text(cr, x + 8, y - 4, vn + " = " + number(lo[va]), 12, 0, 0.5);
    P(hi[ua], hi[va], t0, x, y);
    text(cr, x + 8, y - 4, vn + " = " + number(hi[va]), 12, 0, 0.5);
    P(hi[ua], 0.5 * (lo[va] + hi[va]), t0, x, y);
    text(cr, x + 22, y - 4, vn, 15, 0, 0.5);
    const double tstep = tick_step(t1 - t0, 4);
    cairo_set_line_width(cr, 1);
    for (double t = std::ceil(t0 / tstep) * tstep; t <= t1 + 1e-9 * tstep; t += tstep) {
      P(lo[ua], lo[va], t, x, y);
      cairo_move_to(cr, x - 5, y);
      cairo_line_to(cr, x, y);
      cairo_stroke(cr);
      text(cr, x - 8, y, number(t), 12, 1, 0.5);
    }
    P(lo[ua], lo[va], 0.5 * (t0 + t1), x, y);
    text(cr, x - 44, y, "t", 15, 1, 0.5);
    text(cr, w / 2, 18, options.title.empty() ? "singularity paths in space-time" : options.title, 16, 0.5, 0);
    // Legend.
    const std::pair<const char*, SingularityType> legend[] = {
        {"source", SingularityType::source}, {"sink", SingularityType::sink},
        {"saddle", SingularityType::saddle}, {"center / focus", SingularityType::center}};
    double lx = 20, ly = 50;
    for (const auto& [name, type] : legend) {
      const auto c = type_color(type);
      cairo_set_source_rgb(cr, c[0], c[1], c[2]);
      cairo_rectangle(cr, lx, ly - 6, 22, 4);
      cairo_fill(cr);
      cairo_set_source_rgb(cr, 0.15, 0.15, 0.15);
      text(cr, lx + 30, ly - 4, name, 13, 0, 0.5);
      ly += 20;
    }
    cairo_new_sub_path(cr);
    cairo_arc(cr, lx + 11, ly - 4, 5, 0, 2 * kPi);
    cairo_fill(cr);
    text(cr, lx + 30, ly - 4, "creation", 13, 0, 0.5);
    ly += 20;
    cairo_set_line_width(cr, 1.8);
    cairo_new_sub_path(cr);
    cairo_arc(cr, lx + 11, ly - 4, 5, 0, 2 * kPi);
    cairo_stroke(cr);
    text(cr, lx + 30, ly - 4, "cancellation", 13, 0, 0.5);
    std::vector<char> extra(topology.paths.size(), 0);
    for (const int id : options.extra_paths)
      if (id >= 0 && id < static_cast<int>(extra.size())) extra[static_cast<size_t>(id)] = 1;
    if (!options.extra_paths.empty()) {
      ly += 20;
      const double dash[] = {5, 4};
      cairo_set_dash(cr, dash, 2, 0);
      cairo_set_line_width(cr, 1.4);
      cairo_move_to(cr, lx, ly - 4);
      cairo_line_to(cr, lx + 22, ly - 4);
      cairo_stroke(cr);
      cairo_set_dash(cr, nullptr, 0, 0);
      text(cr, lx + 30, ly - 4, "extra (not designed)", 13, 0, 0.5);
    }
    const bool any_orbits = options.orbits && !options.orbits->orbits.empty();
    constexpr double kAttracting[3] = {0.93, 0.5, 0.05}, kRepelling[3] = {0.0, 0.6, 0.6};
    auto diamond = [&](double cx, double cy, double r) {
      cairo_move_to(cr, cx, cy - r);
      cairo_line_to(cr, cx + r, cy);
      cairo_line_to(cr, cx, cy + r);
      cairo_line_to(cr, cx - r, cy);
      cairo_close_path(cr);
    };
    if (any_orbits) {
      for (int s = 0; s < 2; ++s) {
        ly += 20;
        const double* c = s == 0 ? kAttracting : kRepelling;
        cairo_set_source_rgb(cr, c[0], c[1], c[2]);
        cairo_set_line_width(cr, 1.6);
        cairo_new_sub_path(cr);
        cairo_save(cr);
        cairo_translate(cr, lx + 11, ly - 4);
        cairo_scale(cr, 1, 0.45);
        cairo_arc(cr, 0, 0, 10, 0, 2 * kPi);
        cairo_restore(cr);
        cairo_stroke(cr);
        cairo_set_source_rgb(cr, 0.15, 0.15, 0.15);
        text(cr, lx + 30, ly - 4, s == 0 ? "attracting cycle" : "repelling cycle", 13, 0, 0.5);
      }
    }
    if (options.orbits && !options.orbits->hopf.empty()) {
      ly += 20;
      cairo_set_source_rgb(cr, 0, 0, 0);
      diamond(lx + 11, ly - 4, 6);
      cairo_fill(cr);
      text(cr, lx + 30, ly - 4, "Hopf", 13, 0, 0.5);
    }
    // Paths.
    cairo_set_line_join(cr, CAIRO_LINE_JOIN_ROUND);
    for (const SingularityPath& p : topology.paths) {
      const auto c = type_color(p.type);
      cairo_set_source_rgb(cr, c[0], c[1], c[2]);
      const bool dashed = extra[static_cast<size_t>(p.id)] != 0;
      const double dash[] = {5, 4};
      cairo_set_dash(cr, dash, dashed ? 2 : 0, 0);
      cairo_set_line_width(cr, dashed ? 1.4 : 2.4);
      for (size_t k = 0; k < p.points.size(); ++k) {
        P(p.points[k].position[ua], p.points[k].position[va], p.points[k].t, x, y);
        if (k == 0) cairo_move_to(cr, x, y);
        else cairo_line_to(cr, x, y);
      }
      if (p.points.size() == 1) {
        cairo_new_sub_path(cr);
        cairo_arc(cr, x, y, 1.5, 0, 2 * kPi);
      }
      cairo_stroke(cr);
    }
    cairo_set_dash(cr, nullptr, 0, 0);
    // Periodic orbits: each track at about twelve evenly spaced frames of its life.
    if (any_orbits) {
      std::map<int, std::vector<const PeriodicOrbit*>> tracks;
      for (const PeriodicOrbit& o : options.orbits->orbits) tracks[o.id].push_back(&o);
      cairo_set_line_width(cr, 1.3);
      for (const auto& [id, list] : tracks) {
        const size_t stride = std::max<size_t>(1, (list.size() + 11) / 12);
        for (size_t k = 0; k < list.size(); k += stride) {
          const PeriodicOrbit& o = *list[k];
          const double* c = o.stability == OrbitStability::attracting ? kAttracting : kRepelling;
          cairo_set_source_rgb(cr, c[0], c[1], c[2]);
          for (size_t i = 0; i < o.points.size(); ++i) {
            P(o.points[i][ua], o.points[i][va], o.t, x, y);
            if (i == 0) cairo_move_to(cr, x, y);
            else cairo_line_to(cr, x, y);
          }
          cairo_close_path(cr);
          cairo_stroke(cr);
        }
      }
    }
    // Bifurcations: creations filled, cancellations as rings (white inside).
    cairo_set_line_width(cr, 1.8);
    for (const Bifurcation& b : topology.bifurcations) {
      P(b.position[ua], b.position[va], b.t, x, y);
      cairo_new_sub_path(cr);
      cairo_arc(cr, x, y, 5.5, 0, 2 * kPi);
      if (b.kind == BifurcationKind::creation) {
        cairo_set_source_rgb(cr, 0, 0, 0);
        cairo_fill(cr);
      } else {
        cairo_set_source_rgb(cr, 1, 1, 1);
        cairo_fill_preserve(cr);
        cairo_set_source_rgb(cr, 0, 0, 0);
        cairo_stroke(cr);
      }
    }
    if (options.orbits)
      for (const HopfEvent& e : options.orbits->hopf) {
        P(e.position[ua], e.position[va], e.t, x, y);
        cairo_set_source_rgb(cr, 0, 0, 0);
        diamond(x, y, 7);
        cairo_fill(cr);
      }
  });
}

}  // namespace tvf
