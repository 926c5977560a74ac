#include "tvf/analysis/coherence.h"

#include "tvf/core/error.h"

#include <tbb/parallel_for.h>

#include <cmath>

namespace tvf {

std::vector<double> coherence(const Field& field) {
  const int n = field.frames();
  std::vector<double> y(static_cast<size_t>(n > 1 ? n - 1 : 0), 0.0);
  // One task per frame pair; each sum runs in vertex order, so results do not depend on
  // the number of threads.
  tbb::parallel_for(0, n - 1, [&](int i) {
    const auto a = field.frame(i);
    const auto b = field.frame(i + 1);
    double sum = 0.0;
    for (size_t k = 0; k < a.size(); ++k) sum += std::abs(b[k] - a[k]);
    y[static_cast<size_t>(i)] = sum;
  });
  return y;
}

std::string coherence_csv(const Field& field, const std::vector<double>& y) {
  TVF_CHECK(y.size() + 1 == static_cast<size_t>(field.frames()) || (y.empty() && field.frames() <= 1),
            "{} coherence values for {} frames", y.size(), field.frames());
  std::string csv = "frame,t,coherence\n";
  for (size_t i = 0; i < y.size(); ++i)
    csv += fmt::format("{},{:.17g},{:.17g}\n", i, field.time().time(static_cast<int>(i)), y[i]);
  return csv;
}

}  // namespace tvf
