#pragma once
// Shared measurements of the synthesis tests: fields from formulas, histograms, the
// structure tensor's orientation.
#include "tvf/field/field.h"
#include "tvf/mesh/mesh.h"
#include "tvf/synth/exemplar.h"

#include <algorithm>
#include <cmath>
#include <numbers>
#include <vector>

namespace tvf::test {

template <class F>
Field field_from(const Mesh& mesh, TimeSampling ts, F&& f) {
  Field field(ts, mesh.num_vertices());
  for (int j = 0; j < ts.frames; ++j)
    for (int v = 0; v < mesh.num_vertices(); ++v) field.at(j, v) = f(mesh.position(v), ts.time(j));
  return field;
}

// Per-channel histograms of `bins` bins over [0, 1], normalised to sum 1 per channel.
inline std::vector<double> histogram(const std::vector<float>& values, int channels, int bins) {
  std::vector<double> h(static_cast<size_t>(channels * bins), 0.0);
  const size_t n = values.size() / static_cast<size_t>(channels);
  for (size_t i = 0; i < n; ++i)
    for (int c = 0; c < channels; ++c) {
      const float v = std::clamp(values[i * static_cast<size_t>(channels) + static_cast<size_t>(c)], 0.f, 1.f);
      const int b = std::min(bins - 1, static_cast<int>(v * bins));
      h[static_cast<size_t>(c * bins + b)] += 1.0 / static_cast<double>(n);
    }
  return h;
}

// L1 distance of two histograms, averaged over channels (0: equal, 2: disjoint).
inline double histogram_distance(const std::vector<double>& a, const std::vector<double>& b, int channels) {
  double s = 0;
  for (size_t i = 0; i < a.size(); ++i) s += std::abs(a[i] - b[i]);
  return s / channels;
}

// Luminance of an interleaved picture.
inline std::vector<double> luminance(const std::vector<float>& x, int channels) {
  std::vector<double> l(x.size() / static_cast<size_t>(channels));
  for (size_t i = 0; i < l.size(); ++i) {
    const float* p = x.data() + i * static_cast<size_t>(channels);
    l[i] = channels == 1 ? p[0] : 0.2126 * p[0] + 0.7152 * p[1] + 0.0722 * p[2];
  }
  return l;
}

// The direction of the stripes of a gray picture over a box (image coordinates, y down):
// perpendicular to the structure tensor's dominant gradient direction. Returns the
// angle in [0, π) and, in `coherence`, (λ1 − λ2)/(λ1 + λ2) of the tensor.
inline double stripe_angle(const std::vector<double>& g, int w, int x0, int y0, int x1, int y1, double& coherence) {
  double jxx = 0, jxy = 0, jyy = 0;
  for (int y = std::max(1, y0); y < std::min(y1, static_cast<int>(g.size()) / w - 1); ++y)
    for (int x = std::max(1, x0); x < std::min(x1, w - 1); ++x) {
      const double gx = 0.5 * (g[static_cast<size_t>(y * w + x + 1)] - g[static_cast<size_t>(y * w + x - 1)]);
      const double gy = 0.5 * (g[static_cast<size_t>((y + 1) * w + x)] - g[static_cast<size_t>((y - 1) * w + x)]);
      jxx += gx * gx, jxy += gx * gy, jyy += gy * gy;
    }
  const double gradient_angle = 0.5 * std::atan2(2 * jxy, jxx - jyy);
  const double root = std::hypot(jxx - jyy, 2 * jxy);
  coherence = root / std::max(1e-30, jxx + jyy);
  double a = gradient_angle + std::numbers::pi / 2;
  a = std::fmod(a, std::numbers::pi);
  if (a < 0) a += std::numbers::pi;
  return a;
}

// Difference of two undirected angles, in [0, π/2].
inline double line_angle_difference(double a, double b) {
  double d = std::fmod(std::abs(a - b), std::numbers::pi);
  return std::min(d, std::numbers::pi - d);
}

}  // namespace tvf::test
