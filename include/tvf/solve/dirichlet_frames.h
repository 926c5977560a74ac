#pragma once
// A sequence of Dirichlet problems on one connection Laplacian whose constraints differ on
// few vertices from one problem to the next: the frames of the constrained generator,
// where elements move a little each frame (issue 15).
//
// Each problem is DirichletSolver::solve with penalties (DESIGN §5.2): L z = 0 at free
// vertices, z fixed at constrained ones, a soft pull μ_v |z_v − c_v|² at penalized ones.
// DirichletSolver pays one numeric factorization per problem. Here a block of problems
// shares one: the vertices whose status (fixed, or its penalty) differs between the
// block's problems form the changing set K; with T = K and the free vertices next to it
// ordered last, every problem's matrix has the same leading rows (the set I of the other
// vertices), so one sparse LDLᴴ of the block gives L_II, D_I and L_TI for all of them,
// and a problem costs only the factorization of its small trailing Schur complement
//   Σ = A_TT − L_TI D_I L_TIᴴ  (A_TT changes per problem; the product does not, and is
//                                nonzero only on the free vertices next to K)
// plus one forward and one backward substitution through L_II. The field is the same as
// DirichletSolver's to rounding (each problem's residual is reported, as there), and
// constrained vertices get their values exactly. On a flat connection (planar domains)
// L is real and so are both factorizations; the field stays complex.
// Why and measured: docs/architecture.md, "Frames that share a factorization";
// docs/benchmarks.md, issue 15.
#include "tvf/solve/connection_laplacian.h"

#include <functional>
#include <span>
#include <vector>

namespace tvf {

// One problem: constrained[v] != 0 fixes z_v = values[v]; penalty[v] = μ_v > 0 at a free
// vertex pulls z_v towards values[v] (an empty penalty means none). Sizes |V|.
struct DirichletProblem {
  std::span<const char> constrained;
  std::span<const cplx> values;
  std::span<const double> penalty;
};

struct DirichletFramesOptions {
  // A block whose trailing set T would exceed this fraction of the vertices is split in
  // two (down to single problems, which need no trailing set).
  double max_trailing_fraction = 0.25;
  // From this many vertices the block's factorization is CHOLMOD's supernodal one (BLAS
  // on the supernodes, as DirichletSolver's automatic choice), below Eigen's simplicial.
  int cholmod_from = 8000;
};

// solve() is const and keeps nothing between calls: one object serves every thread.
class DirichletFrames {
public:
  // Hermitian (cotan or uniform) weights only (LDLᴴ); mean-value weights need
  // DirichletSolver's LU.
  explicit DirichletFrames(const ConnectionLaplacian& laplacian, DirichletFramesOptions options = {});

  // What a solve() did (for benchmarks and tests).
  struct Statistics {
    int blocks = 0;            // factorizations (a block split in two counts twice)
    int largest_trailing = 0;  // the largest trailing set T
  };

  // Solves problems[k] into out[k] (|V| entries each), all of them one block (split in
  // two while its trailing set is too large), and returns each one's report as
  // DirichletSolver::solve would (method, residual ‖A z − b‖/‖b‖, success, failure).
  // Components of L's graph without any constraint in a problem get zero there, as in
  // DirichletSolver. Problems whose constraints differ on many vertices cost more than
  // DirichletSolver; the caller groups consecutive frames. after_each(k), if given, is
  // called as soon as problem k is solved (progress; it may throw to cancel the rest).
  // Problem solve_first, if in range, is solved before the others (a viewer's frame); the
  // results do not depend on the order, which only says when each is ready. `parallel`:
  // the problems sharing a factorization are solved at once on TBB's threads (the same
  // results, bit for bit); after_each must then be safe to call from several threads.
  std::vector<SolveReport> solve(std::span<const DirichletProblem> problems, std::span<const std::span<cplx>> out,
                                 Statistics* statistics = nullptr,
                                 const std::function<void(size_t)>& after_each = {},
                                 size_t solve_first = static_cast<size_t>(-1), bool parallel = false) const;

  // Whether L is real (a flat connection), so that the factorizations are real.
  bool real() const { return real_; }

private:
  const ConnectionLaplacian& laplacian_;
  DirichletFramesOptions options_;
  bool real_ = false;
  Eigen::SparseMatrix<double> real_matrix_;  // L's real part, when real_
  std::vector<int> component_;               // per vertex: its connected component in L's graph
  int num_components_ = 0;
};

}  // namespace tvf
