#include "tvf/synth/texture_optimization.h"

#include "tvf/core/error.h"

#include <Eigen/Eigenvalues>
#include <fmt/format.h>
#include <nanoflann.hpp>
#include <tbb/blocked_range.h>
#include <tbb/parallel_for.h>
#include <tbb/parallel_reduce.h>
#include <tbb/parallel_sort.h>

#include <algorithm>
#include <cmath>
#include <functional>
#include <limits>
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

int ExemplarIndex::nearest(const float* query, float& distance2, int hint) const {
  constexpr int kMaxCandidates = 16;
  float projected[256];
  float diff[1024];
  TVF_CHECK(reduced_ <= 256, "reduced dimension {}", reduced_);
  auto full_distance = [&](int m) {
    const float* v = values(m);
    float d = 0;
    for (int i = 0; i < dimension_; ++i) {
      const float e = query[i] - v[i];
      d += e * e;
    }
    return d;
  };
  int best = -1;
  float best_d = std::numeric_limits<float>::max();
  if (hint >= 0 && hint < count_) {
    best = hint;
    best_d = full_distance(hint);
  }
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
  // The hint's full distance bounds the search (KNNResultSet prunes by its last slot).
  if (best >= 0) dist[k - 1] = best_d;
  tree_->tree->findNeighbors(result, projected, nanoflann::SearchParams(32, options_.search_eps));
  const int found = static_cast<int>(result.size());
  for (int c = 0; c < found; ++c) {
    const int m = static_cast<int>(index[c]);
    if (m == best) continue;
    const float d = full_distance(m);
    if (d < best_d) {
      best_d = d;
      best = m;
    }
  }
  if (best < 0) {  // nothing found (cannot happen without a bound): the first neighbourhood
    best = 0;
    best_d = full_distance(0);
  }
  distance2 = best_d;
  return best;
}

namespace {

// Output neighbourhoods are split into this many blocks for the M-step's splatting, each
// into its own accumulator, summed in a fixed order: the same result on any thread count.
constexpr int kSplatBlocks = 4;

}  // namespace

OptimizeReport optimize_texture(const Neighbourhoods& nb, const ExemplarIndex& index, std::vector<float>& x,
                                const std::vector<float>& target, const OptimizeOptions& options,
                                std::vector<int>* matches) {
  TVF_CHECK(nb.size == index.size(), "neighbourhood size {} vs index {}", nb.size, index.size());
  const int C = index.channels();
  const int K = nb.size * nb.size;
  const int D = index.dimension();
  const int count = nb.count();
  TVF_CHECK(x.size() % static_cast<size_t>(C) == 0, "samples");
  const size_t samples = x.size() / static_cast<size_t>(C);
  const bool temporal = !target.empty() && options.temporal_weight > 0;
  if (temporal) TVF_CHECK(target.size() == x.size(), "target {} vs x {}", target.size(), x.size());
  const bool weighted = temporal && !options.target_weights.empty();
  if (weighted) TVF_CHECK(options.target_weights.size() == samples, "target weights {} vs samples {}", options.target_weights.size(), samples);
  OptimizeReport report;
  std::vector<int> match(static_cast<size_t>(count), -1);
  if (matches && matches->size() == match.size())
    for (size_t p = 0; p < match.size(); ++p) match[p] = std::clamp((*matches)[p], -1, index.count() - 1);
  std::vector<float> omega(static_cast<size_t>(count)), dist(static_cast<size_t>(count));
  const size_t values_per_block = x.size() + samples;  // C accumulators and a weight per sample
  std::vector<float> blocks(static_cast<size_t>(kSplatBlocks) * values_per_block);
  const double exponent = (options.robust_exponent - 2.0) / 2.0;  // on squared distances
  for (int it = 0; it < options.iterations; ++it) {
    // E-step (the last match of each neighbourhood is the search's hint).
    tbb::parallel_for(tbb::blocked_range<int>(0, count, 256), [&](const tbb::blocked_range<int>& range) {
      std::vector<float> q(static_cast<size_t>(D));
      for (int p = range.begin(); p < range.end(); ++p) {
        const Tap* taps = nb.taps.data() + static_cast<size_t>(p) * static_cast<size_t>(K);
        for (int k = 0; k < K; ++k) {
          const Tap& t = taps[k];
          // Unused slots have weight 0 and a valid sample: no branch.
          const float* x0 = x.data() + static_cast<size_t>(t.sample[0]) * static_cast<size_t>(C);
          const float* x1 = x.data() + static_cast<size_t>(t.sample[1]) * static_cast<size_t>(C);
          const float* x2 = x.data() + static_cast<size_t>(t.sample[2]) * static_cast<size_t>(C);
          const float* x3 = x.data() + static_cast<size_t>(t.sample[3]) * static_cast<size_t>(C);
          for (int c = 0; c < C; ++c)
            q[static_cast<size_t>(k * C + c)] = t.weight[0] * x0[c] + t.weight[1] * x1[c] + t.weight[2] * x2[c] + t.weight[3] * x3[c];
        }
        float d2 = 0;
        match[static_cast<size_t>(p)] = index.nearest(q.data(), d2, match[static_cast<size_t>(p)]);
        dist[static_cast<size_t>(p)] = d2;
        // Robust weight of the per-value RMS distance (floored so that exact matches do
        // not take over).
        const double rms2 = std::max(static_cast<double>(d2) / D, 1e-4);
        omega[static_cast<size_t>(p)] = static_cast<float>(std::pow(rms2, exponent));
      }
    });
    // M-step: splat the matched exemplar values, block by block in parallel.
    tbb::parallel_for(0, kSplatBlocks, [&](int b) {
      float* acc = blocks.data() + static_cast<size_t>(b) * values_per_block;
      float* wsum = acc + x.size();
      std::fill(acc, acc + values_per_block, 0.f);
      const int p0 = static_cast<int>(static_cast<long>(count) * b / kSplatBlocks);
      const int p1 = static_cast<int>(static_cast<long>(count) * (b + 1) / kSplatBlocks);
      for (int p = p0; p < p1; ++p) {
        const Tap* taps = nb.taps.data() + static_cast<size_t>(p) * static_cast<size_t>(K);
        const float* z = index.values(match[static_cast<size_t>(p)]);
        const float om = omega[static_cast<size_t>(p)];
        for (int k = 0; k < K; ++k) {
          const Tap& t = taps[k];
          for (int i = 0; i < 4; ++i) {
            const float w = om * t.weight[static_cast<size_t>(i)];
            if (w == 0) continue;
            const auto s = static_cast<size_t>(t.sample[static_cast<size_t>(i)]);
            wsum[s] += w;
            for (int c = 0; c < C; ++c) acc[s * static_cast<size_t>(C) + static_cast<size_t>(c)] += w * z[k * C + c];
          }
        }
      }
    });
    const double lambda = temporal ? options.temporal_weight : 0.0;
    const size_t uncovered = tbb::parallel_reduce(
        tbb::blocked_range<size_t>(0, samples, 4096), size_t{0},
        [&](const tbb::blocked_range<size_t>& range, size_t n) {
          for (size_t s = range.begin(); s < range.end(); ++s) {
            double w = 0;
            for (int b = 0; b < kSplatBlocks; ++b) w += blocks[static_cast<size_t>(b) * values_per_block + x.size() + s];
            if (w <= 0) {
              ++n;
              continue;
            }
            for (int c = 0; c < C; ++c) {
              const size_t i = s * static_cast<size_t>(C) + static_cast<size_t>(c);
              double a = 0;
              for (int b = 0; b < kSplatBlocks; ++b) a += blocks[static_cast<size_t>(b) * values_per_block + i];
              const double m = a / w;
              const double l = weighted ? lambda * options.target_weights[s] : lambda;
              x[i] = static_cast<float>(temporal ? (m + l * target[i]) / (1 + l) : m);
            }
          }
          return n;
        },
        std::plus<size_t>());
    if (options.histogram_matching && samples > 1) {
      // Each channel by rank onto the exemplar's sorted values (channels in parallel; ties
      // broken by sample index so that the result is deterministic).
      tbb::parallel_for(0, C, [&](int c) {
        const auto& ex = index.sorted_channel(c);
        std::vector<std::pair<float, std::uint32_t>> order(samples);
        for (size_t s = 0; s < samples; ++s)
          order[s] = {x[s * static_cast<size_t>(C) + static_cast<size_t>(c)], static_cast<std::uint32_t>(s)};
        tbb::parallel_sort(order.begin(), order.end());
        for (size_t k = 0; k < samples; ++k) {
          const size_t e = std::min(ex.size() - 1, (2 * k + 1) * ex.size() / (2 * samples));
          x[order[k].second * static_cast<size_t>(C) + static_cast<size_t>(c)] = ex[e];
        }
      });
    }
    double total = 0;
    for (float d : dist) total += d;
    report.patch_distance = count > 0 ? std::sqrt(total / (static_cast<double>(count) * D)) : 0.0;
    report.uncovered = samples > 0 ? static_cast<double>(uncovered) / static_cast<double>(samples) : 0.0;
    report.iterations = it + 1;
  }
  if (matches) *matches = match;
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
