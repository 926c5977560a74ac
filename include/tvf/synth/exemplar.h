#pragma once
// Exemplars of texture synthesis (synth/texture_optimization.h): a small picture whose
// look the synthesized texture copies. Pixels are floats in [0, 1], `channels` per pixel
// (3: RGB colour, 1: a height map), rows top to bottom, interleaved.
//
// Files: PNG (read through Cairo, render/image.h) and JPEG (libjpeg, Debian package
// libjpeg62-turbo-dev), chosen by the file's first bytes, not its name. Procedural
// exemplars are made in code so that the project ships no binary pictures.
#include "tvf/render/image.h"

#include <cstdint>
#include <string>
#include <vector>

namespace tvf {

struct Exemplar {
  int width = 0;
  int height = 0;
  int channels = 3;          // 3 (RGB) or 1 (gray / height)
  bool tileable = false;     // wraps around at the edges (procedural exemplars do)
  std::vector<float> pixels; // width × height × channels, row-major, top row first

  Exemplar() = default;
  Exemplar(int w, int h, int c)
      : width(w), height(h), channels(c), pixels(static_cast<size_t>(w) * static_cast<size_t>(h) * static_cast<size_t>(c), 0.f) {}
  float& at(int x, int y, int c) {
    return pixels[(static_cast<size_t>(y) * static_cast<size_t>(width) + static_cast<size_t>(x)) * static_cast<size_t>(channels) + static_cast<size_t>(c)];
  }
  float at(int x, int y, int c) const {
    return pixels[(static_cast<size_t>(y) * static_cast<size_t>(width) + static_cast<size_t>(x)) * static_cast<size_t>(channels) + static_cast<size_t>(c)];
  }
};

// Reads a PNG or JPEG exemplar. channels = 1 converts to luminance (Rec. 709 weights) —
// height maps; 3 keeps colour. Throws tvf::Error naming the file when it is missing, not
// a PNG/JPEG, unreadable, or smaller than 8×8 pixels.
Exemplar load_exemplar(const std::string& path, int channels = 3);

// Conversions to and from pictures (values clamped to [0, 1]; gray pictures for 1 channel).
Exemplar exemplar_from_image(const Image& image, int channels = 3);
Image exemplar_to_image(const Exemplar& exemplar);

// Half the resolution (2 × 2 box filter; odd sizes drop the last row/column).
Exemplar downsample(const Exemplar& exemplar);

// Procedural exemplars, tileable (they wrap around at the edges).
enum class ProceduralExemplar {
  stripes,   // wavy dark/light bands along x, `size`/6 pixels apart, colour: wood-like
  pebbles,   // rounded pebbles (a jittered cell pattern) in earthy colours, gaps of dark mortar
  ridges,    // a height map: ridges along x with valleys between (1 channel), for terrain
  dunes,     // a height map: asymmetric dune ridges along x (1 channel), for terrain
};
Exemplar make_procedural_exemplar(ProceduralExemplar kind, int size = 64, std::uint64_t seed = 1);
// "stripes" → stripes …; throws tvf::Error listing the names for an unknown one.
ProceduralExemplar parse_procedural_exemplar(const std::string& name);

}  // namespace tvf
