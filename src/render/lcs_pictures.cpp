#include "tvf/render/lcs_pictures.h"

#include "tvf/field/point_locator.h"

#include "tvf/core/error.h"
#include "tvf/render/mesh_renderer.h"

#include <cairo.h>
#include <tbb/parallel_for.h>

#include <algorithm>
#include <array>
#include <cmath>
#include <limits>

namespace tvf {

std::uint32_t magma(double s) {
  static constexpr std::array<std::array<double, 3>, 9> kStops{{{0, 0, 4},
                                                                {28, 16, 68},
                                                                {79, 18, 123},
                                                                {129, 37, 129},
                                                                {181, 54, 122},
                                                                {229, 80, 100},
                                                                {251, 135, 97},
                                                                {254, 194, 135},
                                                                {252, 253, 191}}};
  if (!(s > 0)) s = 0;
  if (s > 1) s = 1;
  const double x = s * (kStops.size() - 1);
  const size_t k = std::min(static_cast<size_t>(x), kStops.size() - 2);
  const double w = x - static_cast<double>(k);
  std::uint32_t out = 0;
  for (size_t c = 0; c < 3; ++c) {
    const double v = (1 - w) * kStops[k][c] + w * kStops[k + 1][c];
    out = (out << 8) | static_cast<std::uint32_t>(std::lround(v));
  }
  return out;
}

namespace {

void check_size(int size) {
  if (size < 16 || size > 16384) throw Error(fmt::format("picture size {} pixels is outside [16, 16384]", size));
}

}  // namespace

std::pair<double, double> colour_range(std::span<const float> values) {
  std::vector<float> finite;
  for (const float v : values)
    if (std::isfinite(v)) finite.push_back(v);
  if (finite.empty()) return {0.0, 1.0};
  auto at = [&](double q) {
    const auto k = static_cast<size_t>(q * static_cast<double>(finite.size() - 1));
    std::nth_element(finite.begin(), finite.begin() + static_cast<long>(k), finite.end());
    return static_cast<double>(finite[k]);
  };
  double lo = at(0.01), hi = at(0.99);
  if (!(hi > lo)) hi = lo + 1e-6;
  return {lo, hi};
}

namespace {

cairo_t* cairo_on(Image& image, cairo_surface_t*& surface) {
  surface = cairo_image_surface_create_for_data(reinterpret_cast<unsigned char*>(image.pixels.data()),
                                                CAIRO_FORMAT_RGB24, image.width, image.height, image.width * 4);
  return cairo_create(surface);
}

void cairo_done(cairo_t* cr, cairo_surface_t* surface) {
  cairo_destroy(cr);
  cairo_surface_flush(surface);
  cairo_surface_destroy(surface);
}

// The picture with a colour bar, the range and the label added below it.
Image with_legend(const Image& picture, double lo, double hi, const std::string& label) {
  const int bar = std::max(44, picture.width / 14);
  Image out(picture.width, picture.height + bar);
  std::fill(out.pixels.begin(), out.pixels.end(), 0x00FFFFFFu);
  std::copy(picture.pixels.begin(), picture.pixels.end(), out.pixels.begin());
  const int x0 = 12, x1 = out.width - 12, y0 = picture.height + 6, h = bar / 3;
  for (int x = x0; x < x1; ++x)
    for (int y = y0; y < y0 + h; ++y) out.at(x, y) = magma(static_cast<double>(x - x0) / (x1 - x0 - 1));
  cairo_surface_t* surface = nullptr;
  cairo_t* cr = cairo_on(out, surface);
  cairo_select_font_face(cr, "sans-serif", CAIRO_FONT_SLANT_NORMAL, CAIRO_FONT_WEIGHT_NORMAL);
  const double font = std::max(10.0, bar * 0.36);
  cairo_set_font_size(cr, font);
  cairo_set_source_rgb(cr, 0.1, 0.1, 0.1);
  const double base = y0 + h + font + 1;
  cairo_text_extents_t ext;
  const std::string left = fmt::format("{:.3g}", lo), right = fmt::format("{:.3g}", hi);
  cairo_move_to(cr, x0, base);
  cairo_show_text(cr, left.c_str());
  cairo_text_extents(cr, right.c_str(), &ext);
  cairo_move_to(cr, x1 - ext.x_advance, base);
  cairo_show_text(cr, right.c_str());
  if (!label.empty()) {
    cairo_text_extents(cr, label.c_str(), &ext);
    cairo_move_to(cr, 0.5 * (out.width - ext.x_advance), base);
    cairo_show_text(cr, label.c_str());
  }
  cairo_done(cr, surface);
  return out;
}

// Planar pictures: the domain's bounding box, `size` pixels on the long side, y up.
struct Raster {
  int width = 0, height = 0;
  double ppu = 1;
  Vec2 lo, hi;
  Vec2 to_pixel(const Vec2& x) const { return {(x.x() - lo.x()) * ppu, (hi.y() - x.y()) * ppu}; }
};

Raster raster_of(const Mesh& mesh, int size) {
  Raster r;
  r.lo = mesh.bbox_min().head<2>();
  r.hi = mesh.bbox_max().head<2>();
  const Vec2 ext = r.hi - r.lo;
  r.ppu = size / std::max(ext.x(), ext.y());
  r.width = std::max(1, static_cast<int>(std::lround(ext.x() * r.ppu)));
  r.height = std::max(1, static_cast<int>(std::lround(ext.y() * r.ppu)));
  return r;
}

Image planar_scalar(const Mesh& mesh, std::span<const float> values, double lo, double hi,
                    const ScalarPictureOptions& o) {
  const Raster r = raster_of(mesh, o.size);
  Image img(r.width, r.height);
  std::fill(img.pixels.begin(), img.pixels.end(), 0x00FFFFFFu);
  std::vector<char> done(img.pixels.size(), 0);
  for (int f = 0; f < mesh.num_faces(); ++f) {
    const Face& t = mesh.face(f);
    Vec2 p[3];
    for (size_t c = 0; c < 3; ++c) p[c] = r.to_pixel(mesh.position(t[c]).head<2>());
    const int i0 = std::max(0, static_cast<int>(std::floor(std::min({p[0].x(), p[1].x(), p[2].x()}) - 0.5)));
    const int i1 = std::min(r.width - 1, static_cast<int>(std::ceil(std::max({p[0].x(), p[1].x(), p[2].x()}) - 0.5)));
    const int j0 = std::max(0, static_cast<int>(std::floor(std::min({p[0].y(), p[1].y(), p[2].y()}) - 0.5)));
    const int j1 = std::min(r.height - 1, static_cast<int>(std::ceil(std::max({p[0].y(), p[1].y(), p[2].y()}) - 0.5)));
    const Vec2 a = p[1] - p[0], b = p[2] - p[0];
    const double det = a.x() * b.y() - a.y() * b.x();
    if (det == 0) continue;
    const double v0 = values[static_cast<size_t>(t[0])], v1 = values[static_cast<size_t>(t[1])],
                 v2 = values[static_cast<size_t>(t[2])];
    for (int j = j0; j <= j1; ++j)
      for (int i = i0; i <= i1; ++i) {
        const size_t k = static_cast<size_t>(j) * static_cast<size_t>(r.width) + static_cast<size_t>(i);
        if (done[k]) continue;
        const Vec2 d = Vec2(i + 0.5, j + 0.5) - p[0];
        const double l1 = (d.x() * b.y() - d.y() * b.x()) / det;
        const double l2 = (a.x() * d.y() - a.y() * d.x()) / det;
        const double l0 = 1 - l1 - l2;
        constexpr double eps = -1e-9;
        if (l0 < eps || l1 < eps || l2 < eps) continue;
        done[k] = 1;
        const double v = l0 * v0 + l1 * v1 + l2 * v2;
        img.pixels[k] = std::isfinite(v) ? magma((v - lo) / (hi - lo)) : o.nan_color;
      }
  }
  return img;
}

// The direction from which the curves and seeds face the camera: the sum of the surface's
// unit normals at (up to 512 of) their points. Where they wrap round the mesh so that the
// normals cancel (the sum under a tenth of their count), `fallback`.
Vec3 facing(const Mesh& mesh, const std::vector<std::vector<Vec3>>& curves, std::span<const Vec3> seeds,
            const Vec3& fallback) {
  std::vector<Vec3> points(seeds.begin(), seeds.end());
  for (const auto& c : curves) points.insert(points.end(), c.begin(), c.end());
  if (points.empty()) return fallback;
  const PointLocator locator(mesh);
  const size_t stride = std::max<size_t>(1, points.size() / 512);
  Vec3 sum = Vec3::Zero();
  size_t n = 0;
  for (size_t i = 0; i < points.size(); i += stride, ++n) sum += mesh.face_normal(locator.closest(points[i]).face);
  return sum.allFinite() && sum.norm() > 0.1 * static_cast<double>(n) ? sum : fallback;
}

Camera surface_camera(const Mesh& mesh, const SurfaceView& view) {
  return Camera::framing(std::span<const Vec3>(mesh.positions()), view.direction, view.up, 1.0, view.fov);
}

}  // namespace

Image scalar_picture(const TangentBundle& bundle, std::span<const float> values, const ScalarPictureOptions& o) {
  const Mesh& mesh = bundle.mesh();
  check_size(o.size);
  TVF_CHECK(values.size() == static_cast<size_t>(mesh.num_vertices()), "{} values for {} vertices", values.size(),
            mesh.num_vertices());
  auto [lo, hi] = colour_range(values);
  if (std::isfinite(o.lo)) lo = o.lo;
  if (std::isfinite(o.hi)) hi = o.hi;
  if (!(hi > lo)) hi = lo + 1e-6;
  Image img;
  if (bundle.is_flat()) {
    img = planar_scalar(mesh, values, lo, hi, o);
  } else {
    std::vector<std::uint32_t> colors(values.size());
    for (size_t v = 0; v < values.size(); ++v)
      colors[v] = std::isfinite(values[v]) ? magma((values[v] - lo) / (hi - lo)) : o.nan_color;
    MeshRenderer renderer;
    renderer.set_mesh(mesh);
    renderer.set_colors(colors);
    RenderOptions ro;
    ro.width = ro.height = o.size;
    ro.lighting = o.surface.lighting;
    img = renderer.render(surface_camera(mesh, o.surface), ro);
  }
  return o.legend ? with_legend(img, lo, hi, o.label) : img;
}

Image curve_picture(const TangentBundle& bundle, const Field& field, double t,
                    const std::vector<std::vector<Vec3>>& curves, std::span<const Vec3> seeds,
                    const CurvePictureOptions& o) {
  check_size(o.size);
  const Mesh& mesh = bundle.mesh();
  const double width = o.line_width > 0 ? o.line_width : std::max(1.5, o.size / 300.0);
  if (!bundle.is_flat()) {
    MeshRenderer renderer;
    renderer.set_mesh(mesh);
    renderer.set_colors(std::vector<std::uint32_t>(static_cast<size_t>(mesh.num_vertices()), 0xD9D9D9u));
    std::vector<RenderLine> lines;
    std::vector<RenderMarker> markers;
    for (const auto& c : o.under) lines.push_back({c, o.under_color, 3 * width, true, true});
    for (const auto& c : curves) {
      lines.push_back({c, o.color, width, true});
      if (o.dots)
        for (const Vec3& x : c) markers.push_back({x, o.color, 0.9 * width, 0.0});  // as on the plane: no outline
    }
    for (const Vec3& s : seeds) markers.push_back({s, 0xFFFFFF, 2.5 * width});
    RenderOptions ro;
    ro.width = ro.height = o.size;
    ro.lighting = o.surface.lighting;
    SurfaceView view = o.surface;
    if (o.face_curves) {
      std::vector<std::vector<Vec3>> shown = curves;  // the sketch under them too
      shown.insert(shown.end(), o.under.begin(), o.under.end());
      view.direction = facing(mesh, shown, seeds, view.direction);
    }
    return renderer.render(surface_camera(mesh, view), ro, lines, markers);
  }
  TextureOptions texture = o.texture;
  texture.size = o.size;
  TextureAnimator animator(bundle, field, texture);
  animator.advance(t);
  Image img = animator.picture();
  if (!o.under.empty()) draw_curves(img, animator, o.under, {}, o.under_color, 3 * width, false);
  draw_curves(img, animator, curves, seeds, o.color, width, o.dots);
  return img;
}

void draw_curves(Image& img, const TextureAnimator& animator, const std::vector<std::vector<Vec3>>& curves,
                 std::span<const Vec3> seeds, std::uint32_t color, double width, bool dots) {
  const double cr_ = ((color >> 16) & 0xFF) / 255.0, cg = ((color >> 8) & 0xFF) / 255.0, cb = (color & 0xFF) / 255.0;
  cairo_surface_t* surface = nullptr;
  cairo_t* cr = cairo_on(img, surface);
  cairo_set_line_cap(cr, CAIRO_LINE_CAP_ROUND);
  cairo_set_line_join(cr, CAIRO_LINE_JOIN_ROUND);
  for (const auto& c : curves) {
    if (c.empty()) continue;
    cairo_new_path(cr);
    for (size_t k = 0; k < c.size(); ++k) {
      const Vec2 p = animator.to_pixel(c[k].head<2>());
      if (k == 0) cairo_move_to(cr, p.x(), p.y());
      else cairo_line_to(cr, p.x(), p.y());
    }
    cairo_set_source_rgb(cr, 0, 0, 0);
    cairo_set_line_width(cr, 2.2 * width);
    cairo_stroke_preserve(cr);
    cairo_set_source_rgb(cr, cr_, cg, cb);
    cairo_set_line_width(cr, width);
    cairo_stroke(cr);
    if (dots) {
      for (const Vec3& x : c) {
        const Vec2 p = animator.to_pixel(x.head<2>());
        cairo_new_sub_path(cr);
        cairo_arc(cr, p.x(), p.y(), 0.9 * width, 0, 2 * kPi);
      }
      cairo_set_source_rgb(cr, cr_, cg, cb);
      cairo_fill(cr);
    }
  }
  for (const Vec3& s : seeds) {
    const Vec2 p = animator.to_pixel(s.head<2>());
    cairo_new_sub_path(cr);
    cairo_arc(cr, p.x(), p.y(), 2.5 * width, 0, 2 * kPi);
    cairo_set_source_rgb(cr, 1, 1, 1);
    cairo_fill_preserve(cr);
    cairo_set_source_rgb(cr, 0, 0, 0);
    cairo_set_line_width(cr, std::max(1.0, 0.5 * width));
    cairo_stroke(cr);
  }
  cairo_done(cr, surface);
}

}  // namespace tvf