#include "tvf/field/time_sampling.h"

#include <algorithm>
#include <cmath>

namespace tvf {

std::vector<double> TimeSampling::times() const {
  std::vector<double> t(static_cast<size_t>(std::max(frames, 0)));
  for (int j = 0; j < frames; ++j) t[static_cast<size_t>(j)] = time(j);
  return t;
}

void TimeSampling::locate(double t, int& j, double& w) const {
  j = 0;
  w = 0.0;
  if (frames <= 1 || !(t1 != t0)) return;
  const int last = frames - 1;
  // Position in frame units, clamped to [0, N − 1] (NaN goes to 0).
  double s = (t - t0) / (t1 - t0) * static_cast<double>(last);
  if (!(s > 0.0)) s = 0.0;
  if (s > static_cast<double>(last)) s = static_cast<double>(last);
  // At a frame's own time (as time() computes it) the frame is returned exactly.
  const int nearest = static_cast<int>(std::lround(s));
  if (time(nearest) == t || s == static_cast<double>(nearest)) {
    j = std::min(nearest, last - 1);
    w = nearest > j ? 1.0 : 0.0;
    return;
  }
  j = std::min(static_cast<int>(std::floor(s)), last - 1);
  // The weight from the frame times themselves, so that (1 − w)·time(j) + w·time(j + 1)
  // reproduces t as closely as rounding allows.
  const double a = time(j);
  const double b = time(j + 1);
  w = std::clamp((t - a) / (b - a), 0.0, 1.0);
}

}  // namespace tvf
