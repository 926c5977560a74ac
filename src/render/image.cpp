#include "tvf/render/image.h"

#include "tvf/core/atomic_output.h"
#include "tvf/core/error.h"

#include <cairo.h>

#include <cstring>
#include <filesystem>

namespace tvf {

namespace fs = std::filesystem;

void write_png(const std::string& path, const Image& image) {
  TVF_CHECK(image.width > 0 && image.height > 0 && image.pixels.size() == static_cast<size_t>(image.width) * static_cast<size_t>(image.height),
            "image {}×{} with {} pixels", image.width, image.height, image.pixels.size());
  cairo_surface_t* surface = cairo_image_surface_create(CAIRO_FORMAT_RGB24, image.width, image.height);
  cairo_surface_flush(surface);
  unsigned char* data = cairo_image_surface_get_data(surface);
  const int stride = cairo_image_surface_get_stride(surface);
  for (int y = 0; y < image.height; ++y)
    std::memcpy(data + static_cast<size_t>(y) * static_cast<size_t>(stride), &image.pixels[static_cast<size_t>(y) * static_cast<size_t>(image.width)],
                static_cast<size_t>(image.width) * 4);
  cairo_surface_mark_dirty(surface);
  const fs::path tmp = temporary_sibling(path);
  const cairo_status_t status = cairo_surface_write_to_png(surface, tmp.c_str());
  cairo_surface_destroy(surface);
  std::error_code ec;
  if (status != CAIRO_STATUS_SUCCESS) {
    fs::remove(tmp, ec);
    throw_input_error(path, "", fmt::format("cannot write the PNG ({})", cairo_status_to_string(status)));
  }
  fs::rename(tmp, path, ec);
  if (ec) {
    fs::remove(tmp, ec);
    throw_input_error(path, "", "cannot move the finished PNG into place");
  }
}

Image read_png(const std::string& path) {
  cairo_surface_t* png = cairo_image_surface_create_from_png(path.c_str());
  if (cairo_surface_status(png) != CAIRO_STATUS_SUCCESS) {
    const std::string why = cairo_status_to_string(cairo_surface_status(png));
    cairo_surface_destroy(png);
    throw_input_error(path, "", fmt::format("cannot read the PNG ({})", why));
  }
  Image image(cairo_image_surface_get_width(png), cairo_image_surface_get_height(png));
  cairo_surface_t* surface = cairo_image_surface_create(CAIRO_FORMAT_RGB24, image.width, image.height);
  cairo_t* cr = cairo_create(surface);
  cairo_set_source_surface(cr, png, 0, 0);
  cairo_paint(cr);
  cairo_destroy(cr);
  cairo_surface_flush(surface);
  const unsigned char* data = cairo_image_surface_get_data(surface);
  const int stride = cairo_image_surface_get_stride(surface);
  for (int y = 0; y < image.height; ++y)
    std::memcpy(&image.pixels[static_cast<size_t>(y) * static_cast<size_t>(image.width)], data + static_cast<size_t>(y) * static_cast<size_t>(stride),
                static_cast<size_t>(image.width) * 4);
  for (auto& p : image.pixels) p &= 0x00FFFFFFu;
  cairo_surface_destroy(surface);
  cairo_surface_destroy(png);
  return image;
}

}  // namespace tvf
