#include "tvf/solve/spacetime.h"

#include "solve/petsc_spacetime.h"
#include "solve/one_blas_thread.h"
#include "solve/spacetime_coarse.h"
#include "tvf/core/error.h"
#include "tvf/solve/distributed.h"

// GCC 12 sees a null outer-index pointer in the Ref that Eigen's CholmodSupport makes of a
// compressed matrix (viewAsCholmod), which cannot occur (as in connection_laplacian.cpp).
#pragma GCC diagnostic push
#pragma GCC diagnostic ignored "-Wnull-dereference"
#include <Eigen/CholmodSupport>
#pragma GCC diagnostic pop
#include <Eigen/IterativeLinearSolvers>
#include <fmt/format.h>
#include <tbb/blocked_range.h>
#include <tbb/enumerable_thread_specific.h>
#include <tbb/parallel_for.h>

#include <algorithm>
#include <atomic>
#include <cmath>
#include <functional>
#include <limits>
#include <numeric>
#include <vector>

namespace tvf {

// L split into its real diagonal and its off-diagonal entries, row-major: rows are
// gathered (each output written once, rows independent) instead of scattered.
struct SpaceTimeSolver::Operator {
  std::vector<int> row_start, column;
  std::vector<cplx> value;
  std::vector<double> diagonal;    // L_ii
  std::vector<double> weight_sum;  // d_i
  int rows = 0;

  // Off-diagonal part of row i applied to x.
  cplx off(int i, const cplx* x) const {
    cplx acc(0, 0);
    for (int k = row_start[static_cast<size_t>(i)]; k < row_start[static_cast<size_t>(i) + 1]; ++k)
      acc += value[static_cast<size_t>(k)] * x[column[static_cast<size_t>(k)]];
    return acc;
  }
};

namespace detail {
// A slow temporal mode's spatial system L + s·D over a fixed set (fixed rows and columns
// identity, so L's pattern whatever the set: the symbolic analysis is made once per
// object), factored by CHOLMOD (supernodal LLᴴ).
struct ModeFactor {
  std::vector<char> fixed;  // |V|: the fixed set it is (or is to be) the factor for
  double shift = 0;
  bool analysed = false, factored = false;
  Eigen::CholmodSupernodalLLT<Eigen::SparseMatrix<cplx>, Eigen::Lower> llt;
};
}  // namespace detail

// The vectors of a solve (each resized only when the problem's size changes).
struct SpaceTimeSolver::Workspace {
  std::vector<cplx> rhs, x, r, p, ap, zp, t;
  std::vector<double> lower, pivot, upper;
  // What a solve leaves for the next one (a warm re-solve after an edit). The fixed set,
  // its values and the right-hand side: when the next solve has the same fixed set, it
  // compares the fixed values only and updates the right-hand side where they changed
  // (rhs_change lists what changed; an edit changes a key frame's region: a few hundred
  // entries instead of all of them).
  std::vector<char> fixed;                         // the fixed set of the last solve
  std::vector<size_t> fixed_at;                    // its entries,
  std::vector<cplx> fixed_value;                   // and their values
  bool last_kept = false;                          // fixed, fixed_at, fixed_value and rhs are the last solve's
  std::vector<std::pair<size_t, cplx>> rhs_change; // this solve's rhs − the last one's, where they differ
  bool rhs_incremental = false;                    // rhs_change lists every change
  std::vector<char> mark;                          // scratch: n × frames, all zero between uses
  std::vector<double> rhs_parts;                   // ‖rhs‖² by chunks of kSumChunk entries
  std::vector<double> mode_rr;                     // per mode: ‖res_hat's column‖² as the last solve left it
  // The temporal-mode method's, per segment (2|V| × frames, re and im interleaved): the
  // modes of the right-hand side, of the result, and the modes' residuals
  // r_hat − A_k x_hat (the last CG residual of each mode). They stay valid while the fixed
  // set is the same: the next solve then transforms only the rows whose right-hand side
  // changed, skips the transform of its first guess when that guess is this result, and
  // starts every mode from its kept residual instead of a sweep.
  std::vector<std::vector<double>> r_hat, x_hat, res_hat;
  bool modes_kept = false;                         // r_hat, x_hat, res_hat belong to rhs, x
  // A warm re-solve with the kept residuals solves for the change alone (iterate_change):
  // per segment, what it adds to x_hat and the part of res_hat it brought, zero between
  // solves (allocated by the first such solve; change_zero false where a solve that
  // stopped short may have left them otherwise).
  std::vector<std::vector<double>> d_hat, e_hat;
  bool change_zero = true;
  bool same_fixed = false, same_guess = false;     // set by solve() for solve_modes()
  // The fixed set changed at these entries since the last solve (few, the same whole fixed
  // frames, the last solve's modes kept): solve() updated rhs there and x is the last
  // result with the new guess at them; solve_modes() patches the kept modes.
  std::vector<size_t> toggled;
  bool moved = false;
  bool kept_moving = false;  // the kept modes are a solve's with moving constraints (r_hat holds multipliers)
  // The slow modes' factorizations (SpaceTimeOptions::direct_shift), kept for the next
  // solve: one with the same fixed set and shift is used as it is, another one refactored.
  std::vector<std::unique_ptr<detail::ModeFactor>> factors;
  // What depends on the fixed set alone, kept while it is the same (reset by solve() when
  // it changes): which methods apply (-1: not yet known), and the modes with local solves'
  // set-up (their segments' common fixed sets, omega and its rows, the line solves'
  // factors, the local CG's vectors) with the local solves' part of the result not yet
  // in the modes (see LocalSetup).
  int modes_fit = -1, local_fit = -1;
  size_t longest = 0;  // the longest segment's frames (0: not yet known)
  struct LocalSetup;
  std::unique_ptr<LocalSetup> local;
};

// T_s = Q Λ Qᵀ for the frames of one segment.
struct SpaceTimeSolver::TemporalBasis {
  Eigen::MatrixXd q;       // count × count, orthonormal columns (the modes)
  Eigen::VectorXd lambda;  // count
};

namespace {

using Vec = std::vector<cplx>;

// CG preconditioned by `precondition` (z = M⁻¹ r, returning r·z) on a small system whose
// product is `apply` (ap = A p, returning p·Ap): x += the correction, r updated, from the
// residual norm² rr down to tau2 or max_iterations. Returns the iterations. The two local
// solves near moving constraints use it.
template <class Apply, class Precondition>
int local_pcg(Vec& x, Vec& r, Vec& z, Vec& p, Vec& ap, double rr, double tau2, int max_iterations, Apply&& apply,
              Precondition&& precondition) {
  double rz = precondition(r, z);
  p = z;
  int it = 0;
  while (rr > tau2 && it < max_iterations) {
    const double pap = apply(p, ap);
    if (!(pap > 0)) break;
    const double alpha = rz / pap;
    // Four partial sums (a single one is a chain of dependent adds), added in a fixed order.
    double part[4] = {0, 0, 0, 0};
    const size_t nq = x.size(), n4 = nq - nq % 4;
    for (size_t q = 0; q < n4; q += 4)
      for (size_t g = 0; g < 4; ++g) {
        x[q + g] += alpha * p[q + g];
        r[q + g] -= alpha * ap[q + g];
        part[g] += std::norm(r[q + g]);
      }
    for (size_t q = n4; q < nq; ++q) {
      x[q] += alpha * p[q];
      r[q] -= alpha * ap[q];
      part[q - n4] += std::norm(r[q]);
    }
    rr = (part[0] + part[1]) + (part[2] + part[3]);
    ++it;
    if (rr <= tau2) break;
    const double rz_new = precondition(r, z);
    const double beta = rz_new / rz;
    rz = rz_new;
    for (size_t q = 0; q < x.size(); ++q) p[q] = z[q] + beta * p[q];
  }
  return it;
}

// v with n entries, reusing its storage (contents unspecified: callers overwrite them).
template <class T>
std::vector<T>& sized(std::vector<T>& v, size_t n) {
  if (v.size() != n) {
    v.clear();
    v.shrink_to_fit();
    v.resize(n);
  }
  return v;
}

// Runs body(begin, end) over [0, n) in fixed blocks of 2048 entries, in parallel or not.
// The blocks never depend on the thread count or the partitioner, and the serial and
// parallel paths run the same block function: with the partitioner's blocks two runs of
// the CG on two CPUs differed in the last bits (a 41² × 24 spacetime scene); with fixed
// blocks they agree with each other and with the serial solve.
constexpr size_t kBlockEntries = 2048;
template <class F>
void blocks(size_t n, bool parallel, F&& body) {
  const size_t count = (n + kBlockEntries - 1) / kBlockEntries;
  auto run = [&](size_t c) { body(c * kBlockEntries, std::min(n, (c + 1) * kBlockEntries)); };
  if (parallel && count > 1)
    tbb::parallel_for(size_t{0}, count, run);
  else
    for (size_t c = 0; c < count; ++c) run(c);
}

// Σ of partial(task) over tasks [0, count), run in parallel or not, added in task order: the
// tasks are fixed pieces of the work (never the partitioner's or the threads' choice), so a
// sum has the same bits with one thread, two, or none (replay from a scene is bit for bit
// on any machine; a per-thread accumulator or parallel_reduce would add in an order that
// depends on the thread count).
template <class F>
double ordered_sum(size_t count, bool parallel, F&& partial) {
  if (count == 0) return 0.0;
  if (count == 1) return partial(size_t{0});
  std::vector<double> parts(count);
  auto run = [&](size_t t) { parts[t] = partial(t); };
  if (parallel)
    tbb::parallel_for(size_t{0}, count, run);
  else
    for (size_t t = 0; t < count; ++t) run(t);
  double s = 0;
  for (const double x : parts) s += x;
  return s;
}

// Σ over [0, n) of body(begin, end)'s partial sums over fixed chunks of 4096 entries.
constexpr size_t kSumChunk = 4096;
template <class F>
double chunked_sum(size_t n, bool parallel, F&& body) {
  return ordered_sum((n + kSumChunk - 1) / kSumChunk, parallel,
                     [&](size_t c) { return body(c * kSumChunk, std::min(n, (c + 1) * kSumChunk)); });
}

// Σ over [0, n) of term(k), in fixed chunks (see ordered_sum).
template <class F>
double sum(size_t n, bool parallel, F&& term) {
  return chunked_sum(n, parallel, [&](size_t b, size_t e) {
    double s = 0;
    for (size_t k = b; k < e; ++k) s += term(k);
    return s;
  });
}

// The space-time operator on one fixed set, frame-major vectors of frames × n.
struct SpaceTime {
  const SpaceTimeSolver::Operator& op;
  std::span<const char> fixed;
  size_t n, nf;
  double b;
  bool parallel;

  // Visits (A x)_k for every free entry k: emit(k, x_k, (A x)_k) returns what to add up;
  // fixed entries get skip(k). Fixed entries of x must be zero.
  template <class Emit, class Skip>
  double sweep(std::span<const cplx> x, Emit&& emit, Skip&& skip) const {
    // Tasks of a block of rows × a block of frames: each entry of L (column, value) is
    // loaded once for kFrames frames, whose products are independent (the sweep is
    // bound by loads and complex multiply-adds, not by the few flops of a row).
    constexpr size_t kFrames = 4;
    const size_t block = 512;
    const size_t row_blocks = (n + block - 1) / block;
    const size_t frame_blocks = (nf + kFrames - 1) / kFrames;
    auto body = [&](size_t task) {
      const size_t j0 = (task / row_blocks) * kFrames, nj = std::min(kFrames, nf - j0);
      const size_t i0 = (task % row_blocks) * block, i1 = std::min(n, i0 + block);
      const cplx* xs = x.data();
      double partial = 0;
      for (size_t i = i0; i < i1; ++i) {
        double re[kFrames] = {}, im[kFrames] = {};
        for (int e = op.row_start[i]; e < op.row_start[i + 1]; ++e) {
          const cplx v = op.value[static_cast<size_t>(e)];
          const cplx* xc = xs + j0 * n + static_cast<size_t>(op.column[static_cast<size_t>(e)]);
          for (size_t f = 0; f < nj; ++f) {
            const cplx u = xc[f * n];
            re[f] += v.real() * u.real() - v.imag() * u.imag();
            im[f] += v.real() * u.imag() + v.imag() * u.real();
          }
        }
        const double c = b * op.weight_sum[i];
        for (size_t f = 0; f < nj; ++f) {
          const size_t j = j0 + f, k = j * n + i;
          if (fixed[k]) {
            skip(k);
            continue;
          }
          const cplx xi = xs[k];
          cplx t(0, 0);
          if (j > 0) t += xi - xs[k - n];
          if (j + 1 < nf) t += xi - xs[k + n];
          partial += emit(k, xi, op.diagonal[i] * xi + cplx(re[f], im[f]) + c * t);
        }
      }
      return partial;
    };
    return ordered_sum(frame_blocks * row_blocks, parallel, body);
  }

  // y_F = A_FF x_F (y's fixed entries zero); returns Re <x, y>, fused so an iteration
  // reads each vector as few times as possible.
  double apply(std::span<const cplx> x, std::span<cplx> y) const {
    return sweep(
        x,
        [&](size_t k, cplx xi, cplx yi) {
          y[k] = yi;
          return xi.real() * yi.real() + xi.imag() * yi.imag();
        },
        [&](size_t k) { y[k] = 0; });
  }

  // ‖rhs − A_FF x‖² over the free entries, without storing A x.
  double residual_norm2(std::span<const cplx> x, std::span<const cplx> rhs) const {
    return sweep(x, [&](size_t k, cplx, cplx yi) { return std::norm(rhs[k] - yi); }, [](size_t) {});
  }

  // (rhs_F)_k = (−A_FC v_C)_k for a free entry k = j·n + i: what the fixed values ask of it.
  cplx rhs_entry(std::span<const cplx> values, size_t j, size_t i) const {
    const cplx* vj = values.data() + j * n;
    const char* fj = fixed.data() + j * n;
    cplx acc(0, 0);
    for (int k = op.row_start[i]; k < op.row_start[i + 1]; ++k) {
      const auto c = static_cast<size_t>(op.column[static_cast<size_t>(k)]);
      if (fj[c]) acc -= op.value[static_cast<size_t>(k)] * vj[c];
    }
    // The temporal neighbours indexed from the array's start: fj[i − n] with i < n adds a
    // wrapped unsigned offset to the pointer (undefined behaviour; UBSan's pointer-overflow
    // check, found by fuzz_session).
    const double c = b * op.weight_sum[i];
    if (j > 0 && fixed[(j - 1) * n + i]) acc += c * values[(j - 1) * n + i];
    if (j + 1 < nf && fixed[(j + 1) * n + i]) acc += c * values[(j + 1) * n + i];
    return acc;
  }

  // rhs_F = −A_FC v_C (fixed entries of rhs zero).
  void right_hand_side(std::span<const cplx> values, Vec& rhs) const {
    auto body = [&](size_t j) {
      const char* fj = fixed.data() + j * n;
      cplx* rj = rhs.data() + j * n;
      for (size_t i = 0; i < n; ++i) rj[i] = fj[i] ? cplx(0, 0) : rhs_entry(values, j, i);
    };
    if (parallel)
      tbb::parallel_for(size_t{0}, nf, body);
    else
      for (size_t j = 0; j < nf; ++j) body(j);
  }

  // Where the fixed part changed (`sources`: entries whose fixed value changed, or that
  // were fixed and are free now, or the other way round), updates rhs in place at the free
  // entries it reaches (their spatial neighbours in the frame, the entry itself in the
  // frames before and after, and a source that is free now), sets it to zero at the
  // sources that are fixed now, and lists rhs's changes. `mark` is n × frames scratch,
  // zero on entry and exit.
  void update_right_hand_side(std::span<const cplx> values, std::span<const size_t> sources, Vec& rhs,
                              std::vector<char>& mark, std::vector<std::pair<size_t, cplx>>& change) const {
    std::vector<size_t> reached;
    auto reach = [&](size_t k) {
      if (!mark[k] && (!fixed[k] || rhs[k] != cplx(0, 0))) {
        mark[k] = 1;
        reached.push_back(k);
      }
    };
    for (const size_t k : sources) {
      const size_t j = k / n, i = k % n;
      reach(k);
      for (int e = op.row_start[i]; e < op.row_start[i + 1]; ++e)
        reach(j * n + static_cast<size_t>(op.column[static_cast<size_t>(e)]));
      if (j > 0) reach(k - n);
      if (j + 1 < nf) reach(k + n);
    }
    std::sort(reached.begin(), reached.end());
    change.clear();
    for (const size_t k : reached) {
      mark[k] = 0;
      const cplx v = fixed[k] ? cplx(0, 0) : rhs_entry(values, k / n, k % n);
      if (v != rhs[k]) change.emplace_back(k, v - rhs[k]);
      rhs[k] = v;
    }
  }
};

// Scratch vectors of one thread's mode solves, kept between modes (fresh |V|-sized
// vectors per mode cost more in page faults than the sweeps of a high mode).
struct ModeScratch {
  Vec p, ap, res, sp;  // res, sp: the coarse solves' only
  std::vector<double> diagonal, inverse;
  // ModeSystem::iterate_change's: zero (in, cp, cap) between its calls.
  std::vector<char> in;
  Vec cp, cap;
  std::vector<double> cdiagonal, cinverse;
  void resize(size_t n) {
    if (p.size() == n) return;
    p.resize(n), ap.resize(n), diagonal.resize(n), inverse.resize(n);
  }
};

// One temporal mode's spatial system (L_F + s·D_F) y = rhs over the free vertices
// (fixed[i] == 0); fixed entries of y, rhs and the residual are zero.
struct ModeSystem {
  const SpaceTimeSolver::Operator& op;
  const char* fixed;
  double s;

  // res = rhs − A y on the free rows; returns ‖res‖².
  double residual(const cplx* rhs, const cplx* y, cplx* res) const {
    double rr = 0;
    for (size_t i = 0; i < static_cast<size_t>(op.rows); ++i) {
      if (fixed[i]) {
        res[i] = 0;
        continue;
      }
      const double d = op.diagonal[i] + s * op.weight_sum[i];
      res[i] = rhs[i] - (d * y[i] + op.off(static_cast<int>(i), y));
      rr += std::norm(res[i]);
    }
    return rr;
  }

  // Jacobi-preconditioned CG from y, whose residual res and ‖res‖² = rr are given, until
  // ‖res‖² ≤ tau2; y, res and rr are updated. Returns the iterations, or −1 if it did not
  // converge within max_iterations.
  int iterate(cplx* y, cplx* res, double& rr, double tau2, int max_iterations, ModeScratch& w) const {
    if (rr <= tau2) return 0;
    const auto n = static_cast<size_t>(op.rows);
    w.resize(n);
    cplx *p = w.p.data(), *ap = w.ap.data();
    double *diagonal = w.diagonal.data(), *inverse = w.inverse.data();
    double rz = 0;
    for (size_t i = 0; i < n; ++i) {
      diagonal[i] = fixed[i] ? 0.0 : op.diagonal[i] + s * op.weight_sum[i];
      inverse[i] = fixed[i] ? 0.0 : 1.0 / diagonal[i];
      p[i] = inverse[i] * res[i];
      rz += inverse[i] * std::norm(res[i]);
    }
    // ap = A p on the free rows (fixed rows: 0; fixed entries of p are 0); returns Re <p, Ap>.
    auto apply = [&]() {
      double dot = 0;
      for (size_t i = 0; i < n; ++i) {
        const cplx v = fixed[i] ? cplx(0, 0) : diagonal[i] * p[i] + op.off(static_cast<int>(i), p);
        ap[i] = v;
        dot += p[i].real() * v.real() + p[i].imag() * v.imag();
      }
      return dot;
    };
    int it = 0;
    while (rr > tau2) {
      if (it == max_iterations) return -1;
      const double pap = apply();
      if (!(pap > 0)) return -1;
      const double alpha = rz / pap;
      double rz_new = 0;
      rr = 0;
      for (size_t i = 0; i < n; ++i) {
        y[i] += alpha * p[i];
        res[i] -= alpha * ap[i];
        const double q = std::norm(res[i]);
        rr += q;
        rz_new += inverse[i] * q;
      }
      ++it;
      const double beta = rz_new / rz;
      rz = rz_new;
      for (size_t i = 0; i < n; ++i) p[i] = inverse[i] * res[i] + beta * p[i];
    }
    return it;
  }

  // As iterate, with the factorization f of this system (made here when f is not yet
  // factored) as the preconditioner instead of Jacobi: exact up to rounding, so one or two
  // iterations. `l` is L as a matrix (its pattern is f's). Returns −2 when the system
  // cannot be factored (not definite: a part of the mesh without a fixed vertex on a flat
  // connection), for Jacobi-PCG to take it.
  int iterate_direct(cplx* y, cplx* res, double& rr, double tau2, int max_iterations, detail::ModeFactor& f,
                     const ConnectionLaplacian& l, ModeScratch& w) const {
    if (rr <= tau2) return 0;
    const auto n = static_cast<size_t>(op.rows);
    const detail::OneBlasThread one_thread;  // CHOLMOD's BLAS on this thread alone
    if (!f.factored) {
      Eigen::SparseMatrix<cplx> a = l.matrix;
      for (Eigen::Index j = 0; j < a.outerSize(); ++j)
        for (Eigen::SparseMatrix<cplx>::InnerIterator e(a, j); e; ++e) {
          const auto i = static_cast<size_t>(e.row());
          if (fixed[i] || fixed[static_cast<size_t>(j)])
            e.valueRef() = e.row() == j ? cplx(1, 0) : cplx(0, 0);
          else if (e.row() == j)
            e.valueRef() += s * op.weight_sum[i];
        }
      f.llt.cholmod().print = 0;
      if (!f.analysed) f.llt.analyzePattern(a);
      f.analysed = f.llt.info() == Eigen::Success;
      if (f.analysed) f.llt.factorize(a);
      if (!f.analysed || f.llt.info() != Eigen::Success) return -2;  // singular (a part without a fixed vertex)
      f.factored = true;
    }
    w.resize(n);
    cplx *p = w.p.data(), *ap = w.ap.data();
    Eigen::Map<Eigen::VectorXcd> r(res, static_cast<Eigen::Index>(n));
    Eigen::VectorXcd z = f.llt.solve(r);
    double rz = r.dot(z).real();
    for (size_t i = 0; i < n; ++i) p[i] = z[static_cast<Eigen::Index>(i)];
    int it = 0;
    while (rr > tau2) {
      if (it == max_iterations) return -1;
      double pap = 0;
      for (size_t i = 0; i < n; ++i) {
        const cplx v = fixed[i] ? cplx(0, 0) : (op.diagonal[i] + s * op.weight_sum[i]) * p[i] + op.off(static_cast<int>(i), p);
        ap[i] = v;
        pap += p[i].real() * v.real() + p[i].imag() * v.imag();
      }
      if (!(pap > 0)) return -1;
      const double alpha = rz / pap;
      rr = 0;
      for (size_t i = 0; i < n; ++i) {
        y[i] += alpha * p[i];
        res[i] -= alpha * ap[i];
        rr += std::norm(res[i]);
      }
      ++it;
      if (rr <= tau2) break;
      z = f.llt.solve(r);
      const double rz_new = r.dot(z).real();
      const double beta = rz_new / rz;
      rz = rz_new;
      for (size_t i = 0; i < n; ++i) p[i] = z[static_cast<Eigen::Index>(i)] + beta * p[i];
    }
    return it;
  }

  // The same CG run on the change only (a warm re-solve): e is the part of the residual res
  // that this solve brought (res − e, what the last solve left, stays out of the Krylov
  // space), d accumulates what it adds to y. e is zero outside the rows in `active` (free
  // rows), and so are p and d: each iteration grows `active` by one ring of neighbours and
  // works on those rows alone, so a mode that converges in a few iterations touches the
  // rows near the change, not all |V|. rr = ‖res‖² is the stopping test, as above (the rows
  // outside `active` keep what the last solve left: `outside`, their ‖res‖², summed by the caller
  // and kept up to date here as rows join); the caller sees to it that ‖res − e‖² is
  // well below tau2 (else it folds res − e into e and makes every free row active).
  int iterate_change(cplx* y, cplx* d, cplx* res, cplx* e, double& rr, double& outside, double tau2,
                     int max_iterations, std::vector<int>& active, ModeScratch& w) const {
    if (rr <= tau2) return 0;
    const auto n = static_cast<size_t>(op.rows);
    if (w.in.size() != n) {  // zero between calls on the rows they used
      w.in.assign(n, 0);
      w.cp.assign(n, cplx(0, 0));
      w.cap.assign(n, cplx(0, 0));
      w.cinverse.assign(n, 0.0);
      w.cdiagonal.assign(n, 0.0);
    }
    cplx *p = w.cp.data(), *ap = w.cap.data();
    char* in = w.in.data();
    double *diagonal = w.cdiagonal.data(), *inverse = w.cinverse.data();
    auto join = [&](size_t i) {
      in[i] = 1;
      diagonal[i] = op.diagonal[i] + s * op.weight_sum[i];
      inverse[i] = 1.0 / diagonal[i];
    };
    double rz = 0;
    for (const int a : active) {
      const auto i = static_cast<size_t>(a);
      join(i);
      p[i] = inverse[i] * e[i];
      rz += inverse[i] * std::norm(e[i]);
    }
    size_t frontier = 0;                          // active[frontier, end): not yet grown from
    int it = 0, result = 0;
    for (;;) {
      if (rr <= tau2) {
        result = it;
        break;
      }
      if (it == max_iterations || !(rz > 0)) {
        result = -1;
        break;
      }
      const size_t end = active.size();
      for (size_t a = frontier; a < end; ++a) {
        const auto i = static_cast<size_t>(active[a]);
        for (int k = op.row_start[i]; k < op.row_start[i + 1]; ++k) {
          const auto j = static_cast<size_t>(op.column[static_cast<size_t>(k)]);
          if (in[j] || fixed[j]) continue;
          join(j);
          active.push_back(static_cast<int>(j));
          outside -= std::norm(res[j]);
        }
      }
      frontier = end;
      double pap = 0;
      for (const int a : active) {
        const auto i = static_cast<size_t>(a);
        const cplx v = diagonal[i] * p[i] + op.off(a, p);
        ap[i] = v;
        pap += p[i].real() * v.real() + p[i].imag() * v.imag();
      }
      if (!(pap > 0)) {
        result = -1;
        break;
      }
      const double alpha = rz / pap;
      double rz_new = 0, inside = 0;
      for (const int a : active) {
        const auto i = static_cast<size_t>(a);
        const cplx step = alpha * p[i], change = alpha * ap[i];
        y[i] += step;
        d[i] += step;
        e[i] -= change;
        res[i] -= change;
        const double q = std::norm(e[i]);
        inside += std::norm(res[i]);
        rz_new += inverse[i] * q;
      }
      rr = std::max(outside, 0.0) + inside;
      ++it;
      const double beta = rz_new / rz;
      rz = rz_new;
      for (const int a : active) {
        const auto i = static_cast<size_t>(a);
        p[i] = inverse[i] * e[i] + beta * p[i];
      }
    }
    for (const int a : active) {
      const auto i = static_cast<size_t>(a);
      in[i] = 0;
      p[i] = ap[i] = 0;
    }
    return result;
  }
};

// One low temporal mode q of a segment as a coarse space for CG when the fixed set moves
// (solve/spacetime_coarse.h: coarse_weight).
struct CoarseMode {
  size_t first = 0, count = 0;  // the segment's frames
  Eigen::VectorXd q;            // the mode over them
  std::vector<double> scale;    // √s_i
  std::vector<double> shift;    // T_ii
};

struct CoarseSystem {
  const SpaceTimeSolver::Operator& op;
  const CoarseMode& mode;

  // Jacobi-PCG on E y = g from y = 0 until ‖g − E y‖ ≤ tolerance·‖g‖ (or max_iterations).
  // Returns the iterations.
  int solve(const cplx* g, cplx* y, double tolerance, int max_iterations, ModeScratch& w) const {
    const auto n = static_cast<size_t>(op.rows);
    w.resize(n);
    cplx *p = w.p.data(), *ap = w.ap.data();
    double *diagonal = w.diagonal.data(), *inverse = w.inverse.data();
    const double* sc = mode.scale.data();
    if (w.res.size() != n) w.res.resize(n), w.sp.resize(n);
    cplx *res = w.res.data(), *sp = w.sp.data();
    double rz = 0, rr = 0;
    for (size_t i = 0; i < n; ++i) {
      y[i] = 0;
      const bool out = sc[i] == 0;
      diagonal[i] = out ? 0.0 : sc[i] * sc[i] * op.diagonal[i] + mode.shift[i];
      inverse[i] = out ? 0.0 : 1.0 / diagonal[i];
      res[i] = out ? cplx(0, 0) : g[i];
      p[i] = inverse[i] * res[i];
      rz += inverse[i] * std::norm(res[i]);
      rr += std::norm(res[i]);
    }
    const double tau2 = tolerance * tolerance * rr;
    int it = 0;
    while (rr > tau2 && it < max_iterations) {
      double pap = 0;
      for (size_t i = 0; i < n; ++i) sp[i] = sc[i] * p[i];
      for (size_t i = 0; i < n; ++i) {
        const cplx v = sc[i] == 0 ? cplx(0, 0) : diagonal[i] * p[i] + sc[i] * op.off(static_cast<int>(i), sp);
        ap[i] = v;
        pap += p[i].real() * v.real() + p[i].imag() * v.imag();
      }
      if (!(pap > 0)) break;
      const double alpha = rz / pap;
      double rz_new = 0;
      rr = 0;
      for (size_t i = 0; i < n; ++i) {
        y[i] += alpha * p[i];
        res[i] -= alpha * ap[i];
        const double q = std::norm(res[i]);
        rr += q;
        rz_new += inverse[i] * q;
      }
      ++it;
      const double beta = rz_new / rz;
      rz = rz_new;
      for (size_t i = 0; i < n; ++i) p[i] = inverse[i] * res[i] + beta * p[i];
    }
    return it;
  }
};

// How a budget of squared residual is shared among modes whose squared residuals are
// rr0 now: modes already below an equal share of what is left keep theirs, and give the
// rest to the others (water filling). Returns the level each remaining mode must reach
// (infinity when every mode is already within its share).
double share_level(std::vector<double> rr0, double budget) {
  std::sort(rr0.begin(), rr0.end());
  double left = budget;
  size_t count = rr0.size();
  for (const double r : rr0) {
    if (r > left / static_cast<double>(count)) return left / static_cast<double>(count);
    left -= r;
    --count;
  }
  return std::numeric_limits<double>::infinity();
}

// out = in · m (or in · mᵀ) for a tall frame-major block: rows = 2·|V| real numbers
// (re, im interleaved), one column per frame.
void multiply_rows(const double* in, const Eigen::MatrixXd& m, bool transpose, double* out, Eigen::Index rows) {
  // Fixed blocks of rows, each an Eigen product on one thread, the blocks in parallel: every
  // row is computed by the same kernel whatever the thread count. (OpenBLAS's dgemm split
  // the rows by its own thread count, and as it runs on one thread while a CHOLMOD
  // factorization runs elsewhere, by timing too: example 06 came out with other bits on one
  // CPU than on two.)
  const Eigen::Index c = m.rows();
  constexpr Eigen::Index kRows = 2048;
  const Eigen::Index blocks = (rows + kRows - 1) / kRows;
  const Eigen::Map<const Eigen::MatrixXd, 0, Eigen::OuterStride<>> a(in, rows, c, Eigen::OuterStride<>(rows));
  Eigen::Map<Eigen::MatrixXd, 0, Eigen::OuterStride<>> y(out, rows, c, Eigen::OuterStride<>(rows));
  tbb::parallel_for(Eigen::Index{0}, blocks, [&](Eigen::Index b) {
    const Eigen::Index r0 = b * kRows, nr = std::min(kRows, rows - r0);
    if (transpose)
      y.middleRows(r0, nr).noalias() = a.middleRows(r0, nr) * m.transpose();
    else
      y.middleRows(r0, nr).noalias() = a.middleRows(r0, nr) * m;
  });
}

}  // namespace

SpaceTimeSolver::SpaceTimeSolver(const ConnectionLaplacian& laplacian, int frames,
                                 double temporal_weight)
    : laplacian_(laplacian), frames_(frames), b_(temporal_weight) {
  TVF_CHECK(laplacian.hermitian, "the space-time solve needs Hermitian (cotan or uniform) weights");
  TVF_CHECK(frames >= 1, "{} frames", frames);
  auto op = std::make_shared<Operator>();
  const Eigen::SparseMatrix<cplx, Eigen::RowMajor> rows = laplacian.matrix;
  const auto n = static_cast<size_t>(rows.rows());
  op->rows = static_cast<int>(n);
  op->row_start.assign(n + 1, 0);
  op->diagonal.assign(n, 0.0);
  op->weight_sum.assign(laplacian.weight_sum.data(), laplacian.weight_sum.data() + n);
  for (Eigen::Index i = 0; i < rows.outerSize(); ++i) {
    for (Eigen::SparseMatrix<cplx, Eigen::RowMajor>::InnerIterator it(rows, i); it; ++it) {
      if (it.col() == i) {
        op->diagonal[static_cast<size_t>(i)] = it.value().real();
      } else {
        op->column.push_back(static_cast<int>(it.col()));
        op->value.push_back(it.value());
      }
    }
    op->row_start[static_cast<size_t>(i) + 1] = static_cast<int>(op->column.size());
  }
  op_ = std::move(op);
}

void SpaceTimeSolver::interpolate_in_time(std::span<const char> fixed, std::span<const cplx> values,
                                          std::span<cplx> z) const {
  interpolate_lines_in_time(fixed, values, z, static_cast<size_t>(vertices()), static_cast<size_t>(frames_));
}

void interpolate_lines_in_time(std::span<const char> fixed, std::span<const cplx> values, std::span<cplx> z,
                               size_t n, size_t nf) {
  for (size_t i = 0; i < n; ++i) {
    long last = -1;
    for (size_t j = 0; j <= nf; ++j) {
      const bool at_end = j == nf;
      if (!at_end && !fixed[j * n + i]) continue;
      // Fill the free entries between the previous fixed frame `last` and j.
      const size_t from = last < 0 ? 0 : static_cast<size_t>(last) + 1;
      for (size_t k = from; k < j; ++k) {
        cplx v(0, 0);
        if (last >= 0 && !at_end) {
          const double w = static_cast<double>(k - static_cast<size_t>(last)) /
                           static_cast<double>(j - static_cast<size_t>(last));
          v = (1 - w) * values[static_cast<size_t>(last) * n + i] + w * values[j * n + i];
        } else if (last >= 0) {
          v = values[static_cast<size_t>(last) * n + i];
        } else if (!at_end) {
          v = values[j * n + i];
        }
        z[k * n + i] = v;
      }
      if (!at_end) {
        z[j * n + i] = values[j * n + i];
        last = static_cast<long>(j);
      }
    }
  }
}

Segments find_segments(std::span<const char> fixed, size_t n, size_t nf) {
  std::vector<char> key(nf, 0);
  for (size_t j = 0; j < nf; ++j)
    key[j] = std::all_of(fixed.begin() + static_cast<std::ptrdiff_t>(j * n),
                         fixed.begin() + static_cast<std::ptrdiff_t>((j + 1) * n), [](char c) { return c != 0; });
  return segments_between(std::move(key));
}

Segments segments_between(std::vector<char> key) {
  Segments s;
  s.key = std::move(key);
  const size_t nf = s.key.size();
  for (size_t j = 0; j < nf;) {
    if (s.key[j]) {
      ++j;
      continue;
    }
    size_t e = j;
    while (e < nf && !s.key[e]) ++e;
    s.segments.emplace_back(j, e - j);
    j = e;
  }
  return s;
}

namespace {

// The modes with local solves (SpaceTimeMethod::modes_local): one segment's moving
// constraints. The modes take the segment's common fixed set (`base`: vertices fixed at
// every frame of it); the entries fixed at some frames only (a moving element's region) are
// constraints on the vertices `cut`, imposed by a local solve on `omega` (cut and rings of
// neighbours around it, base left out) after every round of the modes' solves.
struct MovingSegment {
  std::vector<char> base;        // per vertex
  std::vector<int> cut, omega;   // sorted vertex lists; cut ⊂ omega
  std::vector<int> outer;        // neither in omega nor in base, next to omega: where A u leaks
  std::vector<int> leak_rows;    // omega, then outer
  std::vector<int> local_of;     // per vertex: index in omega, or −1
  std::vector<int> cut_local;    // per cut vertex: its index in omega
  // L's rows of omega and of outer restricted to omega's columns (local indices).
  std::vector<int> start{0}, column, outer_start{0}, outer_column;
  std::vector<cplx> value, outer_value;
  // |omega| × count, vertex-major (q = li·count + jj): the constraint entries and the
  // temporal line solves' factors on the other entries.
  std::vector<char> moving;
  std::vector<double> lower, pivot, upper;
  // The cut rows in groups for cut_rows_to_frames: their indices in cut, ordered by the
  // first constraint entry of their line, kCutGroup at a time; per group the frames
  // [window_first, window_end) that hold every constraint entry of its rows.
  std::vector<int> cut_order, window_first, window_end;
};

// Cut rows gathered together into one product with the frames they need (see
// cut_rows_to_frames): a group's window is the union of its rows' constraint entries.
constexpr size_t kCutGroup = 8;

// A segment's common fixed set and the vertices whose temporal line its fixed set cuts.
void common_fixed_set(std::span<const char> fixed, size_t n, size_t first, size_t count, std::vector<char>& base,
                      std::vector<int>& cut) {
  std::vector<char> any(n, 0);
  base.assign(n, 1);
  for (size_t j = first; j < first + count; ++j) {
    const char* fj = fixed.data() + j * n;
    for (size_t i = 0; i < n; ++i) {
      if (fj[i])
        any[i] = 1;
      else
        base[i] = 0;
    }
  }
  cut.clear();
  for (size_t i = 0; i < n; ++i)
    if (any[i] && !base[i]) cut.push_back(static_cast<int>(i));
}

// The rows of a segment's modes (hat: 2|V| × count, re and im rows interleaved) at m's cut
// vertices back into frames (out: vertex-major, count per cut row; rows of hat · Qᵀ), at
// their constraint entries only: the rounds read nothing else there. A cut vertex's
// constraint entries span a few of the segment's frames (a moving region passes it), so
// each group of cut rows is multiplied by its window's rows of Q alone (2·kCutGroup ×
// count by count × window) instead of by all of Qᵀ. The other entries of out are zero.
void cut_rows_to_frames(const std::vector<double>& hat, size_t n, const MovingSegment& m, const Eigen::MatrixXd& q,
                        std::vector<cplx>& out, bool parallel) {
  const auto count = q.rows();
  const auto c = static_cast<size_t>(count);
  const Eigen::Map<const Eigen::MatrixXd> h(hat.data(), static_cast<Eigen::Index>(2 * n), count);
  out.assign(m.cut.size() * c, cplx(0, 0));
  // The groups write disjoint rows of out: in parallel or not, the same bits.
  const size_t groups = (m.cut_order.size() + kCutGroup - 1) / kCutGroup;
  auto run = [&](size_t group) {
    Eigen::MatrixXd g, f;
    const size_t g0 = group * kCutGroup;
    const size_t size = std::min(kCutGroup, m.cut_order.size() - g0);
    const Eigen::Index lo = m.window_first[group], len = m.window_end[group] - lo;
    g.resize(static_cast<Eigen::Index>(2 * size), count);
    for (Eigen::Index k = 0; k < count; ++k)
      for (size_t t = 0; t < size; ++t) {
        const int row = m.cut[static_cast<size_t>(m.cut_order[g0 + t])];
        g(static_cast<Eigen::Index>(2 * t), k) = h(2 * row, k);
        g(static_cast<Eigen::Index>(2 * t + 1), k) = h(2 * row + 1, k);
      }
    f.noalias() = g * q.middleRows(lo, len).transpose();
    for (size_t t = 0; t < size; ++t) {
      cplx* o = out.data() + static_cast<size_t>(m.cut_order[g0 + t]) * c + static_cast<size_t>(lo);
      for (Eigen::Index jj = 0; jj < len; ++jj)
        o[jj] = cplx(f(static_cast<Eigen::Index>(2 * t), jj), f(static_cast<Eigen::Index>(2 * t + 1), jj));
    }
  };
  if (parallel && groups > 1)
    tbb::parallel_for(size_t{0}, groups, run);
  else
    for (size_t group = 0; group < groups; ++group) run(group);
}

// hat's rows += values (vertex-major, count per row) · Q; rr[k] (‖column k‖²) updated when
// given, and the same added to also's rows when given. In parallel or not, by fixed blocks
// of Q's columns (each column's product and sum the same either way).
void add_frames_to_rows(std::vector<double>& hat, size_t n, const std::vector<int>& rows, const Eigen::MatrixXd& q,
                        const std::vector<cplx>& values, double* rr, std::vector<double>* also = nullptr,
                        bool parallel = false) {
  const auto count = q.rows();
  const auto c = static_cast<size_t>(count);
  Eigen::Map<Eigen::MatrixXd> h(hat.data(), static_cast<Eigen::Index>(2 * n), count);
  // Rows whose values are all zero add nothing: left out (a warm re-solve's local solves
  // change few of omega's rows).
  std::vector<size_t> some;
  for (size_t r = 0; r < rows.size(); ++r)
    if (std::any_of(values.begin() + static_cast<std::ptrdiff_t>(r * c),
                    values.begin() + static_cast<std::ptrdiff_t>((r + 1) * c), [](cplx v) { return v != cplx(0, 0); }))
      some.push_back(r);
  Eigen::MatrixXd f(static_cast<Eigen::Index>(2 * some.size()), count);
  for (size_t t = 0; t < some.size(); ++t)
    for (Eigen::Index jj = 0; jj < count; ++jj) {
      const cplx v = values[some[t] * c + static_cast<size_t>(jj)];
      f(static_cast<Eigen::Index>(2 * t), jj) = v.real();
      f(static_cast<Eigen::Index>(2 * t + 1), jj) = v.imag();
    }
  constexpr Eigen::Index kColumns = 16;
  const Eigen::Index nblocks = (count + kColumns - 1) / kColumns;
  auto block = [&](Eigen::Index b) {
    const Eigen::Index k0 = b * kColumns, len = std::min(kColumns, count - k0);
    const Eigen::MatrixXd g = f * q.middleCols(k0, len);
    // Column by column (all three matrices are column-major); each rr[k] sums its rows in
    // the same order as row by row.
    for (Eigen::Index col = 0; col < len; ++col) {
      const Eigen::Index k = k0 + col;
      double* also_k = also ? also->data() + static_cast<size_t>(k) * 2 * n : nullptr;
      double sum = 0;
      for (size_t r = 0; r < some.size(); ++r)
        for (int part = 0; part < 2; ++part) {
          const Eigen::Index row = 2 * rows[some[r]] + part;
          const double add = g(static_cast<Eigen::Index>(2 * r) + part, col);
          const double old = h(row, k), now = old + add;
          sum += now * now - old * old;
          h(row, k) = now;
          if (also_k) also_k[row] += add;
        }
      if (rr) rr[k] += sum;
    }
  };
  if (parallel && nblocks > 1)
    tbb::parallel_for(Eigen::Index{0}, nblocks, block);
  else
    for (Eigen::Index b = 0; b < nblocks; ++b) block(b);
}

// A warm re-solve's change back into frames: x (a segment's frames, 2|V| × count real,
// column-major as the modes) += d · Qᵀ, d the change of the segment's modes in this solve,
// zero outside few rows in all but the slowest modes (iterate_change): outside the rows
// reach_of[k] lists for mode k. e (the change's residual) is zero outside the rows
// clear_of[k] lists (a superset: with moving constraints the last local solve's leak joins
// them after the modes' last solve). The modes, ordered by how many rows they reach, go in
// groups whose rows (the union) are gathered and multiplied, 2|T| × g by g × count, instead
// of all 2|V| rows by every mode. d and e are left zero. The groups and the row blocks do
// not depend on the thread count, nor does any row's sum. Returns the rows reached, summed
// over the modes.
size_t add_change_to_frames(std::vector<double>& d, std::vector<double>& e, size_t n, const Eigen::MatrixXd& q,
                            const std::vector<std::span<const int>>& reach_of,
                            const std::vector<const std::vector<int>*>& clear_of, double* x, bool parallel) {
  const auto count = static_cast<size_t>(q.rows());
  auto reach = [&](size_t k) { return reach_of[k]; };
  // Each mode's column alone: in parallel or not, the same.
  auto each_column = [&](auto&& body) {
    if (parallel)
      tbb::parallel_for(size_t{0}, count, body);
    else
      for (size_t k = 0; k < count; ++k) body(k);
  };
  each_column([&](size_t k) {
    cplx* ek = reinterpret_cast<cplx*>(e.data() + 2 * n * k);
    for (const int i : *clear_of[k]) ek[i] = 0;
  });
  std::vector<size_t> order;
  for (size_t k = 0; k < count; ++k)
    if (!reach(k).empty()) order.push_back(k);
  std::stable_sort(order.begin(), order.end(), [&](size_t a, size_t b) { return reach(a).size() > reach(b).size(); });
  std::vector<int> stamp(n, -1);
  const Eigen::Map<const Eigen::MatrixXd> dm(d.data(), static_cast<Eigen::Index>(2 * n), static_cast<Eigen::Index>(count));
  Eigen::Map<Eigen::MatrixXd> xm(x, static_cast<Eigen::Index>(2 * n), static_cast<Eigen::Index>(count));
  constexpr size_t kGroup = 16;
  for (size_t g0 = 0; g0 < order.size();) {
    // Modes reaching at least half the rows of the group's first, at most kGroup of them.
    size_t g1 = g0 + 1;
    while (g1 < order.size() && g1 - g0 < kGroup && 2 * reach(order[g1]).size() >= reach(order[g0]).size()) ++g1;
    const auto group = static_cast<int>(g0);
    std::vector<int> rows;
    for (size_t c = g0; c < g1; ++c)
      for (const int i : reach(order[c]))
        if (stamp[static_cast<size_t>(i)] != group) stamp[static_cast<size_t>(i)] = group, rows.push_back(i);
    std::sort(rows.begin(), rows.end());
    const auto g = static_cast<Eigen::Index>(g1 - g0);
    Eigen::MatrixXd qg(static_cast<Eigen::Index>(count), g);
    for (Eigen::Index c = 0; c < g; ++c) qg.col(c) = q.col(static_cast<Eigen::Index>(order[g0 + static_cast<size_t>(c)]));
    // Fixed blocks of 1024 rows (vertices), each gathered, multiplied and added on one thread.
    constexpr size_t kRowsPerBlock = 1024;
    const size_t nblocks = (rows.size() + kRowsPerBlock - 1) / kRowsPerBlock;
    auto block = [&](size_t b) {
      const size_t t0 = b * kRowsPerBlock, nt = std::min(kRowsPerBlock, rows.size() - t0);
      Eigen::MatrixXd gathered(static_cast<Eigen::Index>(2 * nt), g);
      for (Eigen::Index c = 0; c < g; ++c) {
        const auto k = static_cast<Eigen::Index>(order[g0 + static_cast<size_t>(c)]);
        for (size_t t = 0; t < nt; ++t) {
          const auto row = static_cast<Eigen::Index>(2 * rows[t0 + t]);
          gathered(static_cast<Eigen::Index>(2 * t), c) = dm(row, k);
          gathered(static_cast<Eigen::Index>(2 * t + 1), c) = dm(row + 1, k);
        }
      }
      const Eigen::MatrixXd r = gathered * qg.transpose();
      for (Eigen::Index jj = 0; jj < static_cast<Eigen::Index>(count); ++jj)
        for (size_t t = 0; t < nt; ++t) {
          const auto row = static_cast<Eigen::Index>(2 * rows[t0 + t]);
          xm(row, jj) += r(static_cast<Eigen::Index>(2 * t), jj);
          xm(row + 1, jj) += r(static_cast<Eigen::Index>(2 * t + 1), jj);
        }
    };
    if (parallel && nblocks > 1)
      tbb::parallel_for(size_t{0}, nblocks, block);
    else
      for (size_t b = 0; b < nblocks; ++b) block(b);
    g0 = g1;
  }
  size_t reached = 0;
  for (size_t k = 0; k < count; ++k) reached += reach(k).size();
  each_column([&](size_t k) {
    cplx* dk = reinterpret_cast<cplx*>(d.data() + 2 * n * k);
    for (const int i : reach(k)) dk[i] = 0;
  });
  return reached;
}

// The local solve's set-up for a segment whose common fixed set and cut vertices are in m.
void build_moving(const SpaceTimeSolver::Operator& op, std::span<const char> fixed, size_t n, size_t nf, size_t first,
                  size_t count, int rings, double b, MovingSegment& m) {
  std::vector<char> in(n, 0);
  for (const int i : m.cut) in[static_cast<size_t>(i)] = 1;
  for (int ring = 0; ring < rings; ++ring) {
    std::vector<char> grown = in;
    for (size_t i = 0; i < n; ++i)
      if (in[i])
        for (int e = op.row_start[i]; e < op.row_start[i + 1]; ++e)
          grown[static_cast<size_t>(op.column[static_cast<size_t>(e)])] = 1;
    in = std::move(grown);
  }
  m.local_of.assign(n, -1);
  m.omega.clear();
  for (size_t i = 0; i < n; ++i)
    if (in[i] && !m.base[i]) {
      m.local_of[i] = static_cast<int>(m.omega.size());
      m.omega.push_back(static_cast<int>(i));
    }
  m.cut_local.clear();
  for (const int i : m.cut) m.cut_local.push_back(m.local_of[static_cast<size_t>(i)]);
  std::vector<char> near(n, 0);
  for (const int i : m.omega)
    for (int e = op.row_start[static_cast<size_t>(i)]; e < op.row_start[static_cast<size_t>(i) + 1]; ++e) {
      const auto c = static_cast<size_t>(op.column[static_cast<size_t>(e)]);
      if (m.local_of[c] < 0 && !m.base[c]) near[c] = 1;
    }
  m.outer.clear();
  for (size_t i = 0; i < n; ++i)
    if (near[i]) m.outer.push_back(static_cast<int>(i));
  m.leak_rows = m.omega;
  m.leak_rows.insert(m.leak_rows.end(), m.outer.begin(), m.outer.end());
  auto gather = [&](size_t i, std::vector<int>& start, std::vector<int>& col, std::vector<cplx>& val) {
    for (int e = op.row_start[i]; e < op.row_start[i + 1]; ++e) {
      const int c = m.local_of[static_cast<size_t>(op.column[static_cast<size_t>(e)])];
      if (c >= 0) col.push_back(c), val.push_back(op.value[static_cast<size_t>(e)]);
    }
    start.push_back(static_cast<int>(col.size()));
  };
  for (const int i : m.omega) gather(static_cast<size_t>(i), m.start, m.column, m.value);
  for (const int i : m.outer) gather(static_cast<size_t>(i), m.outer_start, m.outer_column, m.outer_value);
  // The temporal line solves on omega's lines, split at the constraint entries; the key
  // frames beyond the segment are fixed (zero in a correction).
  const size_t nq = m.omega.size() * count;
  m.moving.assign(nq, 0);
  m.lower.assign(nq, 0.0), m.pivot.assign(nq, 0.0), m.upper.assign(nq, 0.0);
  for (size_t li = 0; li < m.omega.size(); ++li) {
    const auto i = static_cast<size_t>(m.omega[li]);
    const double c = b * op.weight_sum[i];
    for (size_t jj = 0; jj < count; ++jj) {
      const size_t j = first + jj, q = li * count + jj;
      m.moving[q] = fixed[j * n + i];
    }
    for (size_t jj = 0; jj < count; ++jj) {
      const size_t j = first + jj, q = li * count + jj;
      if (m.moving[q]) continue;
      const double diag = op.diagonal[i] + c * ((j > 0 ? 1 : 0) + (j + 1 < nf ? 1 : 0));
      const double lo = (jj > 0 && !m.moving[q - 1]) ? -c : 0.0;
      const double up = (jj + 1 < count && !m.moving[q + 1]) ? -c : 0.0;
      const double denom = diag - lo * (jj > 0 ? m.upper[q - 1] : 0.0);
      m.lower[q] = lo;
      m.pivot[q] = 1.0 / denom;
      m.upper[q] = up / denom;
    }
  }
  // The cut rows' windows: each row's first and last constraint entry, the rows ordered by
  // the first, then grouped.
  std::vector<int> first_entry(m.cut.size()), end_entry(m.cut.size());
  for (size_t r = 0; r < m.cut.size(); ++r) {
    const size_t q0 = static_cast<size_t>(m.cut_local[r]) * count;
    size_t lo = count, hi = 0;
    for (size_t jj = 0; jj < count; ++jj)
      if (m.moving[q0 + jj]) lo = std::min(lo, jj), hi = jj + 1;
    if (lo > hi) lo = hi = 0;  // no constraint entry in this segment
    first_entry[r] = static_cast<int>(lo);
    end_entry[r] = static_cast<int>(hi);
  }
  m.cut_order.resize(m.cut.size());
  std::iota(m.cut_order.begin(), m.cut_order.end(), 0);
  std::stable_sort(m.cut_order.begin(), m.cut_order.end(),
                   [&](int r0, int r1) { return first_entry[static_cast<size_t>(r0)] < first_entry[static_cast<size_t>(r1)]; });
  m.window_first.clear();
  m.window_end.clear();
  for (size_t g0 = 0; g0 < m.cut_order.size(); g0 += kCutGroup) {
    int lo = static_cast<int>(count), hi = 0;
    for (size_t t = g0; t < std::min(g0 + kCutGroup, m.cut_order.size()); ++t) {
      const auto r = static_cast<size_t>(m.cut_order[t]);
      if (end_entry[r] == 0) continue;
      lo = std::min(lo, first_entry[r]);
      hi = std::max(hi, end_entry[r]);
    }
    if (lo > hi) lo = hi = 0;
    m.window_first.push_back(lo);
    m.window_end.push_back(hi);
  }
}

// The local solve of a round: u on omega's lines with u = −ε at the constraint entries
// (ε: what the modes' solution has there) and (A u) = 0 at the other entries, zero around
// omega and at the key frames (CG with the line solves to kMovingLocalTolerance). Returns
// the CG iterations; u holds the solution (vertex-major, count per vertex).
struct LocalSolve {
  const SpaceTimeSolver::Operator& op;
  const MovingSegment& m;
  size_t nf, first, count;
  double b;
  std::vector<cplx> r, z, p, ap;
  std::vector<char> hot;  // per omega line: u not zero on it
  bool parallel = false;  // the lines by fixed blocks on threads (each line's sum kept, added in line order)
  std::vector<double> line_dot;

  // body(li) for every omega line, by fixed blocks of lines (in parallel or not), then
  // Σ line_dot[li] in line order: the same bits either way.
  template <class F>
  double each_line(F&& body) {
    const size_t nl = m.omega.size();
    line_dot.resize(nl);
    constexpr size_t kLines = 64;  // a multiple of lines()'s group
    const size_t nb = (nl + kLines - 1) / kLines;
    auto block = [&](size_t k) { body(k * kLines, std::min(nl, (k + 1) * kLines)); };
    if (parallel && nb > 1)
      tbb::parallel_for(size_t{0}, nb, block);
    else
      for (size_t k = 0; k < nb; ++k) block(k);
    double dot = 0;
    for (size_t li = 0; li < nl; ++li) dot += line_dot[li];
    return dot;
  }

  // y = (A u) on omega vertex li's line, u zero outside omega (every entry of u counts).
  void product(const cplx* u, size_t li, cplx* y) const {
    const auto i = static_cast<size_t>(m.omega[li]);
    const double c = b * op.weight_sum[i];
    const cplx* ui = u + li * count;
    for (size_t jj = 0; jj < count; ++jj) {
      const size_t j = first + jj;
      cplx t = (op.diagonal[i] + c * ((j > 0 ? 1 : 0) + (j + 1 < nf ? 1 : 0))) * ui[jj];
      if (jj > 0) t -= c * ui[jj - 1];
      if (jj + 1 < count) t -= c * ui[jj + 1];
      y[jj] = t;
    }
    // Complex products written out (std::complex's operator* checks for NaN and does not
    // vectorise).
    for (int e = m.start[li]; e < m.start[li + 1]; ++e) {
      const cplx v = m.value[static_cast<size_t>(e)];
      const double vr = v.real(), vi = v.imag();
      const double* uc = reinterpret_cast<const double*>(u + static_cast<size_t>(m.column[static_cast<size_t>(e)]) * count);
      double* yd = reinterpret_cast<double*>(y);
      for (size_t jj = 0; jj < count; ++jj) {
        const double re = uc[2 * jj], im = uc[2 * jj + 1];
        yd[2 * jj] += vr * re - vi * im;
        yd[2 * jj + 1] += vr * im + vi * re;
      }
    }
  }
  // y = (A u) on the free entries of omega's lines (constraint entries: 0); returns Re <u, y>.
  double apply(const std::vector<cplx>& u, std::vector<cplx>& y) {
    return each_line([&](size_t l0, size_t l1) {
      for (size_t li = l0; li < l1; ++li) {
        product(u.data(), li, y.data() + li * count);
        double part[2] = {0, 0};
        for (size_t q = li * count; q < (li + 1) * count; ++q) {
          if (m.moving[q]) y[q] = 0;
          part[q & 1] += u[q].real() * y[q].real() + u[q].imag() * y[q].imag();
        }
        line_dot[li] = part[0] + part[1];
      }
    });
  }
  // zl = the temporal line solves of rl on omega's lines; returns Re <rl, zl>. A line's
  // substitutions are chains of dependent multiply-adds, so kGroup lines go side by side
  // (independent chains keep the pipeline busy); each entry's arithmetic is that of one
  // line alone. With the partial sums in local_pcg a small gain, within the noise of the
  // loaded machine it was measured on (the local CG 11–12 ms a round before, 10–12 after:
  // 65² grid, moving vortex, 12 iterations).
  double lines(const std::vector<cplx>& rl, std::vector<cplx>& zl) {
    constexpr size_t kGroup = 4;
    const double *lower = m.lower.data(), *pivot = m.pivot.data(), *upper = m.upper.data();
    const cplx* rs = rl.data();
    cplx* zs = zl.data();
    auto group = [&]<size_t G>(size_t li) {
      size_t q0[G];
      double part[G];
      for (size_t g = 0; g < G; ++g) q0[g] = (li + g) * count, part[g] = 0;
      for (size_t g = 0; g < G; ++g) zs[q0[g]] = rs[q0[g]] * pivot[q0[g]];
      for (size_t jj = 1; jj < count; ++jj)
        for (size_t g = 0; g < G; ++g) {
          const size_t q = q0[g] + jj;
          zs[q] = (rs[q] - lower[q] * zs[q - 1]) * pivot[q];
        }
      for (size_t g = 0; g < G; ++g) {
        const size_t q = q0[g] + count - 1;
        part[g] += rs[q].real() * zs[q].real() + rs[q].imag() * zs[q].imag();
      }
      for (size_t jj = count - 1; jj-- > 0;)
        for (size_t g = 0; g < G; ++g) {
          const size_t q = q0[g] + jj;
          zs[q] -= upper[q] * zs[q + 1];
          part[g] += rs[q].real() * zs[q].real() + rs[q].imag() * zs[q].imag();
        }
      for (size_t g = 0; g < G; ++g) line_dot[li + g] = part[g];
    };
    return each_line([&](size_t l0, size_t l1) {
      size_t li = l0;
      for (; li + kGroup <= l1; li += kGroup) group.template operator()<kGroup>(li);
      for (; li < l1; ++li) group.template operator()<1>(li);
    });
  }
  // u holds −ε at the constraint entries and anything elsewhere on entry. CG until the
  // residual is `tolerance` of its start or below √floor2 (what the round's budget needs).
  int solve(std::vector<cplx>& u, double tolerance, double floor2, int max_iterations) {
    const size_t nq = u.size();
    r.resize(nq), z.resize(nq), p.resize(nq), ap.resize(nq);
    for (size_t q = 0; q < nq; ++q)
      if (!m.moving[q]) u[q] = 0;
    // r = −A u_constraints on the free entries: zero but on the lines where u is not and
    // their neighbours (a warm re-solve's change reaches few of omega's lines).
    const size_t nl = m.omega.size();
    hot.assign(nl, 0);
    for (size_t li = 0; li < nl; ++li)
      hot[li] = std::any_of(u.begin() + static_cast<std::ptrdiff_t>(li * count),
                            u.begin() + static_cast<std::ptrdiff_t>((li + 1) * count), [](cplx v) { return v != cplx(0, 0); });
    double rr = 0;
    for (size_t li = 0; li < nl; ++li) {
      bool near = hot[li] != 0;
      for (int e = m.start[li]; e < m.start[li + 1] && !near; ++e) near = hot[static_cast<size_t>(m.column[static_cast<size_t>(e)])] != 0;
      if (!near) {
        std::fill(r.begin() + static_cast<std::ptrdiff_t>(li * count), r.begin() + static_cast<std::ptrdiff_t>((li + 1) * count),
                  cplx(0, 0));
        continue;
      }
      product(u.data(), li, r.data() + li * count);
      for (size_t q = li * count; q < (li + 1) * count; ++q) {
        r[q] = m.moving[q] ? cplx(0, 0) : -r[q];
        rr += std::norm(r[q]);
      }
    }
    const double tau2 = std::max(tolerance * tolerance * rr, floor2);
    // p stays zero at the constraint entries, so u keeps them.
    return local_pcg(u, r, z, p, ap, rr, tau2, max_iterations, [&](const Vec& x, Vec& y) { return apply(x, y); },
                     [&](const Vec& x, Vec& y) { return lines(x, y); });
  }
};

}  // namespace

// The modes with local solves' set-up for one fixed set (Workspace::local): per segment its
// moving constraints and local solve, built by the first solve with that fixed set and
// used as they are by the next ones while it stays (a warm re-solve after an edit). And
// the local solves' part of the result not yet in the modes (`pending`): a re-solve that
// solves for the change alone adds what its local solves found to x in frames, and of x's
// modes it reads only the cut rows (the local rounds' constraint values), so that part is
// kept in frames (omega × count, and the multipliers' cut × count), summed over such
// solves, instead of being transformed into x_hat and r_hat (|omega| × count by count ×
// count) each time; the cut rows read it beside their modes. Any other solve adds it into
// the modes first where it keeps them (flush), or drops it where it transforms them again.
struct SpaceTimeSolver::Workspace::LocalSetup {
  int rings = -1;
  std::vector<std::pair<size_t, size_t>> segments;
  std::vector<MovingSegment> moving;         // per segment
  std::vector<LocalSolve> solves;            // per segment, on `moving` (built once it is)
  std::vector<std::vector<cplx>> x, lambda;  // pending, per segment: omega × count, cut × count
  bool pending = false;                      // x or lambda may be non-zero

  // x_hat and r_hat += the pending part in the modes; then none is pending.
  void flush(std::vector<std::vector<double>>& x_hat, std::vector<std::vector<double>>& r_hat, size_t n,
             const std::vector<const Eigen::MatrixXd*>& q) {
    if (!pending) return;
    for (size_t si = 0; si < moving.size(); ++si) {
      if (moving[si].cut.empty()) continue;
      add_frames_to_rows(x_hat[si], n, moving[si].omega, *q[si], x[si], nullptr);
      add_frames_to_rows(r_hat[si], n, moving[si].cut, *q[si], lambda[si], nullptr);
    }
    drop();
  }
  void drop() {
    for (auto* parts : {&x, &lambda})
      for (auto& v : *parts) std::fill(v.begin(), v.end(), cplx(0, 0));
    pending = false;
  }
};

void temporal_eigenbasis(int count, bool left_open, bool right_open, int modes, Eigen::MatrixXd& q,
                         Eigen::VectorXd& lambda) {
  // The eigenvectors are the discrete sine/cosine bases of the ends (j = 0 … m−1,
  // k = 0 … m−1):
  //   Dirichlet–Dirichlet  sin(π(k+1)(j+1)/(m+1)),   λ = 2 − 2cos(π(k+1)/(m+1))
  //   Neumann–Dirichlet    cos(π(2k+1)(j+½)/(2m+1)), λ = 2 − 2cos(π(2k+1)/(2m+1))
  //   Neumann–Neumann      cos(πk(j+½)/m),           λ = 2 − 2cos(πk/m)
  // (Dirichlet–Neumann: the second, mirrored), normalised here.
  const int m = count;
  modes = std::min(modes, m);
  q.resize(m, modes);
  lambda.resize(modes);
  for (int k = 0; k < modes; ++k) {
    double angle = 0;  // of λ = 2 − 2cos(angle)
    for (int j = 0; j < m; ++j) {
      double v = 0;
      if (!left_open && !right_open) {
        angle = kPi * (k + 1) / (m + 1);
        v = std::sin(angle * (j + 1));
      } else if (left_open != right_open) {
        angle = kPi * (2 * k + 1) / (2 * m + 1);
        const int jj = left_open ? j : m - 1 - j;
        v = std::cos(angle * (jj + 0.5));
      } else {
        angle = kPi * k / m;
        v = std::cos(angle * (j + 0.5));
      }
      q(j, k) = v;
    }
    q.col(k).normalize();
    lambda[k] = 2.0 - 2.0 * std::cos(angle);
  }
}

CoarseWeight coarse_weight(const Eigen::VectorXd& q, size_t first, std::span<const char> fixed, size_t n, size_t nf,
                           size_t i, double c) {
  const auto count = static_cast<size_t>(q.size());
  double mass = 0, t = 0;
  for (size_t jj = 0; jj < count; ++jj) {
    const size_t j = first + jj;
    if (fixed[j * n + i]) continue;
    const double qj = q[static_cast<Eigen::Index>(jj)];
    const double neighbours = (j > 0 ? 1.0 : 0.0) + (j + 1 < nf ? 1.0 : 0.0);
    mass += qj * qj;
    t += c * neighbours * qj * qj;
    if (jj + 1 < count && !fixed[(j + 1) * n + i]) t -= 2 * c * qj * q[static_cast<Eigen::Index>(jj + 1)];
  }
  if (!(mass > 1e-12)) return {};
  return {std::sqrt(mass), std::max(t, 0.0)};
}

// The transforms cost 6·m flops per entry for a segment of m frames (three products with
// the m × m basis), a CG iteration about 40: past this length CG is cheaper.
constexpr size_t kMostModeFrames = 1024;

// The two-level CG's coarse space (SpaceTimeOptions::coarse_modes lowest temporal modes of
// every segment): each mode's spatial system solved by Jacobi-PCG to this relative residual
// (or this many iterations). A tighter inner tolerance saved no outer iteration (65² grid
// × 100 with a moving vortex, docs/benchmarks.md).
constexpr double kCoarseTolerance = 1e-2;
constexpr int kCoarseIterations = 200;

// The two-level CG's local solve near a moving constraint (SpaceTimeOptions::local_rings):
// CG with the temporal line solves on the space-time entries of the vertices near the cut
// lines, to this relative residual (or this many iterations). A numpy prototype (scalar
// 65² grid × 100, a moving disc, one ring) took the same outer iterations with 1e-1 as
// with 1e-4.
constexpr double kLocalTolerance = 1e-1;
constexpr int kLocalIterations = 50;

// The modes with local solves (SpaceTimeMethod::modes_local). A round leaves a residual
// about 40× what its modes' solves left (their error at the constraint entries, mostly the
// slow lowest modes', is what the local solve corrects, and part of that correction leaks
// out of omega), and takes out all but 1–6 % of the last round's (the local solves' leak:
// 6 % with two rings, 1–2 % with four; 65² grid × 100, moving vortex). So each round solves
// the modes to this fraction of the last round's residual (solved fully every round, the
// rounds took the same number: the leak, not the modes, sets the pace; 0.005 rather than
// 0.002 saved ~5 % of the 20k sphere's solve and 3 % of the 65² grid's, 0.001 nothing;
// docs/benchmarks.md), and the local solve to this relative residual (1e-2: one or two
// rounds more; 1e-1 stalls). A round that leaves more than kRoundStall of the last one's
// residual twice in a row, or more than SpaceTimeOptions::most_rounds rounds, hands the
// rest to CG.
constexpr double kRoundReduction = 0.005;
constexpr double kMovingLocalTolerance = 1e-3;
constexpr int kMovingLocalIterations = 100;
constexpr double kRoundStall = 0.7;
// The rounds' target, as a fraction of the tolerance, and how far below it a local solve's
// own residual must go (it is part of the next round's residual).
constexpr double kMovingShare = 0.9;
constexpr double kLocalFloor = 0.25;

// Tolerances from which the temporal-mode method reports the residual its modes add up
// to instead of measuring it with another sweep over all frames.
constexpr double kModeResidualTolerance = 1e-8;

// Temporal modes whose shift b·λ_k is below this are the slow ones of the Jacobi-PCG (the
// spatial Laplacian dominates their matrix): they are solved last, with what the others
// left of the residual budget.
constexpr double kSlowShift = 1.0;

// Solving for the change (a warm re-solve): a mode whose residual left by the last solve is
// above this fraction of its target takes its whole residual instead (the change alone
// could not bring it below the target, or only with many more iterations).
constexpr double kChangeFold = 0.5;

// Solving for the change with moving constraints: the first round's modes go to this
// fraction of the rounds' target (the rest is room for the local solve's leak).
constexpr double kChangeModesShare = 0.7;

size_t SpaceTimeSolver::longest_segment(std::span<const char> fixed) const {
  size_t most = 0;
  for (const auto& s : find_segments(fixed, static_cast<size_t>(vertices()), static_cast<size_t>(frames_)).segments)
    most = std::max(most, s.second);
  return most;
}

bool SpaceTimeSolver::modes_apply(std::span<const char> fixed) const {
  const auto n = static_cast<size_t>(vertices());
  const auto nf = static_cast<size_t>(frames_);
  if (fixed.size() != n * nf) return false;
  const Segments s = find_segments(fixed, n, nf);
  for (const auto& [first, count] : s.segments) {
    const char* f0 = fixed.data() + first * n;
    for (size_t j = first + 1; j < first + count; ++j)
      if (!std::equal(f0, f0 + n, fixed.data() + j * n)) return false;
  }
  return true;
}

bool SpaceTimeSolver::local_modes_apply(std::span<const char> fixed) const {
  const auto n = static_cast<size_t>(vertices());
  const auto nf = static_cast<size_t>(frames_);
  if (fixed.size() != n * nf) return false;
  const Segments s = find_segments(fixed, n, nf);
  std::vector<char> base;
  std::vector<int> cut;
  for (const auto& [first, count] : s.segments) {
    // Without a key frame the lowest temporal mode has no shift: its spatial system is the
    // Laplacian alone, whose far-reaching response the local solves cannot stand for.
    if (first == 0 && first + count == nf) return false;
    if (count > kMostModeFrames) return false;
    common_fixed_set(fixed, n, first, count, base, cut);
    if (cut.size() > n / 4) return false;
  }
  return true;
}

const SpaceTimeSolver::TemporalBasis& SpaceTimeSolver::temporal_basis(int first, int count) const {
  // The segment's temporal matrix depends only on its length and on whether it touches
  // the first or last frame (those have one temporal neighbour, a free "Neumann" end;
  // a key frame beyond the end makes it a "Dirichlet" end): temporal_eigenbasis. The tests
  // solve all four kinds of segment against CG.
  const bool left_open = first == 0, right_open = first + count == frames_;
  const int ends = (left_open ? 1 : 0) + (right_open ? 2 : 0);
  std::lock_guard lock(bases_mutex_);
  auto& slot = bases_[{count, ends}];
  if (!slot) {
    auto basis = std::make_shared<TemporalBasis>();
    temporal_eigenbasis(count, left_open, right_open, count, basis->q, basis->lambda);
    slot = std::move(basis);
  }
  return *slot;
}

SolveReport SpaceTimeSolver::solve(std::span<const char> fixed, std::span<const cplx> values,
                                   std::span<cplx> z, const SpaceTimeOptions& options) const {
  const auto n = static_cast<size_t>(vertices());
  const auto nf = static_cast<size_t>(frames_);
  const size_t total = n * nf;
  TVF_CHECK(fixed.size() == total && values.size() == total && z.size() == total,
            "space-time sizes {} {} {} for {} entries", fixed.size(), values.size(), z.size(), total);
  // Under mpirun: the distributed back end (solve/distributed.h).
  if (options.distributed && distributed_active() && options.method != SpaceTimeMethod::bicgstab_jacobi)
    return petsc_spacetime_solve(laplacian_, frames_, b_, fixed, values, z, options);
  const bool par = options.parallel;
  const SpaceTime a{*op_, fixed, n, nf, b_, par};
  std::lock_guard lock(work_mutex_);
  if (!work_) work_ = std::make_shared<Workspace>();
  Workspace& w = *work_;
  const bool same_fixed = w.last_kept && std::equal(fixed.begin(), fixed.end(), w.fixed.begin(), w.fixed.end());
  // Or a fixed set that differs from the last one at a few entries, with the same whole
  // fixed frames (an element that stays put moved, came or went: the designer's click),
  // after a solve that left its modes: the modes are the same (the segments are), so the
  // right-hand side is updated as for changed values and a temporal-mode solve starts from
  // the last one's modes and residuals, patched where the fixed set changed.
  w.toggled.clear();
  bool moved = false;
  if (!same_fixed && w.last_kept && w.modes_kept && !w.kept_moving && w.fixed.size() == total) {
    const size_t most = total / 16;
    for (size_t k = 0; k < total && w.toggled.size() <= most; ++k)
      if (fixed[k] != w.fixed[k]) w.toggled.push_back(k);
    moved = w.toggled.size() <= most && find_segments(fixed, n, nf).key == find_segments(w.fixed, n, nf).key;
    if (!moved) w.toggled.clear();
  }
  w.same_fixed = (same_fixed || moved) && w.modes_kept;
  w.moved = moved;
  if (!same_fixed) {
    w.modes_fit = w.local_fit = -1;
    w.longest = 0;
    w.local.reset();
  }
  if (!w.same_fixed) w.modes_kept = false;
  Vec& rhs = sized(w.rhs, total);
  // The right-hand side: updated where the fixed part changed when the fixed set is the
  // last solve's or close to it and little changed, else computed whole.
  w.rhs_incremental = false;
  if (same_fixed || moved) {
    std::vector<size_t> sources = w.toggled;
    for (size_t m = 0; m < w.fixed_at.size(); ++m) {
      const size_t k = w.fixed_at[m];
      if (fixed[k] && values[k] != w.fixed_value[m]) sources.push_back(k);
    }
    if (sources.size() <= total / (moved ? 16 : 64)) {
      sized(w.mark, total);  // zero from its last use (or new)
      a.update_right_hand_side(values, sources, rhs, w.mark, w.rhs_change);
      if (moved) {
        w.fixed.assign(fixed.begin(), fixed.end());
        w.fixed_at.clear();
        for (size_t k = 0; k < total; ++k)
          if (fixed[k]) w.fixed_at.push_back(k);
        w.fixed_value.resize(w.fixed_at.size());
      }
      for (size_t m = 0; m < w.fixed_at.size(); ++m) w.fixed_value[m] = values[w.fixed_at[m]];
      w.rhs_incremental = true;
    } else if (moved) {
      w.moved = false;
      w.same_fixed = false;
      w.modes_kept = false;
      w.toggled.clear();
    }
  }
  if (!w.rhs_incremental) {
    w.last_kept = false;
    a.right_hand_side(values, rhs);
    if (!same_fixed) {
      w.fixed.assign(fixed.begin(), fixed.end());
      w.fixed_at.clear();
      for (size_t k = 0; k < total; ++k)
        if (fixed[k]) w.fixed_at.push_back(k);
    }
    w.fixed_value.resize(w.fixed_at.size());
    for (size_t m = 0; m < w.fixed_at.size(); ++m) w.fixed_value[m] = values[w.fixed_at[m]];
    w.last_kept = true;
  }
  // ‖rhs‖ by fixed chunks (as sum()), each chunk's part kept: where the right-hand side
  // changed at a few entries only their chunks are summed again (the same bits).
  const size_t nchunks = (total + kSumChunk - 1) / kSumChunk;
  auto chunk_norm = [&](size_t c) {
    double part = 0;
    for (size_t k = c * kSumChunk; k < std::min(total, (c + 1) * kSumChunk); ++k) part += std::norm(rhs[k]);
    return part;
  };
  if (w.rhs_incremental && w.rhs_parts.size() == nchunks) {
    std::vector<size_t> dirty;
    for (const auto& change : w.rhs_change) dirty.push_back(change.first / kSumChunk);
    std::sort(dirty.begin(), dirty.end());
    dirty.erase(std::unique(dirty.begin(), dirty.end()), dirty.end());
    for (const size_t c : dirty) w.rhs_parts[c] = chunk_norm(c);
  } else {
    w.rhs_parts.resize(nchunks);
    auto run = [&](size_t c) { w.rhs_parts[c] = chunk_norm(c); };
    if (par && nchunks > 1)
      tbb::parallel_for(size_t{0}, nchunks, run);
    else
      for (size_t c = 0; c < nchunks; ++c) run(c);
  }
  double bnorm2 = 0;
  if (nchunks == 1)
    bnorm2 = w.rhs_parts[0];
  else
    for (const double part : w.rhs_parts) bnorm2 += part;
  const double bnorm = std::sqrt(bnorm2);

  // The unknown: the free part of z (its first guess), fixed entries zero; noting
  // whether it is the last solve's result (whose modes are kept; where the fixed set
  // changed, the last result with the new fixed set's guess).
  Vec& x = sized(w.x, total);
  for (const size_t k : w.toggled) x[k] = fixed[k] ? cplx(0, 0) : z[k];
  std::atomic<bool> changed{false};
  blocks(total, par, [&](size_t s, size_t e) {
    if (changed) return;
    for (size_t k = s; k < e; ++k)
      if ((fixed[k] ? cplx(0, 0) : z[k]) != x[k]) {
        changed = true;
        return;
      }
  });
  if (changed)
    blocks(total, par, [&](size_t s, size_t e) {
      for (size_t k = s; k < e; ++k) x[k] = fixed[k] ? cplx(0, 0) : z[k];
    });
  w.same_guess = w.same_fixed && !changed;

  SolveReport report;
  if (bnorm == 0) {
    std::fill(x.begin(), x.end(), cplx(0, 0));
    // Every entry fixed (a guide field between key frames holds all the free vertices), or
    // free entries that no fixed one pulls away from zero.
    const bool all_fixed = std::all_of(fixed.begin(), fixed.end(), [](char f) { return f != 0; });
    report.method = all_fixed ? "nothing to solve (every entry is fixed)"
                              : "nothing to solve (no fixed entry asks for a non-zero field)";
    report.success = true;
  } else {
    // Which methods apply depends on the fixed set alone: known from the last solve when
    // it is the same.
    auto modes_fit = [&]() {
      if (w.modes_fit < 0) w.modes_fit = modes_apply(fixed) ? 1 : 0;
      return w.modes_fit == 1;
    };
    auto local_fit = [&]() {
      if (w.local_fit < 0) w.local_fit = local_modes_apply(fixed) ? 1 : 0;
      return w.local_fit == 1;
    };
    const bool modes = options.method == SpaceTimeMethod::modes ||
                       (options.method == SpaceTimeMethod::automatic && modes_fit() &&
                        (w.longest ? w.longest : (w.longest = longest_segment(fixed))) <= kMostModeFrames);
    const bool local = !modes && (options.method == SpaceTimeMethod::modes_local ||
                                  (options.method == SpaceTimeMethod::automatic && local_fit()));
    if (options.method == SpaceTimeMethod::modes)
      TVF_CHECK(modes_fit(), "the temporal-mode method needs the same fixed vertices at every "
                                    "frame between two key frames");
    if (options.method == SpaceTimeMethod::modes_local)
      TVF_CHECK(local_fit(), "the temporal modes with local solves need a key frame, at most a "
                                          "quarter of the vertices cut by moving constraints and segments of at "
                                          "most {} frames",
                kMostModeFrames);
    if (!modes && !local) w.modes_kept = false;
    if (options.method == SpaceTimeMethod::bicgstab_jacobi)
      report = solve_bicgstab(fixed, rhs, x, bnorm, options);
    else if (modes || local)
      report = solve_modes(fixed, rhs, x, bnorm, options, local);
    else
      report = solve_cg(fixed, rhs, x, bnorm, options);
  }
  if (bnorm == 0) w.modes_kept = false;
  blocks(total, par, [&](size_t s, size_t e) {
    for (size_t k = s; k < e; ++k) z[k] = fixed[k] ? values[k] : x[k];
  });
  return report;
}

SolveReport SpaceTimeSolver::solve_modes(std::span<const char> fixed, std::span<const cplx> rhs,
                                         std::span<cplx> x, double bnorm, const SpaceTimeOptions& options,
                                         bool local) const {
  const auto n = static_cast<size_t>(vertices());
  const auto nf = static_cast<size_t>(frames_);
  const bool par = options.parallel;
  const Segments segs = find_segments(fixed, n, nf);
  const size_t nseg = segs.segments.size();
  Workspace& w = *work_;
  // (Not where the fixed set changed and moving constraints cut the segments: their common
  // fixed sets and local solves are built again, the modes transformed again.)
  const bool kept = w.modes_kept && w.r_hat.size() == nseg && !(w.moved && local);
  // The kept residuals of the modes are theirs when the first guess is the last result
  // and every change of the right-hand side is known.
  const bool residuals_kept = kept && w.same_guess && w.rhs_incremental;
  // Then the modes' solves work on the change alone (iterate_change: what the last solve
  // left stays out of their Krylov spaces), and the result goes back into frames as the
  // last one plus the change, on the rows the change reaches (add_change_to_frames).
  const bool change = residuals_kept;
  if (change) {
    w.d_hat.resize(nseg);
    w.e_hat.resize(nseg);
  }
  w.modes_kept = false;  // until this solve has left its own modes
  w.r_hat.resize(nseg);
  w.x_hat.resize(nseg);
  w.res_hat.resize(nseg);
  // Each segment's modes take its common fixed set: the first frame's (the same at every
  // frame where the modes apply), or with local solves the vertices fixed at every frame
  // of it, the constraints that move being imposed by the local solves.
  // The local solves' set-up: the last solve's where the fixed set is the same (solve()
  // drops it when it changes), else built here. What its local solves left out of the
  // modes stays out where this solve solves for the change alone with it; otherwise it goes
  // into the modes now where they are kept, and is dropped where they are transformed again.
  const int rings = std::max(options.moving_rings, 0);
  std::unique_ptr<Workspace::LocalSetup>& setup = w.local;
  const bool reuse = local && setup && setup->rings == rings && setup->segments == segs.segments;
  if (setup && setup->pending && !(change && reuse)) {
    if (kept) {
      std::vector<const Eigen::MatrixXd*> q;
      for (const auto& [first, count] : setup->segments)
        q.push_back(&temporal_basis(static_cast<int>(first), static_cast<int>(count)).q);
      setup->flush(w.x_hat, w.r_hat, n, q);
    } else {
      setup->drop();
    }
  }
  if (local && !reuse) {
    setup = std::make_unique<Workspace::LocalSetup>();
    setup->rings = rings;
    setup->segments = segs.segments;
    setup->moving.resize(nseg);
    setup->x.resize(nseg);
    setup->lambda.resize(nseg);
    for (size_t si = 0; si < nseg; ++si) {
      const auto [first, count] = segs.segments[si];
      MovingSegment& m = setup->moving[si];
      common_fixed_set(fixed, n, first, count, m.base, m.cut);
      if (!m.cut.empty()) build_moving(*op_, fixed, n, nf, first, count, rings, b_, m);
      setup->x[si].assign(m.omega.size() * count, cplx(0, 0));
      setup->lambda[si].assign(m.cut.size() * count, cplx(0, 0));
    }
    for (size_t si = 0; si < nseg; ++si)
      setup->solves.push_back({*op_, setup->moving[si], nf, segs.segments[si].first, segs.segments[si].second, b_, {}, {},
                               {}, {}, {}, false, {}});
  }
  static const std::vector<MovingSegment> no_moving;
  const std::vector<MovingSegment>& moving = local ? setup->moving : no_moving;
  std::vector<const char*> seg_fixed(nseg);
  bool has_moving = false;
  size_t local_vertices = 0;
  for (size_t si = 0; si < nseg; ++si) {
    seg_fixed[si] = fixed.data() + segs.segments[si].first * n;
    if (!local) continue;
    seg_fixed[si] = moving[si].base.data();
    if (moving[si].cut.empty()) continue;
    has_moving = true;
    local_vertices += moving[si].omega.size();
  }

  // Into the modes: per segment r_hat = rhs·Q, x_hat = x·Q (complex |V| × count blocks seen
  // as real 2|V| × count ones, re and im interleaved), or updates of the kept ones.
  struct Mode {
    size_t segment, k;
    double shift;
    double rr = 0;       // ‖residual‖²
    double base_rr = 0;       // solving for the change: ‖residual − change‖², what the last solve left,
    std::vector<int> active;  // and the rows the change may have reached (iterate_change),
    size_t solved = 0;        // of which the first `solved` the modes' solves have (the change's
                              // modes, d, are zero on the rest: the last local solve's leak)
    double outside = 0;       // ‖residual‖² on the other rows
    int iterations = 0;
  };
  std::vector<Mode> modes;
  std::vector<const TemporalBasis*> bases(nseg);
  std::vector<size_t> mode_offset(nseg);
  std::vector<std::vector<int>> changed_rows(nseg);  // solving for the change: the rows it starts on
  auto column = [&](std::vector<std::vector<double>>& m, const Mode& mode) {
    return reinterpret_cast<cplx*>(m[mode.segment].data() + 2 * n * mode.k);
  };
  for (size_t si = 0; si < nseg; ++si) {
    const auto [first, count] = segs.segments[si];
    const TemporalBasis& basis = temporal_basis(static_cast<int>(first), static_cast<int>(count));
    bases[si] = &basis;
    const auto rows = static_cast<Eigen::Index>(2 * n), cols = static_cast<Eigen::Index>(count);
    auto* x_seg = reinterpret_cast<double*>(x.data() + first * n);
    Eigen::Map<Eigen::MatrixXd> r_hat(sized(w.r_hat[si], static_cast<size_t>(rows * cols)).data(), rows, cols);
    Eigen::Map<Eigen::MatrixXd> x_hat(sized(w.x_hat[si], static_cast<size_t>(rows * cols)).data(), rows, cols);
    Eigen::Map<Eigen::MatrixXd> res_hat(sized(w.res_hat[si], static_cast<size_t>(rows * cols)).data(), rows, cols);
    if (change) {
      for (auto* v : {&w.d_hat[si], &w.e_hat[si]}) {
        sized(*v, static_cast<size_t>(rows * cols));
        if (!w.change_zero) std::fill(v->begin(), v->end(), 0.0);
      }
    }
    if (kept && w.rhs_incremental) {
      // r_hat (and the kept residuals) += Qᵀ Δ on the rows whose right-hand side changed
      // in this segment: Δ per vertex over the segment's frames.
      std::map<size_t, std::pair<Eigen::VectorXd, Eigen::VectorXd>> delta;  // vertex → (re, im)
      for (const auto& [k, d] : w.rhs_change) {
        const size_t j = k / n, i = k % n;
        if (j < first || j >= first + count) continue;
        auto [it, fresh] = delta.try_emplace(i);
        if (fresh) it->second = {Eigen::VectorXd::Zero(cols), Eigen::VectorXd::Zero(cols)};
        it->second.first[static_cast<Eigen::Index>(j - first)] = d.real();
        it->second.second[static_cast<Eigen::Index>(j - first)] = d.imag();
      }
      for (const auto& [i, d] : delta) {
        const Eigen::RowVectorXd re = (basis.q.transpose() * d.first).transpose();
        const Eigen::RowVectorXd im = (basis.q.transpose() * d.second).transpose();
        const auto row = static_cast<Eigen::Index>(2 * i);
        r_hat.row(row) += re;
        r_hat.row(row + 1) += im;
        if (residuals_kept) {
          res_hat.row(row) += re;
          res_hat.row(row + 1) += im;
        }
        if (change) {
          Eigen::Map<Eigen::MatrixXd> e_hat(w.e_hat[si].data(), rows, cols);
          e_hat.row(row) += re;
          e_hat.row(row + 1) += im;
          changed_rows[si].push_back(static_cast<int>(i));
        }
      }
    } else {
      multiply_rows(reinterpret_cast<const double*>(rhs.data() + first * n), basis.q, false, r_hat.data(), rows);
    }
    if (!kept || !w.same_guess) multiply_rows(x_seg, basis.q, false, x_hat.data(), rows);
    mode_offset[si] = modes.size();
    for (size_t k = 0; k < count; ++k)
      modes.push_back({si, k, b_ * basis.lambda[static_cast<Eigen::Index>(k)], 0, 0, {}, 0, 0, 0});
  }
  auto each_mode = [&](const std::vector<size_t>& which, auto&& body) {
    if (par)
      tbb::parallel_for(size_t{0}, which.size(), [&](size_t m) { body(modes[which[m]]); }, tbb::simple_partitioner());
    else
      for (const size_t m : which) body(modes[m]);
  };
  // Where the fixed set changed (w.toggled) and the kept residuals go on: the result's modes
  // on the vertices whose fixed entries changed are transformed again from x (zero where
  // fixed now, the first guess where free now), and every mode's residual is computed
  // again on them and their neighbours (the only rows A_k x_hat changes on) with the new
  // fixed set; the difference joins the change (e), those rows the change's start.
  size_t moved_vertices = 0;
  if (residuals_kept && w.moved) {
    std::vector<char> on(n, 0);
    for (size_t si = 0; si < nseg; ++si) {
      const auto [first, count] = segs.segments[si];
      std::vector<int> vertices, rows;
      for (const size_t k : w.toggled) {
        const size_t j = k / n, i = k % n;
        if (j < first || j >= first + count || on[i]) continue;
        on[i] = 1;
        vertices.push_back(static_cast<int>(i));
      }
      if (vertices.empty()) continue;
      moved_vertices += vertices.size();
      const auto mrows = static_cast<Eigen::Index>(2 * n), cols = static_cast<Eigen::Index>(count);
      Eigen::Map<Eigen::MatrixXd> x_hat(w.x_hat[si].data(), mrows, cols);
      const Eigen::MatrixXd& q = bases[si]->q;
      for (const int i : vertices) {
        Eigen::VectorXd re(cols), im(cols);
        for (size_t jj = 0; jj < count; ++jj) {
          const cplx v = x[(first + jj) * n + static_cast<size_t>(i)];
          re[static_cast<Eigen::Index>(jj)] = v.real();
          im[static_cast<Eigen::Index>(jj)] = v.imag();
        }
        x_hat.row(2 * i) = (q.transpose() * re).transpose();
        x_hat.row(2 * i + 1) = (q.transpose() * im).transpose();
      }
      for (const int i : vertices) rows.push_back(i);
      for (const int i : vertices)
        for (int e = op_->row_start[static_cast<size_t>(i)]; e < op_->row_start[static_cast<size_t>(i) + 1]; ++e) {
          const int c = op_->column[static_cast<size_t>(e)];
          if (!on[static_cast<size_t>(c)]) on[static_cast<size_t>(c)] = 1, rows.push_back(c);
        }
      for (const int i : rows) on[static_cast<size_t>(i)] = 0;
      const char* sf = seg_fixed[si];
      for (size_t k = 0; k < count; ++k) {
        const Mode& mode = modes[mode_offset[si] + k];
        const cplx *rh = column(w.r_hat, mode), *xh = column(w.x_hat, mode);
        cplx *res = column(w.res_hat, mode), *e = column(w.e_hat, mode);
        for (const int r : rows) {
          const auto i = static_cast<size_t>(r);
          if (sf[i]) {
            res[i] = e[i] = 0;
            continue;
          }
          const cplx now = rh[i] - ((op_->diagonal[i] + mode.shift * op_->weight_sum[i]) * xh[i] + op_->off(r, xh));
          e[i] += now - res[i];
          res[i] = now;
        }
      }
      changed_rows[si].insert(changed_rows[si].end(), rows.begin(), rows.end());
    }
  }
  std::vector<std::vector<char>> start_on(change ? nseg : 0);
  if (change) {
    w.change_zero = false;  // until add_change_to_frames has cleared them
    // The rows the change starts on: where the right-hand side changed, and with moving
    // constraints omega and the ring around it (the local solves' leak goes there).
    for (size_t si = 0; si < nseg; ++si) {
      std::vector<char>& on = start_on[si];
      on.assign(n, 0);
      std::vector<int> start;
      auto add = [&](int i) {
        if (!on[static_cast<size_t>(i)] && !seg_fixed[si][i]) on[static_cast<size_t>(i)] = 1, start.push_back(i);
      };
      for (const int i : changed_rows[si]) add(i);
      for (size_t k = 0; k < segs.segments[si].second; ++k) modes[mode_offset[si] + k].active = start;
    }
  }
  std::vector<size_t> every(modes.size());
  for (size_t m = 0; m < modes.size(); ++m) every[m] = m;
  auto system = [&](const Mode& mode) {
    return ModeSystem{*op_, seg_fixed[mode.segment], mode.shift};
  };

  // Every mode's residual now: kept (updated above), or one sweep. Solving for the change
  // with the last solve's ‖residual‖² per mode kept (w.mode_rr) and no fixed row changed,
  // the residual changed on the change's first rows alone (active): their part of the
  // kept sum, what the last solve left there (res − e), gives what is outside them.
  const bool rr_kept = change && !w.moved && w.mode_rr.size() == modes.size();
  each_mode(every, [&](Mode& mode) {
    cplx* res = column(w.res_hat, mode);
    if (rr_kept) {
      const cplx* e = column(w.e_hat, mode);
      double base = 0, now = 0;
      for (const int i : mode.active) {
        base += std::norm(res[i] - e[i]);
        now += std::norm(res[i]);
      }
      mode.outside = std::max(w.mode_rr[static_cast<size_t>(&mode - modes.data())] - base, 0.0);
      mode.base_rr = mode.outside + base;
      mode.rr = mode.outside + now;
    } else if (residuals_kept) {
      double rr = 0;
      for (size_t i = 0; i < n; ++i) rr += std::norm(res[i]);
      mode.rr = rr;
      if (change) {  // summed apart (no difference of large sums: the change is far above the rest)
        const cplx* e = column(w.e_hat, mode);
        const char* on = start_on[mode.segment].data();
        double outside = 0, base = 0;
        for (size_t i = 0; i < n; ++i)
          if (!on[i]) outside += std::norm(res[i]);
        for (const int i : mode.active) base += std::norm(res[i] - e[i]);
        mode.outside = outside;
        mode.base_rr = outside + base;
      }
    } else {
      mode.rr = system(mode).residual(column(w.r_hat, mode), column(w.x_hat, mode), res);
    }
  });

  // Q is orthogonal, so the squared residuals of the modes add up to the whole one's: the
  // budget (tolerance · ‖b‖)² is theirs to share, with room for the transforms' rounding
  // where the residual is then measured (see kModeResidualTolerance). Modes already within
  // an equal share keep their residual and leave the rest to the others. The lowest modes
  // (shift under kSlowShift: the spatial Laplacian dominates, Jacobi-PCG converges slowly)
  // go last and share what the others left: a fast mode usually stops well below its
  // share, and every factor the slow ones are spared saves them several iterations.
  const double share = options.tolerance >= kModeResidualTolerance ? 0.95 : 0.5;
  const double budget = std::pow(share * options.tolerance * bnorm, 2);
  std::atomic<bool> failed{false};
  std::atomic<int> factorizations{0};
  tbb::enumerable_thread_specific<ModeScratch> scratch;
  // The slow modes' factorizations (options.direct_shift): kept ones where the fixed set
  // and shift are the same, the others refactored (made in converge, where needed).
  std::vector<detail::ModeFactor*> direct(modes.size(), nullptr);
  if (options.direct_shift > 0) {
    std::vector<size_t> wanted;
    for (size_t m = 0; m < modes.size(); ++m)
      if (modes[m].shift < options.direct_shift) wanted.push_back(m);
    std::vector<char> taken(w.factors.size(), 0);
    auto same = [&](const detail::ModeFactor& f, const Mode& mode) {
      return f.shift == mode.shift && std::equal(f.fixed.begin(), f.fixed.end(), seg_fixed[mode.segment]);
    };
    std::vector<size_t> unmatched;
    for (const size_t m : wanted) {
      size_t k = 0;
      while (k < w.factors.size() && (taken[k] || !w.factors[k]->factored || !same(*w.factors[k], modes[m]))) ++k;
      if (k < w.factors.size()) {
        taken[k] = 1;
        direct[m] = w.factors[k].get();
      } else {
        unmatched.push_back(m);
      }
    }
    // The others take new factors while the solver keeps fewer than twice as many as this
    // solve wants (the last fixed set's stay for an undo), else the least recently used
    // one that this solve does not use (its analysis is L's pattern's: refactored only).
    const size_t most = 2 * wanted.size();
    for (const size_t m : unmatched) {
      size_t k = w.factors.size();  // none found: a new one
      if (w.factors.size() >= most)
        for (size_t j = w.factors.size(); j-- > 0;)
          if (!taken[j]) {
            k = j;
            break;
          }
      if (k == w.factors.size()) {
        w.factors.push_back(std::make_unique<detail::ModeFactor>());
        taken.push_back(0);
      }
      taken[k] = 1;
      detail::ModeFactor& f = *w.factors[k];
      f.fixed.assign(seg_fixed[modes[m].segment], seg_fixed[modes[m].segment] + n);
      f.shift = modes[m].shift;
      f.factored = false;
      direct[m] = &f;
    }
    // Most recently used first; at most `most` kept.
    std::vector<std::unique_ptr<detail::ModeFactor>> order;
    for (size_t j = 0; j < w.factors.size(); ++j)
      if (taken[j]) order.push_back(std::move(w.factors[j]));
    for (size_t j = 0; j < w.factors.size() && order.size() < most; ++j)
      if (w.factors[j]) order.push_back(std::move(w.factors[j]));
    if (!wanted.empty()) w.factors = std::move(order);
  }
  auto converge = [&](Mode& mode, double tau2) {
    cplx *y = column(w.x_hat, mode), *res = column(w.res_hat, mode);
    // Solving for the change: the mode takes its whole residual (e = res on every free row)
    // when what the last solve left is too close to its target, or when it is a slow mode
    // (its response reaches every row anyway).
    auto fold = [&]() {
      std::copy(res, res + n, column(w.e_hat, mode));
      mode.base_rr = 0;
      mode.outside = 0;
      mode.active.clear();
      for (size_t i = 0; i < n; ++i)
        if (!seg_fixed[mode.segment][i]) mode.active.push_back(static_cast<int>(i));
    };
    detail::ModeFactor* f = direct[static_cast<size_t>(&mode - modes.data())];
    const bool fresh = f && !f->factored;
    int it = -2;
    if (f) {
      // A slow mode with its factorization: the whole residual; what it adds to y is the
      // change (d), and e stays equal to res on the rows it has (all).
      cplx* d = change ? column(w.d_hat, mode) : nullptr;
      if (change) {
        fold();
        for (size_t i = 0; i < n; ++i) d[i] -= y[i];
      }
      it = system(mode).iterate_direct(y, res, mode.rr, tau2, options.max_iterations, *f, laplacian_, scratch.local());
      if (change) {
        for (size_t i = 0; i < n; ++i) d[i] += y[i];
        std::copy(res, res + n, column(w.e_hat, mode));
      }
    }
    if (it == -2 && change) {
      if (mode.base_rr > kChangeFold * tau2 || (mode.base_rr > 0 && mode.shift < kSlowShift)) fold();
      it = system(mode).iterate_change(y, column(w.d_hat, mode), res, column(w.e_hat, mode), mode.rr, mode.outside,
                                       tau2, options.max_iterations, mode.active, scratch.local());
    } else if (it == -2) {
      it = system(mode).iterate(y, res, mode.rr, tau2, options.max_iterations, scratch.local());
    }
    if (fresh && f->factored) ++factorizations;
    if (it < 0) failed = true;
    mode.iterations += std::max(it, 0);
    mode.solved = mode.active.size();
  };
  // One round of the modes' solves: the squared residuals add up (Q is orthogonal), so a
  // budget of squared residual is theirs to share. Modes already within an equal share keep
  // their residual and leave the rest to the others; the lowest modes (shift under
  // kSlowShift: the spatial Laplacian dominates, Jacobi-PCG converges slowly) go last and
  // share what the others left: a fast mode usually stops well below its share, and every
  // factor the slow ones are spared saves them several iterations.
  auto solve_round = [&](double round_budget) {
    std::vector<double> rr0;
    for (const Mode& m : modes) rr0.push_back(m.rr);
    const double level = share_level(rr0, round_budget);
    std::vector<size_t> fast, slow;
    for (size_t m = 0; m < modes.size(); ++m)
      if (modes[m].rr > level) (modes[m].shift < kSlowShift ? slow : fast).push_back(m);
    each_mode(fast, [&](Mode& mode) { converge(mode, level); });
    if (slow.empty()) return;
    double left = round_budget;
    std::vector<double> slow_rr;
    for (size_t m = 0; m < modes.size(); ++m) {
      if (std::find(slow.begin(), slow.end(), m) == slow.end())
        left -= modes[m].rr;
      else
        slow_rr.push_back(modes[m].rr);
    }
    // left ≥ |slow| · level: the fast modes ended at or below it.
    const double slow_level = share_level(slow_rr, std::max(left, 0.0));
    each_mode(slow, [&](Mode& mode) { converge(mode, slow_level); });
  };

  // With moving constraints (modes_local): rounds of the modes' solves (to a fraction of
  // the residual the last round left) and local solves near the constraints. A local
  // solve sets the modes' solution to zero at the constraint entries (x is the free part)
  // by a correction u on omega that is exact there and A-harmonic at omega's other entries;
  // the modes' right-hand side takes A u at the constraint entries (the constraints'
  // multipliers: those rows are not equations of the problem), and their residual −A u at
  // the free entries it reaches (omega's, the local solve's own residual, and the ring
  // around omega: what leaks out). The next round solves that leak away. The residual of
  // the problem is then the modes' less their constraint rows', whose frames only the cut
  // vertices' rows need.
  int rounds = 0;
  long local_iterations = 0;
  bool stalled = false;
  double theta = 0;  // the problem's residual after the last local solve
  std::vector<cplx> cut_values, u, y_line, delta;
  // The local solves (their vectors kept between rounds and solves) and what earlier
  // solves' local solves left out of the modes (pending: none unless this one solves for
  // the change alone).
  std::vector<LocalSolve>* local_solves = local ? &setup->solves : nullptr;
  const bool pending = local && setup->pending;
  std::vector<double> rr_delta;
  // What the local solves add to x on omega's rows and to the multipliers on the cut rows,
  // kept in frames (omega × count, cut × count per segment) and transformed into the modes
  // once after the rounds: the modes' solves need neither (they work on the residual), and
  // the rounds read x at the cut rows only (the modes' rows plus these).
  std::vector<std::vector<cplx>> x_local(nseg), lambda_local(nseg);
  for (size_t si = 0; si < moving.size(); ++si) {
    x_local[si].assign(moving[si].omega.size() * segs.segments[si].second, cplx(0, 0));
    lambda_local[si].assign(moving[si].cut.size() * segs.segments[si].second, cplx(0, 0));
  }
  double local_floor2 = 0;  // the local solves stop below this squared residual (set below)
  std::vector<int> stamp(change && has_moving ? n : 0, 0);
  std::vector<size_t> free_rows(nseg, 0);  // per segment: the modes' free rows
  if (change && has_moving)
    for (size_t si = 0; si < nseg; ++si)
      free_rows[si] = static_cast<size_t>(std::count(seg_fixed[si], seg_fixed[si] + n, char{0}));
  int stamp_id = 0;
  auto local_round = [&]() {
    for (size_t si = 0; si < nseg; ++si) {
      if (moving[si].cut.empty()) continue;
      const MovingSegment& m = moving[si];
      const auto [first, count] = segs.segments[si];
      const Eigen::MatrixXd& q = bases[si]->q;
      std::vector<cplx>& xl = x_local[si];
      cut_rows_to_frames(w.x_hat[si], n, m, q, cut_values, par);
      u.assign(m.omega.size() * count, cplx(0, 0));
      const cplx* px = pending ? setup->x[si].data() : nullptr;
      for (size_t r = 0; r < m.cut.size(); ++r) {
        const auto li = static_cast<size_t>(m.cut_local[r]);
        for (size_t jj = 0; jj < count; ++jj) {
          const size_t e = li * count + jj;
          if (m.moving[e]) u[e] = -(cut_values[r * count + jj] + xl[e] + (px ? px[e] : cplx(0, 0)));
        }
      }
      LocalSolve& solve = (*local_solves)[si];
      solve.parallel = par;
      local_iterations += solve.solve(u, kMovingLocalTolerance, local_floor2, kMovingLocalIterations);
      for (size_t k = 0; k < u.size(); ++k) xl[k] += u[k];
      // The multipliers take (A u) at the constraint entries, on the cut vertices' lines.
      std::vector<cplx>& ll = lambda_local[si];
      y_line.resize(count);
      for (size_t r = 0; r < m.cut.size(); ++r) {
        const auto li = static_cast<size_t>(m.cut_local[r]);
        solve.product(u.data(), li, y_line.data());
        for (size_t jj = 0; jj < count; ++jj)
          if (m.moving[li * count + jj]) ll[r * count + jj] += y_line[jj];
      }
      // The residual's change, −(A u), into the modes: on omega's free entries the local
      // CG's own residual (A u = 0 there is what it solved), on the ring around omega what
      // leaks out.
      const size_t no = u.size();
      delta.assign(no + m.outer.size() * count, cplx(0, 0));
      std::copy(solve.r.begin(), solve.r.end(), delta.begin());
      for (size_t oi = 0; oi < m.outer.size(); ++oi) {
        double* d = reinterpret_cast<double*>(delta.data() + no + oi * count);
        for (int e = m.outer_start[oi]; e < m.outer_start[oi + 1]; ++e) {
          const cplx v = m.outer_value[static_cast<size_t>(e)];
          const double vr = v.real(), vi = v.imag();
          const double* uc =
              reinterpret_cast<const double*>(u.data() + static_cast<size_t>(m.outer_column[static_cast<size_t>(e)]) * count);
          for (size_t jj = 0; jj < count; ++jj) {
            d[2 * jj] -= vr * uc[2 * jj] - vi * uc[2 * jj + 1];
            d[2 * jj + 1] -= vr * uc[2 * jj + 1] + vi * uc[2 * jj];
          }
        }
      }
      if (change) {
        // Solving for the change: the leak's rows join every mode's active rows first (the
        // rows outside them must keep what the last solve left).
        std::vector<int> leaking;
        for (size_t r = 0; r < m.leak_rows.size(); ++r)
          if (std::any_of(delta.begin() + static_cast<std::ptrdiff_t>(r * count),
                          delta.begin() + static_cast<std::ptrdiff_t>((r + 1) * count),
                          [](cplx v) { return v != cplx(0, 0); }))
            leaking.push_back(m.leak_rows[r]);
        for (size_t k = 0; k < count; ++k) {
          Mode& mode = modes[mode_offset[si] + k];
          if (mode.active.size() == free_rows[si]) continue;  // every free row already (folded)
          ++stamp_id;
          for (const int i : mode.active) stamp[static_cast<size_t>(i)] = stamp_id;
          const cplx* res = column(w.res_hat, mode);
          for (const int i : leaking)
            if (stamp[static_cast<size_t>(i)] != stamp_id) {
              mode.active.push_back(i);
              mode.outside -= std::norm(res[i]);
            }
        }
      }
      rr_delta.assign(count, 0.0);
      add_frames_to_rows(w.res_hat[si], n, m.leak_rows, q, delta, rr_delta.data(), change ? &w.e_hat[si] : nullptr, par);
      for (size_t k = 0; k < count; ++k) {
        Mode& mode = modes[mode_offset[si] + k];
        mode.rr = std::max(mode.rr + rr_delta[k], 0.0);
      }
    }
    double rr = 0;
    for (const Mode& mode : modes) rr += mode.rr;
    for (size_t si = 0; si < nseg; ++si) {
      if (moving[si].cut.empty()) continue;
      const MovingSegment& m = moving[si];
      const size_t count = segs.segments[si].second;
      cut_rows_to_frames(w.res_hat[si], n, m, bases[si]->q, cut_values, par);
      for (size_t r = 0; r < m.cut.size(); ++r) {
        const auto li = static_cast<size_t>(m.cut_local[r]);
        for (size_t jj = 0; jj < count; ++jj)
          if (m.moving[li * count + jj]) rr -= std::norm(cut_values[r * count + jj]);
      }
    }
    return std::sqrt(std::max(rr, 0.0));
  };
  if (!has_moving) {
    solve_round(budget);
  } else {
    // The rounds stop at kMovingShare of the tolerance, also where the residual is then
    // measured (tolerances below kModeResidualTolerance): theta is the modes' exact sum less
    // the constraint rows, up to the transforms' rounding (~1e-14 relative), so the measure
    // agrees; the modes' share of 0.5 for that case often cost one more round.
    const double moving_budget = std::max(budget, std::pow(kMovingShare * options.tolerance * bnorm, 2));
    // A local solve's own residual is part of the next theta: below this it need not go.
    local_floor2 = moving_budget * kLocalFloor * kLocalFloor;
    for (const Mode& mode : modes) theta += mode.rr;
    theta = std::sqrt(theta);
    int slow_rounds = 0;
    for (;;) {
      // Solving for the change (a warm re-solve), the first round's modes go to
      // kChangeModesShare of the target at once: what the change moves at the constraint
      // entries is far below it, so the local solve's leak usually leaves the whole within
      // the target and no second round is needed.
      const double round_budget = change && rounds == 0 ? moving_budget * kChangeModesShare * kChangeModesShare
                                                        : std::max(moving_budget, std::pow(kRoundReduction * theta, 2));
      solve_round(round_budget);
      ++rounds;
      const double now = local_round();
      slow_rounds = now > kRoundStall * theta ? slow_rounds + 1 : 0;
      theta = now;
      if (theta * theta <= moving_budget) break;
      if (failed || rounds >= options.most_rounds || slow_rounds >= 2) {
        stalled = true;
        break;
      }
    }
  }

  // What the local solves added to x and to the multipliers, into the modes; or, solving
  // for the change alone, to what is pending (LocalSetup).
  for (size_t si = 0; si < moving.size(); ++si) {
    if (moving[si].cut.empty()) continue;
    if (change) {
      for (size_t k = 0; k < x_local[si].size(); ++k) setup->x[si][k] += x_local[si][k];
      for (size_t k = 0; k < lambda_local[si].size(); ++k) setup->lambda[si][k] += lambda_local[si][k];
      setup->pending = true;
      continue;
    }
    add_frames_to_rows(w.x_hat[si], n, moving[si].omega, bases[si]->q, x_local[si], nullptr, nullptr, par);
    add_frames_to_rows(w.r_hat[si], n, moving[si].cut, bases[si]->q, lambda_local[si], nullptr, nullptr, par);
  }

  // Back from the modes: the whole transform, or the last result plus the change (what
  // the modes' solves added, and the local solves' part, kept in frames).
  size_t reached = 0, mode_rows = 0;
  for (size_t si = 0; si < nseg; ++si) {
    const auto [first, count] = segs.segments[si];
    auto* x_seg = reinterpret_cast<double*>(x.data() + first * n);
    if (!change) {
      multiply_rows(w.x_hat[si].data(), bases[si]->q, true, x_seg, static_cast<Eigen::Index>(2 * n));
      continue;
    }
    std::vector<std::span<const int>> reach_of(count);
    std::vector<const std::vector<int>*> clear_of(count);
    for (size_t k = 0; k < count; ++k) {
      const Mode& mode = modes[mode_offset[si] + k];
      reach_of[k] = std::span<const int>(mode.active.data(), mode.solved);
      clear_of[k] = &mode.active;
    }
    reached += add_change_to_frames(w.d_hat[si], w.e_hat[si], n, bases[si]->q, reach_of, clear_of, x_seg, par);
    mode_rows += n * count;
    if (local && !moving[si].cut.empty()) {
      const MovingSegment& m = moving[si];
      for (size_t li = 0; li < m.omega.size(); ++li)
        for (size_t jj = 0; jj < count; ++jj)
          x[(first + jj) * n + static_cast<size_t>(m.omega[li])] += x_local[si][li * count + jj];
    }
  }
  if (change) w.change_zero = true;
  // The constraint entries: zero to rounding, exactly zero here (x is the free part); in a
  // segment they are on the cut vertices' rows only.
  if (has_moving && change) {
    for (size_t si = 0; si < nseg; ++si) {
      const auto [first, count] = segs.segments[si];
      if (local)
        for (const int i : moving[si].cut)
          for (size_t j = first; j < first + count; ++j)
            if (fixed[j * n + static_cast<size_t>(i)]) x[j * n + static_cast<size_t>(i)] = 0;
    }
  } else if (has_moving) {
    blocks(n * nf, par, [&](size_t s0, size_t e0) {
      for (size_t k = s0; k < e0; ++k)
        if (fixed[k]) x[k] = 0;
    });
  }

  int most = 0;
  long all = 0;
  double modes_rr = 0;
  w.mode_rr.clear();
  for (const Mode& m : modes) {
    most = std::max(most, m.iterations);
    all += m.iterations;
    modes_rr += m.rr;
    w.mode_rr.push_back(m.rr);  // res_hat's ‖column‖², for the next solve while the modes are kept
  }
  size_t direct_modes = 0;
  long direct_iterations = 0;
  for (size_t m = 0; m < modes.size(); ++m)
    if (direct[m] && direct[m]->factored) ++direct_modes, direct_iterations += modes[m].iterations;
  const std::string by_cholesky =
      direct_modes ? fmt::format(", {} slow modes preconditioned by their sparse Cholesky factorization ({} "
                                 "iterations; {} made now, the others kept)",
                                 direct_modes, direct_iterations, factorizations.load())
                   : std::string();
  SolveReport report;
  if (has_moving) {
    report.method = fmt::format("temporal eigenmodes (direct in time) with Jacobi-PCG per mode and local solves at "
                                "the moving constraints, {} modes, {} rounds, {} spatial iterations in all, "
                                "local solves on {} vertices ({} iterations in all{})",
                                modes.size(), rounds, all, local_vertices, local_iterations,
                                reuse ? ", their set-up kept from the last solve" : "") +
                    by_cholesky;
    report.iterations = rounds;
  } else {
    report.method = fmt::format("temporal eigenmodes (direct in time) with Jacobi-PCG per mode, {} modes, "
                                "{} spatial iterations in all",
                                modes.size(), all) +
                    by_cholesky;
    report.iterations = most;
  }
  if (change)
    report.method += fmt::format(", the change solved alone (it reached {:.1f} % of the modes' rows)",
                                 100.0 * static_cast<double>(reached) / static_cast<double>(std::max<size_t>(mode_rows, 1)));
  if (moved_vertices)
    report.method += fmt::format(", from the last result's modes with the fixed set changed at {} vertices",
                                 moved_vertices);
  // Q is orthogonal, so the modes' residuals add up to the whole one's, up to the
  // rounding of the transforms (~1e-14 relative). Where the tolerance leaves room for
  // that (a warm re-solve to 1e-6), that sum is the residual (with moving constraints,
  // less their rows'); tighter, it is measured as it is (and CG finishes the solve if
  // rounding left it short).
  double rnorm = 0;
  if (options.tolerance >= kModeResidualTolerance) {
    rnorm = has_moving ? theta : std::sqrt(modes_rr);
  } else {
    const SpaceTime a{*op_, fixed, n, nf, b_, par};
    rnorm = std::sqrt(a.residual_norm2(x, rhs));
  }
  report.residual = rnorm / bnorm;
  report.success = !failed && !stalled && report.residual <= options.tolerance;
  w.modes_kept = !failed && !stalled;  // x_hat holds the modes of x, r_hat those of rhs, res_hat their residuals
  w.kept_moving = has_moving;
  if (!report.success && options.method != SpaceTimeMethod::modes) {
    // Rounding (or a mode that would not converge): finish with CG from here.
    w.modes_kept = false;
    SolveReport polish = solve_cg(fixed, rhs, x, bnorm, options);
    polish.method = report.method + ", finished by " + polish.method;
    polish.iterations += report.iterations;
    return polish;
  }
  return report;
}

SolveReport SpaceTimeSolver::solve_bicgstab(std::span<const char> fixed, std::span<const cplx> rhs,
                                            std::span<cplx> x, double bnorm,
                                            const SpaceTimeOptions& options) const {
  // Assembled A with the fixed rows and columns replaced by identity (their right-hand
  // side is zero, so they stay zero and the free rows are A_FF's).
  const auto n = static_cast<size_t>(vertices());
  const auto nf = static_cast<size_t>(frames_);
  const Operator& op = *op_;
  using Index = int;  // Eigen's default sparse index: < 2³¹ non-zeros up to ~200M unknowns
  std::vector<Eigen::Triplet<cplx, Index>> t;
  t.reserve(n * nf * 9);
  for (size_t j = 0; j < nf; ++j)
    for (size_t i = 0; i < n; ++i) {
      const size_t k = j * n + i;
      const auto row = static_cast<Index>(k);
      if (fixed[k]) {
        t.emplace_back(row, row, 1.0);
        continue;
      }
      const double c = b_ * op.weight_sum[i];
      double diagonal = op.diagonal[i];
      for (int e = op.row_start[i]; e < op.row_start[i + 1]; ++e) {
        const size_t col = j * n + static_cast<size_t>(op.column[static_cast<size_t>(e)]);
        if (!fixed[col]) t.emplace_back(row, static_cast<Index>(col), op.value[static_cast<size_t>(e)]);
      }
      if (j > 0) {
        diagonal += c;
        if (!fixed[k - n]) t.emplace_back(row, static_cast<Index>(k - n), -c);
      }
      if (j + 1 < nf) {
        diagonal += c;
        if (!fixed[k + n]) t.emplace_back(row, static_cast<Index>(k + n), -c);
      }
      t.emplace_back(row, row, diagonal);
    }
  const auto size = static_cast<Index>(n * nf);
  Eigen::SparseMatrix<cplx, Eigen::RowMajor> a(size, size);
  a.setFromTriplets(t.begin(), t.end());
  t = {};
  Eigen::BiCGSTAB<decltype(a), Eigen::DiagonalPreconditioner<cplx>> solver;
  solver.setTolerance(options.tolerance);
  solver.setMaxIterations(options.max_iterations);
#pragma GCC diagnostic push
  // GCC 12 sees a null outer-index pointer in Eigen's Ref to a compressed matrix that
  // cannot occur (a is compressed by setFromTriplets).
#pragma GCC diagnostic ignored "-Wnull-dereference"
  solver.compute(a);
#pragma GCC diagnostic pop
  const Eigen::Map<const Eigen::VectorXcd> b(rhs.data(), size);
  Eigen::Map<Eigen::VectorXcd> xv(x.data(), size);
  xv = solver.solveWithGuess(b, Eigen::VectorXcd(xv));
  SolveReport report;
  report.method = "BiCGStab with Jacobi preconditioner on the assembled system (the paper's kind of method)";
  report.iterations = static_cast<int>(solver.iterations());
  // The residual as the other methods measure it (free entries; fixed ones stay zero).
  const SpaceTime st{*op_, fixed, n, nf, b_, options.parallel};
  std::vector<cplx> ax(x.size());
  st.apply(x, ax);
  double rr = 0;
  for (size_t k = 0; k < ax.size(); ++k) rr += std::norm(rhs[k] - ax[k]);
  report.residual = std::sqrt(rr) / bnorm;
  report.success = report.residual <= options.tolerance * (1 + 1e-6);
  return report;
}

SolveReport SpaceTimeSolver::solve_cg(std::span<const char> fixed, std::span<const cplx> rhs_span,
                                      std::span<cplx> x, double bnorm, const SpaceTimeOptions& options) const {
  const auto n = static_cast<size_t>(vertices());
  const auto nf = static_cast<size_t>(frames_);
  const size_t total = n * nf;
  const bool par = options.parallel;
  const SpaceTime a{*op_, fixed, n, nf, b_, par};
  const Operator& op = *op_;
  SolveReport report;
  report.method = "preconditioned CG (temporal line solves), matrix-free";

  // Preconditioner: every vertex's temporal line solved exactly (Thomas algorithm) on
  // the free entries; fixed entries split the line. The elimination depends on the fixed
  // set only, so it is done once here (lower coupling, 1/pivot, upper multiplier per
  // entry; all zero at fixed entries), and each application is two branch-free sweeps
  // over frames, vertex-contiguous inside a frame. Returns Re <r, M⁻¹ r>.
  std::vector<double>& lower = sized(work_->lower, total);
  std::vector<double>& pivot = sized(work_->pivot, total);
  std::vector<double>& upper = sized(work_->upper, total);
  blocks(n, par, [&](size_t i0, size_t i1) {
    for (size_t j = 0; j < nf; ++j) {
      const bool has_prev = j > 0, has_next = j + 1 < nf;
      for (size_t i = i0; i < i1; ++i) {
        const size_t k = j * n + i;
        if (fixed[k]) {
          lower[k] = pivot[k] = upper[k] = 0;
          continue;
        }
        const double c = b_ * op.weight_sum[i];
        const double diag = op.diagonal[i] + c * ((has_prev ? 1 : 0) + (has_next ? 1 : 0));
        const double lo = (has_prev && !fixed[k - n]) ? -c : 0.0;  // coupling to j−1
        const double up = (has_next && !fixed[k + n]) ? -c : 0.0;  // coupling to j+1
        const double denom = diag - lo * (has_prev ? upper[k - n] : 0.0);
        lower[k] = lo;
        pivot[k] = 1.0 / denom;
        upper[k] = up / denom;
      }
    }
  });
  auto precondition = [&](const Vec& r, Vec& out) {
    constexpr size_t kBlock = 256;
    const size_t nblocks = (n + kBlock - 1) / kBlock;
    auto body = [&](size_t blk) {
      const size_t i0 = blk * kBlock, i1 = std::min(n, i0 + kBlock);
      for (size_t i = i0; i < i1; ++i) out[i] = r[i] * pivot[i];
      for (size_t j = 1; j < nf; ++j)
        for (size_t i = i0; i < i1; ++i) {
          const size_t k = j * n + i;
          out[k] = (r[k] - lower[k] * out[k - n]) * pivot[k];
        }
      double partial = 0;
      for (size_t j = nf; j-- > 0;)
        for (size_t i = i0; i < i1; ++i) {
          const size_t k = j * n + i;
          if (j + 1 < nf) out[k] -= upper[k] * out[k + n];
          partial += r[k].real() * out[k].real() + r[k].imag() * out[k].imag();
        }
      return partial;
    };
    return ordered_sum(nblocks, par, body);
  };

  // The two-level preconditioner (options.coarse_modes > 0): the line solves leave the low
  // temporal modes × smooth spatial error nearly untouched (their shift b·λ is small), which
  // is what makes plain CG take ~70 iterations. A coarse correction over the lowest
  // kCoarseModes temporal modes of every segment (CoarseMode: each mode's spatial system,
  // solved by Jacobi-PCG to kCoarseTolerance) comes first, then the line solves act on what
  // it leaves: z = C r + M⁻¹ (r − A C r). The coarse solve is inexact, so the CG is the
  // flexible (Polak–Ribière) one.
  std::vector<CoarseMode> coarse;
  if (options.coarse_modes > 0) {
    const Segments segs = find_segments(fixed, n, nf);
    for (const auto& [first, count] : segs.segments) {
      const TemporalBasis& basis = temporal_basis(static_cast<int>(first), static_cast<int>(count));
      for (size_t k = 0; k < std::min(count, static_cast<size_t>(options.coarse_modes)); ++k) {
        CoarseMode m;
        m.first = first;
        m.count = count;
        m.q = basis.q.col(static_cast<Eigen::Index>(k));
        m.scale.resize(n);
        m.shift.resize(n);
        coarse.push_back(std::move(m));
      }
    }
    // √s_i and T_ii of every mode, vertex blocks in parallel.
    blocks(n, par, [&](size_t i0, size_t i1) {
      for (CoarseMode& m : coarse)
        for (size_t i = i0; i < i1; ++i) {
          const CoarseWeight w = coarse_weight(m.q, m.first, fixed, n, nf, i, b_ * op.weight_sum[i]);
          m.scale[i] = w.scale;
          m.shift[i] = w.shift;
        }
    });
  }
  // The local solve (options.local_rings ≥ 0, with the coarse correction): the coarse
  // space represents a vertex whose temporal line a moving constraint cuts poorly (each cut
  // line has its own low modes), so after the coarse correction the error is largest there.
  // The vertices whose line has both fixed entries outside the key frames and free
  // entries, grown by local_rings rings of neighbours, are solved together over all frames
  // (Dirichlet zero around them) by a few CG iterations with the line solves (which are
  // the global ones' rows: temporal lines do not couple vertices), and the residual
  // updated on them and their neighbours before the global line solves. Serial, its sums
  // in a fixed order.
  std::vector<int> local_vertex, local_of(coarse.empty() || options.local_rings < 0 ? 0 : n, -1);
  std::vector<int> touched;  // local_vertex and their neighbours: where A δ can be non-zero
  if (!local_of.empty()) {
    const Segments segs = find_segments(fixed, n, nf);
    std::vector<char> cut(n, 0), free_entry(n, 0), in(n, 0);
    for (size_t j = 0; j < nf; ++j) {  // frame by frame: the fixed set is frame-major
      const char* fj = fixed.data() + j * n;
      for (size_t i = 0; i < n; ++i) {
        if (!fj[i])
          free_entry[i] = 1;
        else if (!segs.key[j])
          cut[i] = 1;
      }
    }
    for (size_t i = 0; i < n; ++i) in[i] = cut[i] && free_entry[i];
    for (int ring = 0; ring < options.local_rings; ++ring) {
      std::vector<char> grown = in;
      for (size_t i = 0; i < n; ++i)
        if (in[i])
          for (int e = op.row_start[i]; e < op.row_start[i + 1]; ++e)
            grown[static_cast<size_t>(op.column[static_cast<size_t>(e)])] = 1;
      in = std::move(grown);
    }
    std::vector<char> near = in;
    for (size_t i = 0; i < n; ++i)
      if (in[i]) {
        local_of[i] = static_cast<int>(local_vertex.size());
        local_vertex.push_back(static_cast<int>(i));
        for (int e = op.row_start[i]; e < op.row_start[i + 1]; ++e)
          near[static_cast<size_t>(op.column[static_cast<size_t>(e)])] = 1;
      }
    for (size_t i = 0; i < n; ++i)
      if (near[i]) touched.push_back(static_cast<int>(i));
  }
  const size_t nl = local_vertex.size(), nq = nl * nf;
  // Local vectors are vertex-major (q = li·frames + j): a line is contiguous, and a
  // neighbour's entries over all frames too. The rows of L among the local vertices and of
  // their neighbours (touched) with local columns, and the line solves' factors, gathered
  // once.
  std::vector<int> local_start{0}, local_col, touched_start{0}, touched_col;
  std::vector<cplx> local_val, touched_val;
  std::vector<double> l_lower(nq), l_pivot(nq), l_upper(nq);
  std::vector<char> l_fixed(nq);
  auto gather_row = [&](size_t i, std::vector<int>& start, std::vector<int>& col, std::vector<cplx>& val) {
    for (int e = op.row_start[i]; e < op.row_start[i + 1]; ++e) {
      const int c = local_of[static_cast<size_t>(op.column[static_cast<size_t>(e)])];
      if (c >= 0) col.push_back(c), val.push_back(op.value[static_cast<size_t>(e)]);
    }
    start.push_back(static_cast<int>(col.size()));
  };
  for (size_t li = 0; li < nl; ++li) {
    const auto i = static_cast<size_t>(local_vertex[li]);
    gather_row(i, local_start, local_col, local_val);
    for (size_t j = 0; j < nf; ++j) {
      const size_t k = j * n + i, q = li * nf + j;
      l_lower[q] = lower[k], l_pivot[q] = pivot[k], l_upper[q] = upper[k], l_fixed[q] = fixed[k];
    }
  }
  for (const int i : touched) gather_row(static_cast<size_t>(i), touched_start, touched_col, touched_val);
  Vec local_r(nq), local_x(nq), local_p(nq), local_ap(nq), local_z(nq), row_acc(nf);
  long local_iterations = 0;
  // y = A x on the local vertices' lines, Dirichlet zero around them (fixed entries of x are
  // zero); fixed entries of y: 0.
  auto local_product = [&](const cplx* xl, size_t li, cplx* y) {
    const auto i = static_cast<size_t>(local_vertex[li]);
    const double c = b_ * op.weight_sum[i];
    const cplx* xi = xl + li * nf;
    for (size_t j = 0; j < nf; ++j) {
      cplx t = op.diagonal[i] * xi[j];
      if (j > 0) t += c * (xi[j] - xi[j - 1]);
      if (j + 1 < nf) t += c * (xi[j] - xi[j + 1]);
      y[j] = t;
    }
    for (int e = local_start[li]; e < local_start[li + 1]; ++e) {
      const cplx v = local_val[static_cast<size_t>(e)];
      const cplx* xc = xl + static_cast<size_t>(local_col[static_cast<size_t>(e)]) * nf;
      for (size_t j = 0; j < nf; ++j) y[j] += v * xc[j];
    }
  };
  // yl = A_ΩΩ xl; returns Re <x, y>.
  auto local_apply = [&](const Vec& xl, Vec& yl) {
    double dot = 0;
    for (size_t li = 0; li < nl; ++li) {
      cplx* y = yl.data() + li * nf;
      local_product(xl.data(), li, y);
      for (size_t j = 0; j < nf; ++j) {
        const size_t q = li * nf + j;
        if (l_fixed[q]) y[j] = 0;
        dot += xl[q].real() * y[j].real() + xl[q].imag() * y[j].imag();
      }
    }
    return dot;
  };
  // zl = the line solves of rl on the local vertices (the global ones' rows); returns Re <r, z>.
  auto local_lines = [&](const Vec& rl, Vec& zl) {
    double dot = 0;
    for (size_t li = 0; li < nl; ++li) {
      const size_t q0 = li * nf;
      zl[q0] = rl[q0] * l_pivot[q0];
      for (size_t q = q0 + 1; q < q0 + nf; ++q) zl[q] = (rl[q] - l_lower[q] * zl[q - 1]) * l_pivot[q];
      for (size_t q = q0 + nf; q-- > q0;) {
        if (q + 1 < q0 + nf) zl[q] -= l_upper[q] * zl[q + 1];
        dot += rl[q].real() * zl[q].real() + rl[q].imag() * zl[q].imag();
      }
    }
    return dot;
  };
  // With res = r − A t (global, fixed entries 0): t += δ ≈ A_ΩΩ⁻¹ res_Ω, res −= A δ.
  auto local_correction = [&](Vec& tg, Vec& res) {
    double rr = 0;
    for (size_t li = 0; li < nl; ++li)
      for (size_t j = 0; j < nf; ++j) {
        const cplx v = res[j * n + static_cast<size_t>(local_vertex[li])];
        local_r[li * nf + j] = v;
        rr += std::norm(v);
      }
    std::fill(local_x.begin(), local_x.end(), cplx(0, 0));
    const double tau2 = kLocalTolerance * kLocalTolerance * rr;
    local_iterations += local_pcg(local_x, local_r, local_z, local_p, local_ap, rr, tau2, kLocalIterations, local_apply,
                                  local_lines);
    // res −= A δ on the local vertices and their neighbours (δ = local_x, zero elsewhere).
    for (size_t ti = 0; ti < touched.size(); ++ti) {
      const auto i = static_cast<size_t>(touched[ti]);
      const int li = local_of[i];
      if (li >= 0) {
        local_product(local_x.data(), static_cast<size_t>(li), row_acc.data());
        for (size_t j = 0; j < nf; ++j) tg[j * n + i] += local_x[static_cast<size_t>(li) * nf + j];
      } else {
        std::fill(row_acc.begin(), row_acc.end(), cplx(0, 0));
        for (int e = touched_start[ti]; e < touched_start[ti + 1]; ++e) {
          const cplx v = touched_val[static_cast<size_t>(e)];
          const cplx* xc = local_x.data() + static_cast<size_t>(touched_col[static_cast<size_t>(e)]) * nf;
          for (size_t j = 0; j < nf; ++j) row_acc[j] += v * xc[j];
        }
      }
      for (size_t j = 0; j < nf; ++j)
        if (!fixed[j * n + i]) res[j * n + i] -= row_acc[j];
    }
  };

  std::vector<std::vector<cplx>> coarse_g(coarse.size()), coarse_y(coarse.size());
  for (size_t m = 0; m < coarse.size(); ++m) coarse_g[m].resize(n), coarse_y[m].resize(n);
  tbb::enumerable_thread_specific<ModeScratch> coarse_scratch;
  std::atomic<long> coarse_iterations{0};
  // out = C r: restriction to the modes, their spatial solves, prolongation (fixed entries 0).
  // The modes of each frame (index into coarse, the frame's index in the segment).
  std::vector<std::vector<std::pair<size_t, size_t>>> frame_modes(nf);
  for (size_t m = 0; m < coarse.size(); ++m)
    for (size_t jj = 0; jj < coarse[m].count; ++jj) frame_modes[coarse[m].first + jj].emplace_back(m, jj);
  auto coarse_correction = [&](const Vec& r, Vec& out) {
    // Blocks of vertices, every frame read once and used by all its modes.
    blocks(n, par, [&](size_t i0, size_t i1) {
      for (size_t m = 0; m < coarse.size(); ++m)
        std::fill(coarse_g[m].begin() + static_cast<std::ptrdiff_t>(i0),
                  coarse_g[m].begin() + static_cast<std::ptrdiff_t>(i1), cplx(0, 0));
      for (size_t j = 0; j < nf; ++j) {
        const cplx* rj = r.data() + j * n;
        for (const auto& [m, jj] : frame_modes[j]) {
          const double q = coarse[m].q[static_cast<Eigen::Index>(jj)];
          cplx* g = coarse_g[m].data();
          for (size_t i = i0; i < i1; ++i) g[i] += q * rj[i];
        }
      }
    });
    auto solve_mode = [&](size_t m) {
      const int it = CoarseSystem{op, coarse[m]}.solve(coarse_g[m].data(), coarse_y[m].data(), kCoarseTolerance,
                                                      kCoarseIterations, coarse_scratch.local());
      coarse_iterations += it;
    };
    if (par)
      tbb::parallel_for(size_t{0}, coarse.size(), solve_mode, tbb::simple_partitioner());
    else
      for (size_t m = 0; m < coarse.size(); ++m) solve_mode(m);
    blocks(n, par, [&](size_t i0, size_t i1) {
      for (size_t j = 0; j < nf; ++j) {
        cplx* oj = out.data() + j * n;
        std::fill(oj + i0, oj + i1, cplx(0, 0));
        for (const auto& [m, jj] : frame_modes[j]) {
          const double q = coarse[m].q[static_cast<Eigen::Index>(jj)];
          const cplx* y = coarse_y[m].data();
          for (size_t i = i0; i < i1; ++i) oj[i] += q * y[i];
        }
        const char* fj = fixed.data() + j * n;
        for (size_t i = i0; i < i1; ++i)
          if (fj[i]) oj[i] = 0;
      }
    });
  };

  Vec& r = sized(work_->r, total);
  Vec& p = sized(work_->p, total);
  Vec& ap = sized(work_->ap, total);
  Vec& zp = sized(work_->zp, total);
  Vec& t = coarse.empty() ? work_->t : sized(work_->t, total);
  // zp = M r (either preconditioner); returns Re <r, zp>.
  auto apply_preconditioner = [&]() {
    if (coarse.empty()) return precondition(r, zp);
    coarse_correction(r, t);  // t = C r
    // ap = r − A C r (ap is free until the next product), in the sweep itself.
    a.sweep(
        t,
        [&](size_t k, cplx, cplx yk) {
          ap[k] = r[k] - yk;
          return 0.0;
        },
        [&](size_t k) { ap[k] = 0; });
    if (nl > 0) local_correction(t, ap);  // t += δ, ap −= A δ
    precondition(ap, zp);  // zp = M⁻¹ (r − A t)
    return chunked_sum(total, par, [&](size_t s, size_t e) {
      double partial = 0;
      for (size_t k = s; k < e; ++k) {
        zp[k] += t[k];
        partial += r[k].real() * zp[k].real() + r[k].imag() * zp[k].imag();
      }
      return partial;
    });
  };
  a.apply(x, ap);
  blocks(total, par, [&](size_t s, size_t e) {
    for (size_t k = s; k < e; ++k) r[k] = rhs_span[k] - ap[k];
  });
  double rz = apply_preconditioner();
  p = zp;
  double rnorm = std::sqrt(sum(total, par, [&](size_t k) { return std::norm(r[k]); }));
  int it = 0;
  const bool flexible = !coarse.empty();
  while (rnorm > options.tolerance * bnorm && it < options.max_iterations) {
    const double pap = a.apply(p, ap);
    if (!(pap > 0)) break;  // not positive definite on this subspace
    const double alpha = rz / pap;
    // x += αp, r −= αAp, ‖r‖² and (flexible CG) Re <r_new, z_old> in one pass.
    double r_z_old = 0;
    if (flexible) {
      std::vector<double> parts((total + kSumChunk - 1) / kSumChunk);
      rnorm = std::sqrt(chunked_sum(total, par, [&](size_t s, size_t e) {
        double partial = 0, cross = 0;
        for (size_t k = s; k < e; ++k) {
          x[k] += alpha * p[k];
          r[k] -= alpha * ap[k];
          partial += std::norm(r[k]);
          cross += r[k].real() * zp[k].real() + r[k].imag() * zp[k].imag();
        }
        parts[s / kSumChunk] = cross;
        return partial;
      }));
      for (const double c : parts) r_z_old += c;
    } else {
      rnorm = std::sqrt(chunked_sum(total, par, [&](size_t s, size_t e) {
        double partial = 0;
        for (size_t k = s; k < e; ++k) {
          x[k] += alpha * p[k];
          r[k] -= alpha * ap[k];
          partial += std::norm(r[k]);
        }
        return partial;
      }));
    }
    ++it;
    if (rnorm <= options.tolerance * bnorm) break;
    const double rz_new = apply_preconditioner();
    const double beta = (rz_new - r_z_old) / rz;
    rz = rz_new;
    blocks(total, par, [&](size_t s, size_t e) {
      for (size_t k = s; k < e; ++k) p[k] = zp[k] + beta * p[k];
    });
  }
  if (!coarse.empty())
    report.method = fmt::format("preconditioned CG (temporal line solves) with {} low temporal modes as coarse "
                                "correction ({} spatial iterations in all){}, matrix-free",
                                coarse.size(), coarse_iterations.load(),
                                nl > 0 ? fmt::format(" and a local solve on the {} vertices near the moving "
                                                     "constraints ({} iterations in all)",
                                                     nl, local_iterations)
                                       : std::string());
  report.iterations = it;
  report.residual = rnorm / bnorm;
  report.success = std::isfinite(report.residual) && report.residual <= options.tolerance;
  return report;
}

}  // namespace tvf
