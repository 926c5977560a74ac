#pragma once
// Texture optimization (Kwatra, Essa, Bobick, Kwatra 2005), the core shared by planar and
// surface synthesis (synth/planar_synthesis.h, synth/surface_synthesis.h).
//
// The output is a set of samples (pixels of a grid, or vertices of a mesh), `channels`
// floats each. A neighbourhood is a size × size grid of taps laid out in the output around
// one sample, oriented by the field (its rows run along the field's direction, which the
// exemplar's x axis is mapped to); each tap reads the output by interpolation, Σ wᵢ·x[sᵢ]
// over up to four samples (bilinear on a grid, barycentric on a mesh). The energy
//     E(x) = Σ_p ω_p ‖x_p − z_p‖²,   z_p the exemplar neighbourhood nearest to x_p,
// is lowered by alternating its two steps:
//  - E-step: for every output neighbourhood x_p, the nearest exemplar neighbourhood z_p,
//    searched in a kd-tree (nanoflann, Debian libnanoflann-dev) over PCA-reduced
//    neighbourhood vectors (Eigen), the few best candidates then ranked in full dimension;
//  - M-step: every sample becomes the weighted average of what the matched exemplar
//    neighbourhoods say about it (each tap splats its exemplar value with its
//    interpolation weights), with Kwatra's robust weights ω_p = ‖x_p − z_p‖^(r−2), r = 0.8.
// Averaging overlapping patches washes out contrast and colour; as in Kopf et al. 2007
// (solid texture synthesis), each M-step ends with a histogram match: every channel of the
// output is mapped monotonically (by rank) onto the exemplar's distribution of that channel.
// Temporal coherence (Kwatra, Adalsteinsson, Kim, Kwatra, Carlson, Lin 2007): an optional
// target x̃ (the previous frame advected by the flow) is blended in as a soft constraint,
// x ← (x_M + λ·x̃)/(1 + λ) (λ may vary per sample).
#include "tvf/synth/exemplar.h"

#include <array>
#include <cstdint>
#include <memory>
#include <span>
#include <vector>

namespace tvf {

// One tap: the output there is Σ weight[i]·x[sample[i]] (unused slots have weight 0).
struct Tap {
  std::array<int, 4> sample{0, 0, 0, 0};
  std::array<float, 4> weight{0, 0, 0, 0};
};

// The neighbourhoods of one level: count() × size² taps, each neighbourhood row-major in
// the exemplar's layout (tap (row, column) reads offset ((column − r)·u + (row − r)·v)·spacing
// from its centre, r = size/2, u the field direction, v = u turned clockwise, so that the
// picture is not mirrored).
struct Neighbourhoods {
  int size = 0;             // odd
  std::vector<Tap> taps;
  int count() const { return size > 0 ? static_cast<int>(taps.size()) / (size * size) : 0; }
};

struct ExemplarIndexOptions {
  int size = 7;             // neighbourhood size (odd, at least 3)
  int pca_dimensions = 16;  // dimensions kept by PCA (at most size²·channels)
  int candidates = 4;       // kd-tree candidates ranked in full dimension
  float search_eps = 1.0f;  // nanoflann's approximate search: distances within (1 + eps)
};

// Every neighbourhood of one exemplar (wrapping around when it is tileable), their PCA
// and a kd-tree over the reduced vectors. Immutable after construction; queries are
// thread-safe.
class ExemplarIndex {
public:
  // Throws tvf::Error when the exemplar is smaller than one neighbourhood.
  ExemplarIndex(const Exemplar& exemplar, const ExemplarIndexOptions& options = {});
  ~ExemplarIndex();
  ExemplarIndex(const ExemplarIndex&) = delete;
  ExemplarIndex& operator=(const ExemplarIndex&) = delete;

  int size() const { return options_.size; }
  int channels() const { return channels_; }
  int dimension() const { return dimension_; }        // size² · channels
  int count() const { return count_; }                // exemplar neighbourhoods
  int pca_dimensions() const { return reduced_; }
  double explained_variance() const { return explained_; }  // fraction kept by the PCA
  const Exemplar& exemplar() const { return exemplar_; }
  // The exemplar's values of channel c, sorted ascending.
  const std::vector<float>& sorted_channel(int c) const { return sorted_[static_cast<size_t>(c)]; }

  // The exemplar neighbourhood nearest to `query` (dimension() floats); its squared
  // distance in full dimension in `distance2`. `hint` (≥ 0), a neighbourhood that is
  // probably close (the last match of this output neighbourhood), is a candidate itself
  // and bounds the kd-tree search: the reduced distance is at most the full one, so no
  // point farther than the hint in reduced space can beat it — pruning that loses nothing.
  int nearest(const float* query, float& distance2, int hint = -1) const;
  // The values of exemplar neighbourhood m (dimension() floats) and its top-left pixel.
  const float* values(int m) const { return values_.data() + static_cast<size_t>(m) * static_cast<size_t>(dimension_); }
  std::array<int, 2> position(int m) const { return positions_[static_cast<size_t>(m)]; }

private:
  struct Tree;
  Exemplar exemplar_;
  ExemplarIndexOptions options_;
  int channels_ = 0, dimension_ = 0, count_ = 0, reduced_ = 0;
  double explained_ = 0;
  std::vector<float> values_;                 // count × dimension
  std::vector<std::array<int, 2>> positions_; // top-left pixel of each
  std::vector<float> mean_;                   // dimension
  std::vector<float> basis_;                  // reduced × dimension, rows orthonormal
  std::vector<float> reduced_values_;         // count × reduced
  std::vector<std::vector<float>> sorted_;    // per channel
  std::unique_ptr<Tree> tree_;
};

struct OptimizeOptions {
  int iterations = 3;
  double robust_exponent = 0.8;   // Kwatra's r (2: plain least squares)
  double temporal_weight = 0.0;   // λ of the soft target (0: none)
  // Per-sample factors of λ (one per sample, in [0, 1]), or empty: all 1. Samples with 0
  // follow the exemplar alone (where the target was re-seeded).
  std::span<const float> target_weights;
  bool histogram_matching = true; // map each channel onto the exemplar's histogram (by rank)
};

struct OptimizeReport {
  int iterations = 0;
  // Root mean square difference per value between each output neighbourhood and its
  // nearest exemplar neighbourhood, in the last E-step (values in [0, 1]).
  double patch_distance = 0;
  // The fraction of samples that no tap touched (they keep their value).
  double uncovered = 0;
};

// Runs `options.iterations` E/M steps on x (num_samples × channels, interleaved).
// `target` (same layout) is the soft temporal target, or empty. `matches`, when given,
// holds the exemplar neighbourhood matched to each output neighbourhood: used as search
// hints when it has one per neighbourhood (the last frame's matches), and set to the last
// E-step's. Thread-parallel (TBB); the result does not depend on the number of threads.
OptimizeReport optimize_texture(const Neighbourhoods& neighbourhoods, const ExemplarIndex& index,
                                std::vector<float>& x, const std::vector<float>& target,
                                const OptimizeOptions& options, std::vector<int>* matches = nullptr);

// Fills x (num_samples × channels) with exemplar pixels picked at random: the usual
// starting point of the coarsest level.
void random_exemplar_pixels(const Exemplar& exemplar, int num_samples, std::uint64_t seed, std::vector<float>& x);

}  // namespace tvf
