#include "tvf/synth/texture_optimization.h"

#include "tvf/core/error.h"

#include <Eigen/Eigenvalues>
#include <fmt/format.h>
#include <nanoflann.hpp>
#include <tbb/blocked_range.h>
#include <tbb/parallel_for.h>

#include <algorithm>
#include <cmath>
#include <random>

namespace tvf {

namespace {

// nanoflann's dataset interface over the reduced vectors.
struct ReducedCloud {
  const float* data = nullptr;
  size_t n = 0;
  size_t d = 0;
  size_t kdtree_get_point_count() const { return n; }
  float kdtree_get_pt(size_t i, size_t dim) const { return data[i * d + dim]; }
  template <class Box>
  bool kdtree_get_bbox(Box&) const { return false; }
};

using KdTree = nanoflann::KDTreeSingleIndexAdaptor<nanoflann::L2_Simple_Adaptor<float, ReducedCloud>, ReducedCloud, -1,
                                                   std::uint32_t>;

}  // namespace

struct ExemplarIndex::Tree {
  ReducedCloud cloud;
  std::unique_ptr<KdTree> tree;
};

ExemplarIndex::ExemplarIndex(const Exemplar& exemplar, const ExemplarIndexOptions& options)
    : exemplar_(exemplar), options_(options) {
  const int w = options.size;
  if (w < 3 || w % 2 == 0) throw Error(fmt::format("neighbourhood size {}: must be odd and at least 3", w));
  if (options.pca_dimensions < 1) throw Error(fmt::format("PCA dimensions {}: must be at least 1", options.pca_dimensions));
  if (options.candidates < 1) throw Error(fmt::format("search candidates {}: must be at least 1", options.candidates));
  if (!(options.search_eps >= 0)) throw Error(fmt::format("search eps {}: must be at least 0", options.search_eps));
  channels_ = exemplar.channels;
  dimension_ = w * w * channels_;
  const bool wrap = exemplar.tileable;
  const int nx = wrap ? exemplar.width : exemplar.width - w + 1;
  const int ny = wrap ? exemplar.height : exemplar.height - w + 1;
  if (nx < 1 || ny < 1)
    throw Error(fmt::format("the exemplar ({}×{} pixels at this level) is smaller than one {}×{} neighbourhood; "
                            "give a larger exemplar or fewer levels", exemplar.width, exemplar.height, w, w));
  count_ = nx * ny;
  values_.resize(static_cast<size_t>(count_) * static_cast<size_t>(dimension_));
  positions_.resize(static_cast<size_t>(count_));
  for (int y0 = 0; y0 < ny; ++y0)
    for (int x0 = 0; x0 < nx; ++x0) {
      const int m = y0 * nx + x0;
      positions_[static_cast<size_t>(m)] = {x0, y0};
      float* v = values_.data() + static_cast<size_t>(m) * static_cast<size_t>(dimension_);
      for (int r = 0; r < w; ++r)
        for (int c = 0; c < w; ++c)
          for (int k = 0; k < channels_; ++k)
            *v++ = exemplar.at((x0 + c) % exemplar.width, (y0 + r) % exemplar.height, k);
    }

  // PCA of the neighbourhood vectors (in double; the centred matrix is formed explicitly,
  // not as a broadcast expression inside a product).
  const auto D = static_cast<Eigen::Index>(dimension_);
  const Eigen::Map<const Eigen::MatrixXf> all(values_.data(), D, count_);  // one column each
  Eigen::MatrixXd centred = all.cast<double>();
  const Eigen::VectorXd mean = centred.rowwise().mean();
  for (Eigen::Index m = 0; m < centred.cols(); ++m) centred.col(m) -= mean;
  const Eigen::MatrixXd cov = centred * centred.transpose() / std::max(1, count_);
  Eigen::SelfAdjointEigenSolver<Eigen::MatrixXd> eig(cov);
  reduced_ = std::min(options.pca_dimensions, dimension_);
  const double total = std::max(1e-30, eig.eigenvalues().sum());
  const Eigen::MatrixXd top = eig.eigenvectors().rightCols(reduced_);  // largest last
  explained_ = eig.eigenvalues().tail(reduced_).sum() / total;
  mean_.resize(static_cast<size_t>(dimension_));
  for (int i = 0; i < dimension_; ++i) mean_[static_cast<size_t>(i)] = static_cast<float>(mean(i));
  basis_.resize(static_cast<size_t>(reduced_) * static_cast<size_t>(dimension_));
  for (int j = 0; j < reduced_; ++j)
    for (int i = 0; i < dimension_; ++i)
      basis_[static_cast<size_t>(j) * static_cast<size_t>(dimension_) + static_cast<size_t>(i)] = static_cast<float>(top(i, j));
  // The reduced vectors, as a query is reduced (nearest()): float basis, float difference.
  const Eigen::Map<const Eigen::MatrixXf> B(basis_.data(), D, reduced_);  // column j = basis row j
  reduced_values_.resize(static_cast<size_t>(count_) * static_cast<size_t>(reduced_));
  Eigen::Map<Eigen::MatrixXf> R(reduced_values_.data(), reduced_, count_);
  const Eigen::MatrixXf centred_f = centred.cast<float>();
  R.noalias() = B.transpose() * centred_f;

  sorted_.resize(static_cast<size_t>(channels_));
  for (int c = 0; c < channels_; ++c) {
    auto& v = sorted_[static_cast<size_t>(c)];
    for (size_t i = static_cast<size_t>(c); i < exemplar.pixels.size(); i += static_cast<size_t>(channels_))
      v.push_back(exemplar.pixels[i]);
    std::sort(v.begin(), v.end());
  }

  tree_ = std::make_unique<Tree>();
  tree_->cloud = {reduced_values_.data(), static_cast<size_t>(count_), static_cast<size_t>(reduced_)};
  tree_->tree = std::make_unique<KdTree>(static_cast<int>(reduced_), tree_->cloud,
                                         nanoflann::KDTreeSingleIndexAdaptorParams(16));
}

ExemplarIndex::~ExemplarIndex() = default;

int ExemplarIndex::nearest(const float* query, float& distance2) const {
  constexpr int kMaxCandidates = 16;
  float projected[256];
  float diff[1024];
  TVF_CHECK(reduced_ <= 256, "reduced dimension {}", reduced_);
  // Project (query − mean) onto the basis.
  const bool small = dimension_ <= 1024;
  for (int i = 0; i < dimension_ && small; ++i) diff[i] = query[i] - mean_[static_cast<size_t>(i)];
  for (int j = 0; j < reduced_; ++j) {
    const float* b = basis_.data() + static_cast<size_t>(j) * static_cast<size_t>(dimension_);
    float s = 0;
    if (small) {
      for (int i = 0; i < dimension_; ++i) s += b[i] * diff[i];
    } else {
      for (int i = 0; i < dimension_; ++i) s += b[i] * (query[i] - mean_[static_cast<size_t>(i)]);
    }
    projected[j] = s;
  }
  const int k = std::min({options_.candidates, kMaxCandidates, count_});
  std::uint32_t index[kMaxCandidates] = {};
  float dist[kMaxCandidates] = {};
  nanoflann::KNNResultSet<float, std::uint32_t> result(static_cast<size_t>(k));
  result.init(index, dist);
  tree_->tree->findNeighbors(result, projected, nanoflann::SearchParams(32, options_.search_eps));
  const int found = static_cast<int>(result.size());
  int best = static_cast<int>(index[0]);
  float best_d = std::numeric_limits<float>::max();
  for (int c = 0; c < found; ++c) {
    const float* v = values(static_cast<int>(index[c]));
    float d = 0;
    for (int i = 0; i < dimension_; ++i) {
      const float e = query[i] - v[i];
      d += e * e;
    }
    if (d < best_d) {
      best_d = d;
      best = static_cast<int>(index[c]);
    }
  }
  distance2 = best_d;
  return best;
}

OptimizeReport optimize_texture(const Neighbourhoods& nb, const ExemplarIndex& index, std::vector<float>& x,
                                const std::vector<float>& target, const OptimizeOptions& options) {
  TVF_CHECK(nb.size == index.size(), "neighbourhood size {} vs index {}", nb.size, index.size());
  const int C = index.channels();
  const int K = nb.size * nb.size;
  const int D = index.dimension();
  const int count = nb.count();
  TVF_CHECK(x.size() % static_cast<size_t>(C) == 0, "samples");
  const size_t samples = x.size() / static_cast<size_t>(C);
  const bool temporal = !target.empty() && options.temporal_weight > 0;
  if (temporal) TVF_CHECK(target.size() == x.size(), "target {} vs x {}", target.size(), x.size());
  OptimizeReport report;
  std::vector<int> match(static_cast<size_t>(count));
  std::vector<float> omega(static_cast<size_t>(count)), dist(static_cast<size_t>(count));
  std::vector<double> acc(x.size()), wsum(samples);
  const double exponent = (options.robust_exponent - 2.0) / 2.0;  // on squared distances
  for (int it = 0; it < options.iterations; ++it) {
    // E-step.
    tbb::parallel_for(tbb::blocked_range<int>(0, count, 256), [&](const tbb::blocked_range<int>& range) {
      std::vector<float> q(static_cast<size_t>(D));
      for (int p = range.begin(); p < range.end(); ++p) {
        const Tap* taps = nb.taps.data() + static_cast<size_t>(p) * static_cast<size_t>(K);
        for (int k = 0; k < K; ++k) {
          const Tap& t = taps[k];
          for (int c = 0; c < C; ++c) {
            float s = 0;
            for (int i = 0; i < 4; ++i)
              if (t.weight[static_cast<size_t>(i)] != 0.f)
                s += t.weight[static_cast<size_t>(i)] * x[static_cast<size_t>(t.sample[static_cast<size_t>(i)]) * static_cast<size_t>(C) + static_cast<size_t>(c)];
            q[static_cast<size_t>(k * C + c)] = s;
          }
        }
        float d2 = 0;
        match[static_cast<size_t>(p)] = index.nearest(q.data(), d2);
        dist[static_cast<size_t>(p)] = d2;
        // Robust weight of the per-value RMS distance (floored so that exact matches do
        // not take over).
        const double rms2 = std::max(static_cast<double>(d2) / D, 1e-4);
        omega[static_cast<size_t>(p)] = static_cast<float>(std::pow(rms2, exponent));
      }
    });
    // M-step: splat the matched exemplar values.
    std::fill(acc.begin(), acc.end(), 0.0);
    std::fill(wsum.begin(), wsum.end(), 0.0);
    for (int p = 0; p < count; ++p) {
      const Tap* taps = nb.taps.data() + static_cast<size_t>(p) * static_cast<size_t>(K);
      const float* z = index.values(match[static_cast<size_t>(p)]);
      const double om = omega[static_cast<size_t>(p)];
      for (int k = 0; k < K; ++k) {
        const Tap& t = taps[k];
        for (int i = 0; i < 4; ++i) {
          const double w = om * t.weight[static_cast<size_t>(i)];
          if (w == 0) continue;
          const auto s = static_cast<size_t>(t.sample[static_cast<size_t>(i)]);
          wsum[s] += w;
          for (int c = 0; c < C; ++c) acc[s * static_cast<size_t>(C) + static_cast<size_t>(c)] += w * z[k * C + c];
        }
      }
    }
    size_t uncovered = 0;
    const double lambda = temporal ? options.temporal_weight : 0.0;
    for (size_t s = 0; s < samples; ++s) {
      if (wsum[s] <= 0) {
        ++uncovered;
        continue;
      }
      for (int c = 0; c < C; ++c) {
        const size_t i = s * static_cast<size_t>(C) + static_cast<size_t>(c);
        const double m = acc[i] / wsum[s];
        x[i] = static_cast<float>(temporal ? (m + lambda * target[i]) / (1 + lambda) : m);
      }
    }
    if (options.histogram_matching && samples > 1) {
      std::vector<std::uint32_t> order(samples);
      for (int c = 0; c < C; ++c) {
        const auto& ex = index.sorted_channel(c);
        for (size_t s = 0; s < samples; ++s) order[s] = static_cast<std::uint32_t>(s);
        std::sort(order.begin(), order.end(), [&](std::uint32_t a, std::uint32_t b) {
          return x[a * static_cast<size_t>(C) + static_cast<size_t>(c)] < x[b * static_cast<size_t>(C) + static_cast<size_t>(c)];
        });
        for (size_t k = 0; k < samples; ++k) {
          const size_t e = std::min(ex.size() - 1, (2 * k + 1) * ex.size() / (2 * samples));
          x[order[k] * static_cast<size_t>(C) + static_cast<size_t>(c)] = ex[e];
        }
      }
    }
    double total = 0;
    for (float d : dist) total += d;
    report.patch_distance = count > 0 ? std::sqrt(total / (static_cast<double>(count) * D)) : 0.0;
    report.uncovered = samples > 0 ? static_cast<double>(uncovered) / static_cast<double>(samples) : 0.0;
    report.iterations = it + 1;
  }
  return report;
}

void random_exemplar_pixels(const Exemplar& e, int num_samples, std::uint64_t seed, std::vector<float>& x) {
  std::mt19937_64 rng(seed);
  std::uniform_int_distribution<int> px(0, e.width - 1), py(0, e.height - 1);
  x.resize(static_cast<size_t>(num_samples) * static_cast<size_t>(e.channels));
  for (int s = 0; s < num_samples; ++s) {
    const int a = px(rng), b = py(rng);
    for (int c = 0; c < e.channels; ++c) x[static_cast<size_t>(s) * static_cast<size_t>(e.channels) + static_cast<size_t>(c)] = e.at(a, b, c);
  }
}

}  // namespace tvf
