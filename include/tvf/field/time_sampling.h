#pragma once
// Time sampling (DESIGN §3): frames t_j = t0 + j·(t1 − t0)/(N − 1), j = 0..N−1.
#include <vector>

namespace tvf {

struct TimeSampling {
  double t0 = 0.0;
  double t1 = 1.0;
  int frames = 100;

  double time(int j) const {
    return frames > 1 ? t0 + (t1 - t0) * static_cast<double>(j) / static_cast<double>(frames - 1)
                      : t0;
  }
  std::vector<double> times() const;
  // Frame interval holding t (clamped to the range) and the weight of its second frame:
  // t ≈ (1 − w)·time(j) + w·time(j + 1). For a single frame, j = 0 and w = 0.
  void locate(double t, int& j, double& w) const;
};

}  // namespace tvf
