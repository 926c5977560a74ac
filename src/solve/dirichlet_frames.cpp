#include "tvf/solve/dirichlet_frames.h"

#include "tvf/core/error.h"
#include "solve/one_blas_thread.h"

// GCC 12 sees a null outer-index pointer in the Ref that Eigen's CholmodSupport makes of a
// compressed matrix (viewAsCholmod), which cannot occur (as in connection_laplacian.cpp).
#pragma GCC diagnostic push
#pragma GCC diagnostic ignored "-Wnull-dereference"
#include <Eigen/CholmodSupport>
#include <Eigen/OrderingMethods>
#include <Eigen/SparseCholesky>

#include <tbb/enumerable_thread_specific.h>
#include <tbb/parallel_for.h>

#include <algorithm>
#include <cmath>
#include <memory>

namespace tvf {

namespace {

// One problem's constraints as solved: components without any constraint held at zero
// (as DirichletSolver does), penalties only at free vertices.
struct Frame {
  std::vector<char> fixed;
  std::vector<cplx> values;     // meaningful at fixed and penalized vertices
  std::vector<double> penalty;  // μ_v at free vertices, 0 elsewhere
  int fixed_count = 0;          // the problem's own fixed vertices (for the failure sentence)
};

Frame effective(const DirichletProblem& p, std::span<const int> component, int num_components) {
  const size_t n = component.size();
  TVF_CHECK(p.constrained.size() == n && p.values.size() == n && (p.penalty.empty() || p.penalty.size() == n),
            "sizes {} {} {} for {} vertices", p.constrained.size(), p.values.size(), p.penalty.size(), n);
  Frame f;
  f.fixed.assign(p.constrained.begin(), p.constrained.end());
  f.values.assign(p.values.begin(), p.values.end());
  f.penalty.assign(n, 0.0);
  std::vector<char> component_fixed(static_cast<size_t>(num_components), 0);
  for (size_t v = 0; v < n; ++v) {
    const bool soft = !p.penalty.empty() && p.penalty[v] > 0;
    if (f.fixed[v]) {
      f.fixed[v] = 1;
      ++f.fixed_count;
    } else if (soft) {
      f.penalty[v] = p.penalty[v];
    }
    if (f.fixed[v] || soft) component_fixed[static_cast<size_t>(component[v])] = 1;
  }
  for (size_t v = 0; v < n; ++v)
    if (!component_fixed[static_cast<size_t>(component[v])]) {
      f.fixed[v] = 1;
      f.values[v] = cplx(0, 0);
    }
  return f;
}

inline double conj_of(double x) { return x; }
inline cplx conj_of(cplx x) { return std::conj(x); }

template <class Scalar>
using SpMat = Eigen::SparseMatrix<Scalar>;
template <class Scalar>
using Dense = Eigen::Matrix<Scalar, Eigen::Dynamic, Eigen::Dynamic>;

// The block's solver: what is shared (the ordering, the factorization of the leading rows,
// the trailing product C = L_TI D_I L_TIᴴ, the trailing pattern) and the per-problem solve.
template <class Scalar>
class Block {
public:
  Block(const SpMat<Scalar>& l, const Eigen::VectorXd& diagonal, std::span<const Frame> frames, bool cholmod)
      : l_(l), diagonal_(diagonal), frames_(frames), n_(static_cast<int>(l.rows())), cholmod_(cholmod) {}

  // The trailing set of the block: K (status differs between its problems) and the free
  // vertices next to K. Its size, to decide whether to split.
  int trailing() {
    const Frame& f0 = frames_.front();
    std::vector<char> changing(static_cast<size_t>(n_), 0);
    for (const Frame& f : frames_.subspan(1))
      for (int v = 0; v < n_; ++v) {
        const auto u = static_cast<size_t>(v);
        if (f.fixed[u] != f0.fixed[u] || (!f.fixed[u] && f.penalty[u] != f0.penalty[u])) changing[u] = 1;
      }
    std::vector<char> next(static_cast<size_t>(n_), 0);
    for (int v = 0; v < n_; ++v) {
      if (!changing[static_cast<size_t>(v)]) continue;
      for (typename SpMat<Scalar>::InnerIterator it(l_, v); it; ++it) {
        const auto w = static_cast<size_t>(it.row());
        if (!changing[w] && !f0.fixed[w]) next[w] = 1;
      }
    }
    border_.clear();
    changing_.clear();
    for (int v = 0; v < n_; ++v) {
      if (next[static_cast<size_t>(v)]) border_.push_back(v);
      if (changing[static_cast<size_t>(v)]) changing_.push_back(v);
    }
    return static_cast<int>(border_.size() + changing_.size());
  }

  // Orders and factors the leading rows; false if the factorization failed.
  bool factor() {
    const Frame& f0 = frames_.front();
    const int nb = static_cast<int>(border_.size());
    nt_ = nb + static_cast<int>(changing_.size());
    ni_ = n_ - nt_;
    // Trailing positions: the border, then K.
    position_.assign(static_cast<size_t>(n_), -1);
    for (int k = 0; k < nb; ++k) position_[static_cast<size_t>(border_[static_cast<size_t>(k)])] = ni_ + k;
    for (size_t k = 0; k < changing_.size(); ++k)
      position_[static_cast<size_t>(changing_[k])] = ni_ + nb + static_cast<int>(k);
    // The leading set I, ordered by AMD on its couplings (free to free: a fixed vertex's
    // row and column are the identity's).
    std::vector<int> lead;
    lead.reserve(static_cast<size_t>(ni_));
    std::vector<int> local(static_cast<size_t>(n_), -1);
    for (int v = 0; v < n_; ++v)
      if (position_[static_cast<size_t>(v)] < 0) {
        local[static_cast<size_t>(v)] = static_cast<int>(lead.size());
        lead.push_back(v);
      }
    if (ni_ > 0) {
      std::vector<Eigen::Triplet<double>> pt;
      for (int k = 0; k < ni_; ++k) {
        const int v = lead[static_cast<size_t>(k)];
        pt.emplace_back(k, k, 1.0);
        if (f0.fixed[static_cast<size_t>(v)]) continue;
        for (typename SpMat<Scalar>::InnerIterator it(l_, v); it; ++it) {
          const auto w = static_cast<size_t>(it.row());
          if (static_cast<int>(w) != v && local[w] >= 0 && !f0.fixed[w]) pt.emplace_back(local[w], k, 1.0);
        }
      }
      SpMat<double> pattern(ni_, ni_);
      pattern.setFromTriplets(pt.begin(), pt.end());
      Eigen::PermutationMatrix<Eigen::Dynamic, Eigen::Dynamic, int> order;
      Eigen::AMDOrdering<int>()(pattern, order);  // order.indices()[new] = old
      for (int k = 0; k < ni_; ++k)
        position_[static_cast<size_t>(lead[static_cast<size_t>(order.indices()[k])])] = k;
    }
    vertex_.assign(static_cast<size_t>(n_), 0);
    for (int v = 0; v < n_; ++v) vertex_[static_cast<size_t>(position_[static_cast<size_t>(v)])] = v;

    // The block's matrix: the leading rows as every problem has them; the trailing block
    // diagonal, d_v + μ_v + (d_v + 1) at the border (so that it stays positive definite:
    // its Schur complement is never used), 1 in K.
    std::vector<Eigen::Triplet<Scalar>> t;
    t.reserve(static_cast<size_t>(l_.nonZeros()));
    for (int v = 0; v < n_; ++v) {
      const auto u = static_cast<size_t>(v);
      const int pv = position_[u];
      if (pv >= ni_ + nb) {
        t.emplace_back(pv, pv, Scalar(1));
        continue;
      }
      if (f0.fixed[u]) {
        t.emplace_back(pv, pv, Scalar(1));
        continue;
      }
      for (typename SpMat<Scalar>::InnerIterator it(l_, v); it; ++it) {
        const auto w = static_cast<size_t>(it.row());
        const int pw = position_[w];
        if (pw == pv) {
          const double extra = pv >= ni_ ? diagonal_[v] + 1 : 0.0;
          t.emplace_back(pv, pv, it.value() + Scalar(f0.penalty[u] + extra));
        } else if (!f0.fixed[w] && (pv < ni_ || pw < ni_)) {
          t.emplace_back(pw, pv, it.value());
        }
      }
    }
    SpMat<Scalar> a(n_, n_);
    a.setFromTriplets(t.begin(), t.end());
    if (!(cholmod_ && factor_cholmod(a)) && !factor_simplicial(a)) return false;

    // C = L_TI D_I L_TIᴴ on the border (L_KI = 0: K meets I only through the border).
    Dense<Scalar> c = Dense<Scalar>::Zero(nb, nb);
    std::vector<std::pair<int, Scalar>> col;
    for (int j = 0; j < ni_; ++j) {
      col.clear();
      for (int p = fp_[static_cast<size_t>(j)]; p < fp_[static_cast<size_t>(j) + 1]; ++p) {
        const int row = fi_[static_cast<size_t>(p)];
        const Scalar x = fx_[static_cast<size_t>(p)];
        if (row < ni_ || x == Scalar(0)) continue;  // (CHOLMOD's relaxed supernodes store zeros)
        TVF_CHECK(row < ni_ + nb, "a leading column reaches the changing set");
        col.emplace_back(row - ni_, x);
      }
      for (const auto& [ra, va] : col)
        for (const auto& [rb, vb] : col) c(ra, rb) += va * Scalar(fd_[static_cast<size_t>(j)]) * conj_of(vb);
    }

    // The trailing pattern: L's entries among T, the border's dense block, the diagonal.
    std::vector<Eigen::Triplet<Scalar>> st;
    for (int k = 0; k < nt_; ++k) {
      const int v = vertex_[static_cast<size_t>(ni_ + k)];
      st.emplace_back(k, k, Scalar(0));
      for (typename SpMat<Scalar>::InnerIterator it(l_, v); it; ++it) {
        const int pw = position_[static_cast<size_t>(it.row())];
        if (pw >= ni_ && pw - ni_ != k) st.emplace_back(pw - ni_, k, Scalar(0));
      }
      if (k < nb)
        for (int r = 0; r < nb; ++r)
          if (r != k) st.emplace_back(r, k, Scalar(0));
    }
    sigma_.resize(nt_, nt_);
    sigma_.setFromTriplets(st.begin(), st.end());  // duplicates summed: one entry each
    sigma_.makeCompressed();
    // What each stored entry is made of: L's entry and C's.
    entry_l_.assign(static_cast<size_t>(sigma_.nonZeros()), Scalar(0));
    entry_c_.assign(static_cast<size_t>(sigma_.nonZeros()), Scalar(0));
    entry_row_.assign(static_cast<size_t>(sigma_.nonZeros()), 0);
    for (int k = 0; k < nt_; ++k) {
      const int v = vertex_[static_cast<size_t>(ni_ + k)];
      for (typename SpMat<Scalar>::InnerIterator it(sigma_, k); it; ++it) {
        const auto p = static_cast<size_t>(&it.valueRef() - sigma_.valuePtr());
        const int r = static_cast<int>(it.row());
        entry_row_[p] = r;
        entry_l_[p] = l_.coeff(vertex_[static_cast<size_t>(ni_ + r)], v);
        if (r < nb && k < nb) entry_c_[p] = c(r, k);
      }
    }
    return true;
  }

  // What one problem's solve changes: the trailing Schur complement's values and their
  // factorization. The rest of the block is only read, so problems may be solved at once,
  // each thread with its own Scratch (the same ordering: the same arithmetic).
  struct Scratch {
    SpMat<Scalar> sigma;
    Eigen::SimplicialLDLT<SpMat<Scalar>, Eigen::Lower, Eigen::AMDOrdering<int>> small;
  };
  std::unique_ptr<Scratch> scratch() const {
    auto s = std::make_unique<Scratch>();
    s->sigma = sigma_;
    if (nt_ > 0) s->small.analyzePattern(s->sigma);
    return s;
  }

  // Solves problem k into out; fills the report (not the method).
  void solve(int k, std::span<cplx> out, SolveReport& report, Scratch& scratch) const {
    const Frame& f = frames_[static_cast<size_t>(k)];
    const auto n = static_cast<size_t>(n_);
    // b: c at fixed vertices; μ c − Σ_{w fixed} L_vw c_w at free ones.
    std::vector<cplx> y(n, cplx(0, 0));
    for (size_t w = 0; w < n; ++w) {
      if (f.fixed[w]) {
        const cplx cw = f.values[w];
        y[static_cast<size_t>(position_[w])] += cw;
        if (cw == cplx(0, 0)) continue;
        for (typename SpMat<Scalar>::InnerIterator it(l_, static_cast<int>(w)); it; ++it) {
          const auto v = static_cast<size_t>(it.row());
          if (!f.fixed[v]) y[static_cast<size_t>(position_[v])] -= it.value() * cw;
        }
      } else if (f.penalty[w] > 0) {
        y[static_cast<size_t>(position_[w])] += f.penalty[w] * f.values[w];
      }
    }
    double bn = 0;
    for (const cplx& b : y) bn += std::norm(b);
    bn = std::sqrt(bn);

    // Forward through the leading columns; the trailing entries then hold the reduced
    // right-hand side b_T − L_TI y_I.
    const int* lp = fp_.data();
    const int* li = fi_.data();
    const Scalar* lx = fx_.data();
    const double* d = fd_.data();
    for (int j = 0; j < ni_; ++j) {
      const cplx yj = y[static_cast<size_t>(j)];
      if (yj == cplx(0, 0)) continue;
      for (int p = lp[j]; p < lp[j + 1]; ++p) y[static_cast<size_t>(li[p])] -= lx[p] * yj;
    }
    for (int j = 0; j < ni_; ++j) y[static_cast<size_t>(j)] /= d[j];

    std::vector<cplx> z(n);
    if (nt_ > 0) {
      // The trailing Schur complement of this problem: A_TT − C.
      SpMat<Scalar>& s = scratch.sigma;
      Scalar* sx = s.valuePtr();
      for (int kk = 0; kk < nt_; ++kk) {
        const auto v = static_cast<size_t>(vertex_[static_cast<size_t>(ni_ + kk)]);
        for (int p = s.outerIndexPtr()[kk]; p < s.outerIndexPtr()[kk + 1]; ++p) {
          const auto up = static_cast<size_t>(p);
          const int r = entry_row_[up];
          const auto w = static_cast<size_t>(vertex_[static_cast<size_t>(ni_ + r)]);
          if (f.fixed[v] || f.fixed[w]) {
            sx[p] = Scalar(r == kk ? 1.0 : 0.0);
          } else {
            sx[p] = entry_l_[up] - entry_c_[up];
            if (r == kk) sx[p] += Scalar(f.penalty[v]);
          }
        }
      }
      scratch.small.factorize(s);
      if (scratch.small.info() != Eigen::Success) {
        report.success = false;
        report.failure = "a zero pivot in the changing vertices' Schur complement";
        return;
      }
      solve_trailing(y, z, scratch.small);
    }
    // Backward through the leading columns.
    for (int j = ni_ - 1; j >= 0; --j) {
      cplx sum = y[static_cast<size_t>(j)];
      for (int p = lp[j]; p < lp[j + 1]; ++p) sum -= conj_of(lx[p]) * z[static_cast<size_t>(li[p])];
      z[static_cast<size_t>(j)] = sum;
    }
    for (size_t v = 0; v < n; ++v) out[v] = f.fixed[v] ? f.values[v] : z[static_cast<size_t>(position_[v])];

    // The residual ‖A z − b‖ / ‖b‖ (fixed rows: z_v − c_v = 0), as DirichletSolver reports it.
    double rn = 0;
    for (size_t v = 0; v < n; ++v) {
      if (f.fixed[v]) continue;
      cplx r = f.penalty[v] * (out[v] - f.values[v]);
      for (typename SpMat<Scalar>::InnerIterator it(l_, static_cast<int>(v)); it; ++it)
        r += conj_of(it.value()) * out[static_cast<size_t>(it.row())];  // row v = conj(column v)
      rn += std::norm(r);
    }
    report.residual = bn > 0 ? std::sqrt(rn) / bn : 0.0;
    report.success = std::isfinite(report.residual);
    if (!report.success) report.failure = "the solution is not finite";
  }

private:
  // Eigen's up-looking simplicial LDLᴴ, in the given order.
  bool factor_simplicial(const SpMat<Scalar>& a) {
    Eigen::SimplicialLDLT<SpMat<Scalar>, Eigen::Lower, Eigen::NaturalOrdering<int>> ldlt(a);
    if (ldlt.info() != Eigen::Success) return false;
    const SpMat<Scalar>& lf = ldlt.matrixL().nestedExpression();
    fp_.assign(lf.outerIndexPtr(), lf.outerIndexPtr() + n_ + 1);
    fi_.assign(lf.innerIndexPtr(), lf.innerIndexPtr() + lf.nonZeros());
    fx_.assign(lf.valuePtr(), lf.valuePtr() + lf.nonZeros());
    fd_.resize(static_cast<size_t>(n_));
    for (int j = 0; j < n_; ++j) fd_[static_cast<size_t>(j)] = std::real(ldlt.vectorD()[j]);
    return true;
  }

  // CHOLMOD's supernodal factorization (BLAS kernels on the supernodes, one BLAS thread)
  // in the given order (natural, no postordering), turned into a simplicial LDLᴴ to read
  // its columns. False (and Eigen's then) if anything differs from that.
  bool factor_cholmod(SpMat<Scalar>& a) {
    cholmod_common c;
    cholmod_start(&c);
    c.print = 0;
    c.nmethods = 1;
    c.method[0].ordering = CHOLMOD_NATURAL;
    c.postorder = 0;
    c.supernodal = CHOLMOD_SUPERNODAL;
    cholmod_sparse view = Eigen::viewAsCholmod(Eigen::Ref<SpMat<Scalar>>(a));
    view.stype = -1;  // the lower triangle
    bool ok = false;
    cholmod_factor* f = cholmod_analyze(&view, &c);
    if (f && c.status == CHOLMOD_OK) {
      const detail::OneBlasThread one_thread;
      ok = cholmod_factorize(&view, f, &c) && c.status == CHOLMOD_OK && f->minor == f->n &&
           cholmod_change_factor(f->xtype, false, false, true, true, f, &c) && !f->is_super && !f->is_ll;
    }
    if (ok) {
      const auto* perm = static_cast<const int*>(f->Perm);
      for (int j = 0; j < n_ && ok; ++j) ok = perm[j] == j;
    }
    if (ok) {
      const auto* p = static_cast<const int*>(f->p);
      const auto* i = static_cast<const int*>(f->i);
      const auto* x = static_cast<const Scalar*>(f->x);
      fp_.assign(static_cast<size_t>(n_) + 1, 0);
      fi_.clear();
      fx_.clear();
      fd_.resize(static_cast<size_t>(n_));
      for (int j = 0; j < n_ && ok; ++j) {
        // Column j: D_j first (the diagonal of an LDLᴴ factor holds D), then L below it.
        ok = i[p[j]] == j;
        fd_[static_cast<size_t>(j)] = std::real(x[p[j]]);
        for (int q = p[j] + 1; q < p[j + 1]; ++q) {
          if (x[q] == Scalar(0)) continue;  // the relaxed supernodes' padding
          fi_.push_back(i[q]);
          fx_.push_back(x[q]);
        }
        fp_[static_cast<size_t>(j) + 1] = static_cast<int>(fi_.size());
      }
    }
    cholmod_free_factor(&f, &c);
    cholmod_finish(&c);
    return ok;
  }

  template <class Small>
  void solve_trailing(const std::vector<cplx>& y, std::vector<cplx>& z, const Small& small) const {
    const auto off = static_cast<size_t>(ni_);
    if constexpr (std::is_same_v<Scalar, double>) {
      Eigen::MatrixXd r(nt_, 2);
      for (int k = 0; k < nt_; ++k) {
        r(k, 0) = y[off + static_cast<size_t>(k)].real();
        r(k, 1) = y[off + static_cast<size_t>(k)].imag();
      }
      const Eigen::MatrixXd x = small.solve(r);
      for (int k = 0; k < nt_; ++k) z[off + static_cast<size_t>(k)] = cplx(x(k, 0), x(k, 1));
    } else {
      Eigen::VectorXcd r(nt_);
      for (int k = 0; k < nt_; ++k) r[k] = y[off + static_cast<size_t>(k)];
      const Eigen::VectorXcd x = small.solve(r);
      for (int k = 0; k < nt_; ++k) z[off + static_cast<size_t>(k)] = x[k];
    }
  }

  const SpMat<Scalar>& l_;
  const Eigen::VectorXd& diagonal_;
  std::span<const Frame> frames_;
  int n_;
  int ni_ = 0, nt_ = 0;
  std::vector<int> border_, changing_;
  std::vector<int> position_;  // vertex → its row in the block's ordering
  std::vector<int> vertex_;    // row → vertex
  bool cholmod_;
  // The block's factor: D, and L strictly below its diagonal (column j: rows
  // fi_[fp_[j] … fp_[j + 1]), in increasing order, values fx_).
  std::vector<int> fp_, fi_;
  std::vector<Scalar> fx_;
  std::vector<double> fd_;
  SpMat<Scalar> sigma_;
  std::vector<Scalar> entry_l_, entry_c_;
  std::vector<int> entry_row_;
};

template <class Scalar>
void solve_frames(const SpMat<Scalar>& l, const Eigen::VectorXd& diagonal, double max_trailing,
                  std::span<const Frame> frames, std::span<const std::span<cplx>> out, std::span<SolveReport> reports,
                  DirichletFrames::Statistics& stats, const std::function<void(size_t)>& after_each,
                  size_t first, bool cholmod, size_t solve_first, bool parallel) {
  Block<Scalar> block(l, diagonal, frames, cholmod);
  const int nt = block.trailing();
  if (frames.size() > 1 && nt > max_trailing * static_cast<double>(l.rows())) {
    const size_t half = frames.size() / 2;
    auto lower = [&] {
      solve_frames(l, diagonal, max_trailing, frames.first(half), out.first(half), reports.first(half), stats,
                   after_each, first, cholmod, solve_first, parallel);
    };
    auto upper = [&] {
      solve_frames(l, diagonal, max_trailing, frames.subspan(half), out.subspan(half), reports.subspan(half), stats,
                   after_each, first + half, cholmod, solve_first, parallel);
    };
    // The half holding solve_first goes first (the halves' results do not depend on it).
    if (solve_first >= first + half && solve_first < first + frames.size()) {
      upper();
      lower();
    } else {
      lower();
      upper();
    }
    return;
  }
  ++stats.blocks;
  stats.largest_trailing = std::max(stats.largest_trailing, nt);
  if (!block.factor()) {
    for (size_t k = 0; k < frames.size(); ++k) {
      reports[k].success = false;
      reports[k].failure = "a zero pivot (the matrix is singular)";
      if (after_each) after_each(first + k);
    }
    return;
  }
  // Each frame is solved on its own with the block's factorization: the order only says
  // which is ready first (solve_first alone, then the others, at once when `parallel`:
  // otherwise a machine with more cores than blocks of frames would leave them idle).
  using Scratch = typename Block<Scalar>::Scratch;
  const size_t lead = solve_first >= first && solve_first < first + frames.size() ? solve_first - first : frames.size();
  auto one = [&](size_t k, Scratch& s) {
    block.solve(static_cast<int>(k), out[k], reports[k], s);
    if (after_each) after_each(first + k);
  };
  const std::unique_ptr<Scratch> own = block.scratch();
  if (lead < frames.size()) one(lead, *own);
  if (!parallel) {
    for (size_t k = 0; k < frames.size(); ++k)
      if (k != lead) one(k, *own);
    return;
  }
  tbb::enumerable_thread_specific<std::unique_ptr<Scratch>> scratches;
  tbb::parallel_for(size_t(0), frames.size(), [&](size_t k) {
    if (k == lead) return;
    std::unique_ptr<Scratch>& s = scratches.local();
    if (!s) s = block.scratch();
    one(k, *s);
  });
}

}  // namespace

DirichletFrames::DirichletFrames(const ConnectionLaplacian& laplacian, DirichletFramesOptions options)
    : laplacian_(laplacian), options_(options) {
  TVF_CHECK(laplacian.hermitian, "DirichletFrames needs Hermitian (cotan or uniform) weights");
  const SpMat<cplx>& l = laplacian.matrix;
  real_ = true;
  for (Eigen::Index k = 0; k < l.nonZeros() && real_; ++k) real_ = l.valuePtr()[k].imag() == 0;
  if (real_) real_matrix_ = l.real();
  // Connected components of L's graph, as DirichletSolver finds them.
  num_components_ = graph_components(laplacian, component_);
}

std::vector<SolveReport> DirichletFrames::solve(std::span<const DirichletProblem> problems,
                                                std::span<const std::span<cplx>> out, Statistics* statistics,
                                                const std::function<void(size_t)>& after_each,
                                                size_t solve_first, bool parallel) const {
  TVF_CHECK(problems.size() == out.size(), "{} problems, {} outputs", problems.size(), out.size());
  std::vector<SolveReport> reports(problems.size());
  if (problems.empty()) return reports;
  const auto n = static_cast<size_t>(laplacian_.matrix.rows());
  std::vector<Frame> frames;
  frames.reserve(problems.size());
  for (size_t k = 0; k < problems.size(); ++k) {
    TVF_CHECK(out[k].size() == n, "an output of {} entries for {} vertices", out[k].size(), n);
    frames.push_back(effective(problems[k], component_, num_components_));
  }
  Statistics stats;
  const bool cholmod = static_cast<int>(n) >= options_.cholmod_from;
  if (real_)
    solve_frames<double>(real_matrix_, laplacian_.weight_sum, options_.max_trailing_fraction, frames, out, reports,
                         stats, after_each, 0, cholmod, solve_first, parallel);
  else
    solve_frames<cplx>(laplacian_.matrix, laplacian_.weight_sum, options_.max_trailing_fraction, frames, out, reports,
                       stats, after_each, 0, cholmod, solve_first, parallel);
  const char* method = real_ ? "sparse Cholesky (real LDLᵀ shared by a block of frames, changing vertices last)"
                             : "sparse Cholesky (LDLᴴ shared by a block of frames, changing vertices last)";
  for (size_t k = 0; k < reports.size(); ++k) {
    reports[k].method = method;
    if (!reports[k].success)
      reports[k].failure = fmt::format(
          "factoring the connection Laplacian ({} weights; {} vertices, {} of them fixed) by {} failed: {}",
          laplacian_.weights == LaplacianWeights::cotan ? "cotan" : "uniform", n, frames[k].fixed_count, method,
          reports[k].failure);
  }
  if (statistics) *statistics = stats;
  return reports;
}

}  // namespace tvf

#pragma GCC diagnostic pop
