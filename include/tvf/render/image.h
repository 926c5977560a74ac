#pragma once
// A picture in memory and its PNG file. Pixels are 32-bit words 0x00RRGGBB, rows top to
// bottom — Cairo's CAIRO_FORMAT_RGB24 layout, so Cairo can draw on an Image in place
// (overlays) and write it as PNG (cairo_surface_write_to_png).
#include <cstdint>
#include <string>
#include <vector>

namespace tvf {

struct Image {
  int width = 0;
  int height = 0;
  std::vector<std::uint32_t> pixels;  // width × height, row-major, top row first

  Image() = default;
  Image(int w, int h) : width(w), height(h), pixels(static_cast<size_t>(w) * static_cast<size_t>(h), 0u) {}
  std::uint32_t& at(int x, int y) { return pixels[static_cast<size_t>(y) * static_cast<size_t>(width) + static_cast<size_t>(x)]; }
  std::uint32_t at(int x, int y) const { return pixels[static_cast<size_t>(y) * static_cast<size_t>(width) + static_cast<size_t>(x)]; }
};

inline std::uint32_t rgb(std::uint8_t r, std::uint8_t g, std::uint8_t b) {
  return (std::uint32_t{r} << 16) | (std::uint32_t{g} << 8) | std::uint32_t{b};
}
inline std::uint32_t gray(std::uint8_t v) { return rgb(v, v, v); }

// Writes `image` as PNG through a temporary name (atomic). Throws tvf::Error naming the
// file on failure.
void write_png(const std::string& path, const Image& image);
// Reads a PNG (any Cairo-readable format, converted to RGB24). Throws tvf::Error.
Image read_png(const std::string& path);

}  // namespace tvf
