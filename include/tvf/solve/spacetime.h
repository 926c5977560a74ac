#pragma once
// The spatio-temporal optimization of DESIGN §5.3 (paper §6.1, eq. 10): all frames of a
// field at once. With cotan (or uniform) weights the energy
//   Σ_j z_jᴴ L z_j + Σ_j Σ_i b·d_i |z_{j+1,i} − z_{j,i}|²,   d_i = Σ_k w_ik,
// is minimised with some entries (j, i) fixed (key frames, element regions). Its normal
// equations are A = I ⊗ L + b·(T ⊗ D), T the path-graph Laplacian in time: Hermitian
// positive (semi)definite, solved matrix-free by preconditioned CG. The preconditioner
// solves every vertex's temporal line exactly (a real tridiagonal system per vertex, the
// fixed entries splitting it): with b = 30 the time couplings carry about 60/61 of each
// diagonal, so this captures most of the operator (DESIGN §5, measured there at ~56
// iterations for pure key frames, independent of mesh size).
#include "tvf/solve/connection_laplacian.h"

#include <span>

namespace tvf {

struct SpaceTimeOptions {
  double tolerance = 1e-10;    // relative residual ‖b − A z‖ / ‖b‖ over the free entries
  int max_iterations = 5000;
  bool parallel = true;
};

class SpaceTimeSolver {
public:
  // `laplacian` must be Hermitian (cotan or uniform weights) and outlive the solver.
  SpaceTimeSolver(const ConnectionLaplacian& laplacian, int frames, double temporal_weight);

  // fixed, values and z are frames × |V|, frame-major (the Field layout). Entries with
  // fixed != 0 keep values[k]; the others are solved for. z holds the initial guess on
  // entry (warm start: e.g. the previous solution after an edit) and the result on exit.
  SolveReport solve(std::span<const char> fixed, std::span<const cplx> values, std::span<cplx> z,
                    const SpaceTimeOptions& options = {}) const;

  // A first guess: along every vertex's temporal line, linear interpolation between its
  // fixed entries (constant beyond the first and last; zero on lines with none).
  void interpolate_in_time(std::span<const char> fixed, std::span<const cplx> values,
                           std::span<cplx> z) const;

  int frames() const { return frames_; }
  int vertices() const { return static_cast<int>(laplacian_.matrix.rows()); }

private:
  const ConnectionLaplacian& laplacian_;
  int frames_;
  double b_;
};

}  // namespace tvf
