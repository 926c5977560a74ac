#pragma once
// The spatio-temporal optimization of DESIGN §5.3 (paper §6.1, eq. 10): all frames of a
// field at once. With cotan (or uniform) weights the energy
//   Σ_j z_jᴴ L z_j + Σ_j Σ_i b·d_i |z_{j+1,i} − z_{j,i}|²,   d_i = Σ_k w_ik,
// is minimised with some entries (j, i) fixed (key frames, element regions). Its normal
// equations are A = I ⊗ L + b·(T ⊗ D), T the path-graph Laplacian in time: Hermitian
// positive (semi)definite. Two methods behind one interface (docs/architecture.md):
//
// * Temporal modes (direct in time). Whole fixed frames (key frames) cut time into
//   segments. Where the fixed vertex set is the same at every frame of a segment (key
//   frames alone, or with elements that stay put), the segment's system is a tensor
//   product L_F ⊗ I + b·D_F ⊗ T_s, and the eigenvectors Q of the small tridiagonal T_s
//   (T_s = Q Λ Qᵀ) decouple it into independent spatial systems (L_F + b·λ_k·D_F) y_k = r_k,
//   one per temporal mode. Those are solved by Jacobi-preconditioned CG in parallel: the
//   shift b·λ_k makes all but the lowest few modes nearly diagonal, so the whole solve
//   costs a few dozen spatial sweeps instead of a few dozen space-time ones. Q is
//   orthogonal, so the residuals of the modes add up to the residual of the whole.
// * Temporal modes with local solves (a moving element between key frames): the modes of
//   each segment's common fixed set (the vertices fixed at all its frames), in rounds; after
//   each round's mode solves, a local constrained solve on the vertices whose temporal line
//   the moving constraints cut (and `moving_rings` rings around them) sets the solution to
//   its fixed values there, and only those rows are transformed between frames and modes.
//   The constraints' multipliers join the modes' right-hand side; what the local solve
//   leaks out is the next round's residual. 4–6 rounds, flat in the mesh size.
// * Matrix-free CG (anything else: moving constraints without a key frame). The preconditioner solves
//   every vertex's temporal line exactly (a real tridiagonal system, fixed entries
//   splitting it): with b = 30 the time couplings carry about 60/61 of each diagonal
//   (DESIGN §5: ~60 iterations, independent of mesh size). What it leaves is the low
//   temporal modes × smooth spatial error; a coarse correction over the lowest
//   `coarse_modes` temporal modes of every segment (each mode's spatial system by
//   Jacobi-PCG, as the mode method's) takes that out before the line solves (flexible
//   CG), and a local solve on the vertices whose temporal line a moving constraint cuts
//   (`local_rings`) what the coarse space represents poorly: ~15 iterations instead of
//   66–72 (65² grid, moving vortex).
//
// The solver object keeps its set-up (row-major operator, temporal eigenbases, the solve's
// vectors) between solves, and every solve starts from the z it is given (warm start
// after an edit). It also keeps the temporal modes of its last solve, so a re-solve with
// the same fixed set transforms only what changed (docs/architecture.md). Calls to
// solve() on one object are serialised.
#include "tvf/solve/connection_laplacian.h"

#include <map>
#include <memory>
#include <mutex>
#include <span>
#include <tuple>

namespace tvf {

enum class SpaceTimeMethod {
  automatic,  // temporal modes where the fixed set allows it (segments up to 1024 frames), else the
              // modes with local solves where those apply, else CG
  modes,      // temporal modes, or an error where the fixed set does not allow it
  cg,         // matrix-free CG with temporal line solves
  // Temporal modes with a local solve where the fixed set moves (a moving element): the
  // modes of the fixed set common to a segment's frames, alternating with a local
  // constrained solve on the moving constraints' vertices and a few rings around them, or
  // an error where it does not apply (see local_modes_apply).
  modes_local,
  // The paper's kind of method, kept as the baseline of the benchmarks: the assembled
  // sparse system, BiCGStab with a Jacobi preconditioner, one thread.
  bicgstab_jacobi,
};

struct SpaceTimeOptions {
  double tolerance = 1e-10;    // relative residual ‖b − A z‖ / ‖b‖ over the free entries
  int max_iterations = 5000;   // CG iterations (per temporal mode for the mode method)
  bool parallel = true;
  SpaceTimeMethod method = SpaceTimeMethod::automatic;
  // Under `mpirun -n K` (any K ≥ 1, solve/distributed.h): solve on all ranks with the PETSc
  // back end (CG preconditioned as below, whatever `method` says but bicgstab_jacobi) and
  // gather the result to every rank. Every rank must then make the same solve() calls in
  // the same order. Off: the solve stays in this process (edit windows, tests' references).
  bool distributed = false;

  // CG only: the two-level preconditioner, this many lowest temporal modes of every
  // segment as a coarse correction before the temporal line solves (flexible CG). 0: the
  // line solves alone (the method before it, kept as the benchmarks' baseline).
  int coarse_modes = 4;
  // CG with coarse modes only: a local solve after the coarse correction on the vertices
  // whose temporal line a moving constraint cuts, grown by this many rings of neighbours
  // (all frames; a few CG iterations with the line solves). 0: those vertices alone (one
  // ring measured the same outer iterations for more work). Negative: none (the two-level
  // method before it, kept as the benchmarks' baseline).
  int local_rings = 0;

  // modes_local only: the local solve near a moving constraint covers the vertices whose
  // temporal line it cuts and this many rings of neighbours around them (Dirichlet zero
  // beyond). More rings: fewer rounds, more work per round (docs/benchmarks.md: 4 rings took
  // 6 rounds where 2 took 9–10, as fast on the 65² grid and 14 % faster on the sphere).
  int moving_rings = 4;
  // modes_local only: after this many rounds (or two rounds in a row that each leave more
  // than 0.7 of the last one's residual) the rounds stop and CG finishes the solve from
  // where they are (the report's method then says "finished by").
  int most_rounds = 40;

  // The temporal-mode methods: modes whose shift b·λ_k is below this have their spatial
  // system (L + b·λ_k·D on the free vertices) solved with a sparse Cholesky factorization
  // (CHOLMOD supernodal LLᴴ) as CG's preconditioner: one or two iterations instead of the
  // hundreds (thousands with no key frame: the lowest mode is then L alone) of Jacobi-PCG.
  // A factorization is kept by the solver while its fixed set and shift are the same (a
  // warm re-solve reuses it). On the 20k sphere one costs about what 200 Jacobi-PCG
  // iterations do, so the default takes only modes with (nearly) no shift: the lowest of a
  // segment without a key frame (500+ iterations there; 70 for the lowest with key frames,
  // shift 0.03 at 100 frames: docs/benchmarks.md). 0: Jacobi-PCG for every mode (the
  // method before, kept as the benchmarks' baseline).
  double direct_shift = 0.005;
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

  // Whether the temporal-mode method applies to this fixed set (see above).
  bool modes_apply(std::span<const char> fixed) const;
  // Whether the temporal modes with local solves apply: every segment between key frames
  // ends at a key frame on at least one side, at most a quarter of the vertices have a
  // temporal line that the fixed set cuts (fixed at some of the segment's frames but not
  // all), and no segment is longer than the modes take.
  bool local_modes_apply(std::span<const char> fixed) const;

  int frames() const { return frames_; }
  int vertices() const { return static_cast<int>(laplacian_.matrix.rows()); }

  struct Operator;  // row-major copy of L and its diagonal (private to the solver)
  struct TemporalBasis;
  struct Workspace;  // the vectors of a solve, kept for the next one

private:
  // The eigenbasis of the temporal path-graph Laplacian on frames [first, first + count),
  // computed once per segment shape and kept.
  const TemporalBasis& temporal_basis(int first, int count) const;
  size_t longest_segment(std::span<const char> fixed) const;
  SolveReport solve_cg(std::span<const char> fixed, std::span<const cplx> rhs, std::span<cplx> x,
                       double bnorm, const SpaceTimeOptions& options) const;
  SolveReport solve_bicgstab(std::span<const char> fixed, std::span<const cplx> rhs, std::span<cplx> x,
                             double bnorm, const SpaceTimeOptions& options) const;
  SolveReport solve_modes(std::span<const char> fixed, std::span<const cplx> rhs, std::span<cplx> x,
                          double bnorm, const SpaceTimeOptions& options, bool local = false) const;

  const ConnectionLaplacian& laplacian_;
  int frames_;
  double b_;
  std::shared_ptr<const Operator> op_;
  mutable std::mutex bases_mutex_;
  // Solves on one object run one at a time; their vectors are reused (fresh ones cost
  // page faults comparable to a warm re-solve).
  mutable std::mutex work_mutex_;
  mutable std::shared_ptr<Workspace> work_;
  mutable std::map<std::tuple<int, int>, std::shared_ptr<const TemporalBasis>> bases_;
};

// SpaceTimeSolver::interpolate_in_time on `lines` temporal lines of `frames` entries each
// (frames × lines, frame-major: a field's vertices, or one rank's share of them under
// mpirun). z may be values itself (fixed entries are read before they are written, and
// written with themselves).
void interpolate_lines_in_time(std::span<const char> fixed, std::span<const cplx> values, std::span<cplx> z,
                               size_t lines, size_t frames);

}  // namespace tvf
