#include "tvf/synth/exemplar.h"

#include "tvf/core/error.h"

#include <fmt/format.h>

#include <algorithm>
#include <array>
#include <cmath>
#include <csetjmp>
#include <cstdio>
#include <fstream>
#include <numbers>
#include <random>

// libjpeg's header needs <cstdio> first.
#include <jpeglib.h>

namespace tvf {

namespace {

constexpr float kByte = 1.0f / 255.0f;

float luminance(float r, float g, float b) { return 0.2126f * r + 0.7152f * g + 0.0722f * b; }

// libjpeg reports errors through a callback; this one jumps back with the message.
struct JpegError {
  jpeg_error_mgr mgr;
  std::jmp_buf jump;
  char message[JMSG_LENGTH_MAX];
};

void jpeg_error_exit(j_common_ptr info) {
  auto* err = reinterpret_cast<JpegError*>(info->err);
  (*info->err->format_message)(info, err->message);
  std::longjmp(err->jump, 1);
}

// Plain C state only between setjmp and longjmp (no destructors are skipped).
Image read_jpeg(const std::string& path) {
  std::FILE* file = std::fopen(path.c_str(), "rb");
  if (!file) throw_input_error(path, "", "cannot open the JPEG");
  jpeg_decompress_struct info;
  JpegError err;
  info.err = jpeg_std_error(&err.mgr);
  err.mgr.error_exit = jpeg_error_exit;
  err.message[0] = 0;
  unsigned char* volatile buffer = nullptr;
  int width = 0, height = 0;
  if (setjmp(err.jump)) {
    jpeg_destroy_decompress(&info);
    std::fclose(file);
    std::free(buffer);
    throw_input_error(path, "", fmt::format("cannot read the JPEG ({})", err.message));
  }
  jpeg_create_decompress(&info);
  jpeg_stdio_src(&info, file);
  jpeg_read_header(&info, TRUE);
  info.out_color_space = JCS_RGB;
  jpeg_start_decompress(&info);
  width = static_cast<int>(info.output_width);
  height = static_cast<int>(info.output_height);
  const size_t row = static_cast<size_t>(width) * 3;
  buffer = static_cast<unsigned char*>(std::malloc(row * static_cast<size_t>(height)));
  while (info.output_scanline < info.output_height) {
    unsigned char* line = buffer + row * info.output_scanline;
    jpeg_read_scanlines(&info, &line, 1);
  }
  jpeg_finish_decompress(&info);
  jpeg_destroy_decompress(&info);
  std::fclose(file);
  Image image(width, height);
  for (size_t i = 0; i < image.pixels.size(); ++i)
    image.pixels[i] = rgb(buffer[3 * i], buffer[3 * i + 1], buffer[3 * i + 2]);
  std::free(buffer);
  return image;
}

}  // namespace

Exemplar exemplar_from_image(const Image& image, int channels) {
  TVF_CHECK(channels == 1 || channels == 3, "channels = {}", channels);
  Exemplar e(image.width, image.height, channels);
  for (int y = 0; y < image.height; ++y)
    for (int x = 0; x < image.width; ++x) {
      const std::uint32_t p = image.at(x, y);
      const float r = static_cast<float>((p >> 16) & 0xFF) * kByte;
      const float g = static_cast<float>((p >> 8) & 0xFF) * kByte;
      const float b = static_cast<float>(p & 0xFF) * kByte;
      if (channels == 1) {
        e.at(x, y, 0) = luminance(r, g, b);
      } else {
        e.at(x, y, 0) = r;
        e.at(x, y, 1) = g;
        e.at(x, y, 2) = b;
      }
    }
  return e;
}

Image exemplar_to_image(const Exemplar& e) {
  Image image(e.width, e.height);
  auto byte = [](float v) { return static_cast<std::uint8_t>(std::lround(std::clamp(v, 0.f, 1.f) * 255.f)); };
  for (int y = 0; y < e.height; ++y)
    for (int x = 0; x < e.width; ++x)
      image.at(x, y) = e.channels == 1 ? gray(byte(e.at(x, y, 0)))
                                       : rgb(byte(e.at(x, y, 0)), byte(e.at(x, y, 1)), byte(e.at(x, y, 2)));
  return image;
}

Exemplar load_exemplar(const std::string& path, int channels) {
  if (channels != 1 && channels != 3)
    throw Error(fmt::format("{}: exemplars have 1 (height) or 3 (colour) channels, not {}", path, channels));
  std::ifstream in(path, std::ios::binary);
  if (!in) throw_input_error(path, "", "no such exemplar picture (give a PNG or JPEG file)");
  std::array<unsigned char, 8> magic{};
  in.read(reinterpret_cast<char*>(magic.data()), magic.size());
  const bool png = in.gcount() == 8 && magic[0] == 0x89 && magic[1] == 'P' && magic[2] == 'N' && magic[3] == 'G';
  const bool jpeg = in.gcount() >= 3 && magic[0] == 0xFF && magic[1] == 0xD8 && magic[2] == 0xFF;
  in.close();
  if (!png && !jpeg) throw_input_error(path, "", "not a PNG or JPEG picture");
  const Image image = png ? read_png(path) : read_jpeg(path);
  if (image.width < 8 || image.height < 8)
    throw_input_error(path, "", fmt::format("the exemplar is {}×{} pixels; it must be at least 8×8", image.width, image.height));
  return exemplar_from_image(image, channels);
}

Exemplar downsample(const Exemplar& e) {
  Exemplar d(std::max(1, e.width / 2), std::max(1, e.height / 2), e.channels);
  d.tileable = e.tileable && e.width % 2 == 0 && e.height % 2 == 0;
  for (int y = 0; y < d.height; ++y)
    for (int x = 0; x < d.width; ++x)
      for (int c = 0; c < e.channels; ++c) {
        const int x0 = std::min(2 * x, e.width - 1), x1 = std::min(2 * x + 1, e.width - 1);
        const int y0 = std::min(2 * y, e.height - 1), y1 = std::min(2 * y + 1, e.height - 1);
        d.at(x, y, c) = 0.25f * (e.at(x0, y0, c) + e.at(x1, y0, c) + e.at(x0, y1, c) + e.at(x1, y1, c));
      }
  return d;
}

namespace {

constexpr double kTau = 2 * std::numbers::pi;

// A smooth tileable noise: a sum of a few random waves whose frequencies are whole
// numbers of periods across the tile.
struct TileNoise {
  struct Wave {
    double fx, fy, phase, amplitude;
  };
  std::vector<Wave> waves;
  TileNoise(std::mt19937_64& rng, int count, int max_frequency) {
    std::uniform_int_distribution<int> f(-max_frequency, max_frequency);
    std::uniform_real_distribution<double> u(0, 1);
    for (int i = 0; i < count; ++i) {
      int fx = f(rng), fy = f(rng);
      if (fx == 0 && fy == 0) fx = 1;
      waves.push_back({double(fx), double(fy), kTau * u(rng), 1.0 / std::hypot(fx, fy)});
    }
  }
  // u, v in [0, 1): a value of about unit size.
  double operator()(double u, double v) const {
    double s = 0, norm = 0;
    for (const auto& w : waves) {
      s += w.amplitude * std::sin(kTau * (w.fx * u + w.fy * v) + w.phase);
      norm += w.amplitude * w.amplitude;
    }
    return s / std::sqrt(0.5 * norm);
  }
};

}  // namespace

Exemplar make_procedural_exemplar(ProceduralExemplar kind, int size, std::uint64_t seed) {
  if (size < 16 || size > 4096) throw Error(fmt::format("procedural exemplar size {}: must be in [16, 4096]", size));
  std::mt19937_64 rng(seed);
  const bool height = kind == ProceduralExemplar::ridges || kind == ProceduralExemplar::dunes;
  Exemplar e(size, size, height ? 1 : 3);
  e.tileable = true;
  const TileNoise wobble(rng, 6, 2);
  const TileNoise grain(rng, 24, 9);
  auto mix = [](const std::array<float, 3>& a, const std::array<float, 3>& b, double s) {
    const float t = static_cast<float>(std::clamp(s, 0.0, 1.0));
    return std::array<float, 3>{a[0] + (b[0] - a[0]) * t, a[1] + (b[1] - a[1]) * t, a[2] + (b[2] - a[2]) * t};
  };
  const int bands = 6;
  if (kind == ProceduralExemplar::pebbles) {
    // Jittered cells, wrapped: the distance to the nearest and second-nearest centre.
    const int cells = std::max(3, size / 14);
    std::uniform_real_distribution<double> u(0.15, 0.85);
    std::vector<std::array<double, 2>> centre(static_cast<size_t>(cells * cells));
    std::vector<std::array<float, 3>> colour(centre.size());
    const std::array<std::array<float, 3>, 4> palette{{{0.62f, 0.55f, 0.47f}, {0.45f, 0.40f, 0.36f},
                                                       {0.72f, 0.64f, 0.52f}, {0.55f, 0.47f, 0.40f}}};
    std::uniform_int_distribution<int> pick(0, 3);
    std::uniform_real_distribution<float> shade(0.85f, 1.15f);
    for (int j = 0; j < cells; ++j)
      for (int i = 0; i < cells; ++i) {
        centre[static_cast<size_t>(j * cells + i)] = {(i + u(rng)) / cells, (j + u(rng)) / cells};
        const auto base = palette[static_cast<size_t>(pick(rng))];
        const float s = shade(rng);
        colour[static_cast<size_t>(j * cells + i)] = {base[0] * s, base[1] * s, base[2] * s};
      }
    for (int y = 0; y < size; ++y)
      for (int x = 0; x < size; ++x) {
        const double px = (x + 0.5) / size, py = (y + 0.5) / size;
        double d1 = 1e9, d2 = 1e9;
        size_t best = 0;
        const int ci = static_cast<int>(px * cells), cj = static_cast<int>(py * cells);
        for (int dj = -2; dj <= 2; ++dj)
          for (int di = -2; di <= 2; ++di) {
            const int i = ((ci + di) % cells + cells) % cells, j = ((cj + dj) % cells + cells) % cells;
            const auto& c = centre[static_cast<size_t>(j * cells + i)];
            const double ox = c[0] + std::floor(static_cast<double>(ci + di) / cells) - px;
            const double oy = c[1] + std::floor(static_cast<double>(cj + dj) / cells) - py;
            const double d = std::hypot(ox, oy) * cells;
            if (d < d1) {
              d2 = d1;
              d1 = d;
              best = static_cast<size_t>(j * cells + i);
            } else if (d < d2) {
              d2 = d;
            }
          }
        const double edge = (d2 - d1) * 0.5;  // distance to the cell border, in cell units
        const double inside = std::clamp((edge - 0.06) / 0.08, 0.0, 1.0);
        const double dome = std::clamp(1.1 - 0.9 * d1, 0.0, 1.0);
        const double g = 0.04 * grain(px, py);
        const auto stone = colour[best];
        const std::array<float, 3> mortar{0.18f, 0.15f, 0.13f};
        const auto c = mix(mortar, stone, inside);
        for (int k = 0; k < 3; ++k) e.at(x, y, k) = std::clamp(static_cast<float>(c[static_cast<size_t>(k)] * (0.75 + 0.35 * dome) + g), 0.f, 1.f);
      }
    return e;
  }
  for (int y = 0; y < size; ++y)
    for (int x = 0; x < size; ++x) {
      const double u = (x + 0.5) / size, v = (y + 0.5) / size;
      const double phase = bands * v + 0.35 * wobble(u, v) / bands * 2;
      const double f = phase - std::floor(phase);
      switch (kind) {
        case ProceduralExemplar::stripes: {
          const double s = 0.5 + 0.5 * std::cos(kTau * f);
          const double g = 0.06 * grain(u, v);
          const auto c = mix({0.36f, 0.20f, 0.10f}, {0.90f, 0.72f, 0.48f}, std::pow(s, 1.4) + g);
          for (int k = 0; k < 3; ++k) e.at(x, y, k) = c[static_cast<size_t>(k)];
          break;
        }
        case ProceduralExemplar::ridges: {
          const double r = 1.0 - std::abs(std::sin(std::numbers::pi * f));
          e.at(x, y, 0) = static_cast<float>(std::clamp(0.1 + 0.75 * std::pow(r, 1.5) + 0.05 * grain(u, v), 0.0, 1.0));
          break;
        }
        case ProceduralExemplar::dunes: {
          const double h = f < 0.75 ? f / 0.75 : (1.0 - f) / 0.25;  // long windward, steep lee side
          const double s = h * h * (3 - 2 * h);
          e.at(x, y, 0) = static_cast<float>(std::clamp(0.1 + 0.75 * s + 0.03 * grain(u, v), 0.0, 1.0));
          break;
        }
        case ProceduralExemplar::pebbles:
          break;
      }
    }
  return e;
}

ProceduralExemplar parse_procedural_exemplar(const std::string& name) {
  if (name == "stripes") return ProceduralExemplar::stripes;
  if (name == "pebbles") return ProceduralExemplar::pebbles;
  if (name == "ridges") return ProceduralExemplar::ridges;
  if (name == "dunes") return ProceduralExemplar::dunes;
  throw Error(fmt::format("unknown procedural exemplar '{}': choose stripes, pebbles, ridges or dunes", name));
}

}  // namespace tvf
