#include "tvf/solve/spacetime.h"

#include "tvf/core/error.h"

#include <tbb/blocked_range.h>
#include <tbb/combinable.h>
#include <tbb/parallel_for.h>
#include <tbb/parallel_reduce.h>

#include <algorithm>
#include <cmath>
#include <functional>
#include <vector>

namespace tvf {

namespace {

using Vec = std::vector<cplx>;

// Runs body(begin, end) over [0, n), in parallel blocks or not.
template <class F>
void blocks(size_t n, bool parallel, F&& body) {
  if (!parallel || n < 4096) {
    body(size_t{0}, n);
    return;
  }
  tbb::parallel_for(tbb::blocked_range<size_t>(0, n, 2048),
                    [&](const tbb::blocked_range<size_t>& r) { body(r.begin(), r.end()); });
}

double dot_real(const Vec& a, const Vec& b, bool parallel) {
  if (!parallel || a.size() < 4096) {
    double s = 0;
    for (size_t k = 0; k < a.size(); ++k) s += (std::conj(a[k]) * b[k]).real();
    return s;
  }
  return tbb::parallel_reduce(
      tbb::blocked_range<size_t>(0, a.size(), 4096), 0.0,
      [&](const tbb::blocked_range<size_t>& r, double s) {
        for (size_t k = r.begin(); k < r.end(); ++k) s += (std::conj(a[k]) * b[k]).real();
        return s;
      },
      std::plus<>());
}

}  // namespace

SpaceTimeSolver::SpaceTimeSolver(const ConnectionLaplacian& laplacian, int frames,
                                 double temporal_weight)
    : laplacian_(laplacian), frames_(frames), b_(temporal_weight) {
  TVF_CHECK(laplacian.hermitian, "the space-time solve needs Hermitian (cotan or uniform) weights");
  TVF_CHECK(frames >= 1, "{} frames", frames);
}

void SpaceTimeSolver::interpolate_in_time(std::span<const char> fixed, std::span<const cplx> values,
                                          std::span<cplx> z) const {
  const auto n = static_cast<size_t>(vertices());
  const auto nf = static_cast<size_t>(frames_);
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

SolveReport SpaceTimeSolver::solve(std::span<const char> fixed, std::span<const cplx> values,
                                   std::span<cplx> z, const SpaceTimeOptions& options) const {
  const auto n = static_cast<size_t>(vertices());
  const auto nf = static_cast<size_t>(frames_);
  const size_t total = n * nf;
  TVF_CHECK(fixed.size() == total && values.size() == total && z.size() == total,
            "space-time sizes {} {} {} for {} entries", fixed.size(), values.size(), z.size(), total);
  SolveReport report;
  report.method = "preconditioned CG (temporal line solves), matrix-free";
  const auto& l = laplacian_.matrix;
  const Eigen::VectorXd& d = laplacian_.weight_sum;
  const Eigen::VectorXd ldiag = l.diagonal().real();
  const bool par = options.parallel;

  // y = A x over all entries (x's fixed entries included as they are).
  // y = A x over all entries (x's fixed entries included as they are). With `masked`,
  // y's fixed entries are zeroed and Re <x, y> over the rest is returned (fused, so the
  // iteration reads each vector as few times as possible: the solve is bandwidth-bound).
  auto apply = [&](const Vec& x, Vec& y, bool masked) {
    tbb::combinable<double> dot([] { return 0.0; });
    tbb::parallel_for(size_t{0}, nf, [&](size_t j) {
      const cplx* xj = x.data() + j * n;
      cplx* yj = y.data() + j * n;
      const char* fj = fixed.data() + j * n;
      for (Eigen::Index col = 0; col < l.outerSize(); ++col) yj[col] = 0;
      // Column-major L: y_j = L x_j.
      for (Eigen::Index col = 0; col < l.outerSize(); ++col) {
        const cplx xc = xj[col];
        if (xc == cplx(0, 0)) continue;
        for (Eigen::SparseMatrix<cplx>::InnerIterator it(l, col); it; ++it) yj[it.row()] += it.value() * xc;
      }
      // + b·D·(T x) along time.
      const cplx* xp = j > 0 ? xj - n : nullptr;
      const cplx* xn = j + 1 < nf ? xj + n : nullptr;
      double partial = 0;
      for (size_t i = 0; i < n; ++i) {
        cplx t(0, 0);
        if (xp) t += xj[i] - xp[i];
        if (xn) t += xj[i] - xn[i];
        cplx yi = yj[i] + b_ * d[static_cast<Eigen::Index>(i)] * t;
        if (masked) {
          if (fj[i]) yi = 0;
          partial += (std::conj(xj[i]) * yi).real();
        }
        yj[i] = yi;
      }
      dot.local() += partial;
    });
    return dot.combine(std::plus<>());
  };
  // Preconditioner: every vertex's temporal line solved exactly (Thomas algorithm) on
  // the free entries; fixed entries split the line. Lines are swept in blocks of
  // consecutive vertices, frame by frame, so memory is read in contiguous runs rather
  // than with a stride of |V| per line.
  constexpr size_t kBlock = 32;
  auto precondition = [&](const Vec& r, Vec& out) {
    const size_t nblocks = (n + kBlock - 1) / kBlock;
    tbb::combinable<double> dot([] { return 0.0; });
    tbb::parallel_for(size_t{0}, nblocks, [&](size_t blk) {
      const size_t i0 = blk * kBlock, i1 = std::min(n, i0 + kBlock);
      const size_t w = i1 - i0;
      std::vector<double> cp(w * nf);
      std::vector<cplx> dp(w * nf);
      for (size_t j = 0; j < nf; ++j) {
        const bool has_prev = j > 0, has_next = j + 1 < nf;
        for (size_t i = i0; i < i1; ++i) {
          const size_t k = j * n + i, q = j * w + (i - i0);
          if (fixed[k]) {
            cp[q] = 0;
            dp[q] = 0;
            continue;
          }
          const double c = b_ * d[static_cast<Eigen::Index>(i)];
          const double diag = ldiag[static_cast<Eigen::Index>(i)] + c * ((has_prev ? 1 : 0) + (has_next ? 1 : 0));
          const double lower = (has_prev && !fixed[k - n]) ? -c : 0.0;  // coupling to j−1
          const double upper = (has_next && !fixed[k + n]) ? -c : 0.0;  // coupling to j+1
          const double cprev = has_prev ? cp[q - w] : 0.0;
          const cplx dprev = has_prev ? dp[q - w] : cplx(0, 0);
          const double denom = diag - lower * cprev;
          cp[q] = upper / denom;
          dp[q] = (r[k] - lower * dprev) / denom;
        }
      }
      double partial = 0;
      for (size_t j = nf; j-- > 0;) {
        for (size_t i = i0; i < i1; ++i) {
          const size_t k = j * n + i, q = j * w + (i - i0);
          out[k] = fixed[k] ? cplx(0, 0) : dp[q] - (j + 1 < nf ? cp[q] * out[k + n] : cplx(0, 0));
          partial += (std::conj(r[k]) * out[k]).real();
        }
      }
      dot.local() += partial;
    });
    return dot.combine(std::plus<>());  // Re <r, M⁻¹ r>
  };

  // Right-hand side over the free entries: −A_FC z_C, from A applied to the fixed values.
  Vec xc(total), rhs(total);
  blocks(total, par, [&](size_t a, size_t e) {
    for (size_t k = a; k < e; ++k) xc[k] = fixed[k] ? values[k] : cplx(0, 0);
  });
  apply(xc, rhs, false);
  blocks(total, par, [&](size_t a, size_t e) {
    for (size_t k = a; k < e; ++k) rhs[k] = fixed[k] ? cplx(0, 0) : -rhs[k];
  });
  const double bnorm = std::sqrt(dot_real(rhs, rhs, par));

  // Unknown: the free part of z (initial guess from z).
  Vec x(total), r(total), p(total), ap(total), zp(total);
  blocks(total, par, [&](size_t a, size_t e) {
    for (size_t k = a; k < e; ++k) x[k] = fixed[k] ? cplx(0, 0) : z[k];
  });
  if (bnorm == 0) {
    std::fill(x.begin(), x.end(), cplx(0, 0));
  } else {
    apply(x, ap, true);
    blocks(total, par, [&](size_t a, size_t e) {
      for (size_t k = a; k < e; ++k) r[k] = rhs[k] - ap[k];
    });
    double rz = precondition(r, zp);
    p = zp;
    double rnorm = std::sqrt(dot_real(r, r, par));
    int it = 0;
    while (rnorm > options.tolerance * bnorm && it < options.max_iterations) {
      const double pap = apply(p, ap, true);
      if (!(pap > 0)) break;  // not positive definite on this subspace
      const double alpha = rz / pap;
      // x += αp, r −= αAp and ‖r‖² in one pass.
      tbb::combinable<double> rr([] { return 0.0; });
      blocks(total, par, [&](size_t a, size_t e) {
        double partial = 0;
        for (size_t k = a; k < e; ++k) {
          x[k] += alpha * p[k];
          r[k] -= alpha * ap[k];
          partial += std::norm(r[k]);
        }
        rr.local() += partial;
      });
      rnorm = std::sqrt(rr.combine(std::plus<>()));
      ++it;
      if (rnorm <= options.tolerance * bnorm) break;
      const double rz_new = precondition(r, zp);
      const double beta = rz_new / rz;
      rz = rz_new;
      blocks(total, par, [&](size_t a, size_t e) {
        for (size_t k = a; k < e; ++k) p[k] = zp[k] + beta * p[k];
      });
    }
    report.iterations = it;
    report.residual = rnorm / bnorm;
  }
  report.success = std::isfinite(report.residual) && report.residual <= options.tolerance;
  blocks(total, par, [&](size_t a, size_t e) {
    for (size_t k = a; k < e; ++k) z[k] = fixed[k] ? values[k] : x[k];
  });
  return report;
}

}  // namespace tvf
