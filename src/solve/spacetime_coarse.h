#pragma once
// The two-level CG's coarse space (docs/architecture.md, "Space-time solve"), shared by the
// one process (solve/spacetime.cpp) and the distributed back end (solve/petsc_spacetime.cpp):
// the segments between key frames, their temporal eigenbases, and each low temporal mode's
// separable Galerkin matrix. Private to libtvf.
#include <Eigen/Core>

#include <cstddef>
#include <span>
#include <utility>
#include <vector>

namespace tvf {

// Whole fixed frames (key frames) and the runs of other frames between them.
struct Segments {
  std::vector<char> key;                            // per frame
  std::vector<std::pair<size_t, size_t>> segments;  // [first, first + count)
};

// fixed is frames × n, frame-major.
Segments find_segments(std::span<const char> fixed, size_t n, size_t nf);
// The same from the key frames' marks (per frame: whether every vertex is fixed there).
Segments segments_between(std::vector<char> key);

// The eigenvectors (columns of q, normalised, ascending eigenvalue) and eigenvalues of the
// path-graph Laplacian of a segment of `count` frames, its first `modes` of them; an open
// end (the first or last frame of the field) is a free "Neumann" end, an end at a key frame
// a "Dirichlet" one.
void temporal_eigenbasis(int count, bool left_open, bool right_open, int modes, Eigen::MatrixXd& q,
                         Eigen::VectorXd& lambda);

// One low temporal mode q (over the segment's frames first … first + q.size() − 1) as a
// coarse space: the space-time vectors w_i(j) = q(j)·[(j, i) free]. Its Galerkin matrix
// wᵢᴴ A wᵢ' is approximated by the separable E = S^½ L S^½ + T with
//   s_i = Σ_j q(j)² [(j, i) free],  T_ii = wᵢᴴ (b·D ⊗ T_time) wᵢ,
// exact at every vertex the fixed set leaves alone in the segment (s_i = 1, T_ii = b·λ·d_i:
// the temporal-mode method's system) and Hermitian positive definite everywhere. Returns
// {√s_i, T_ii} of vertex i (c = b·d_i), {0, 0} for a vertex fixed at every frame of the
// segment (left out of the coarse space).
struct CoarseWeight {
  double scale = 0, shift = 0;
};
CoarseWeight coarse_weight(const Eigen::VectorXd& q, size_t first, std::span<const char> fixed, size_t n, size_t nf,
                           size_t i, double c);

}  // namespace tvf
