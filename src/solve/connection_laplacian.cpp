#include "tvf/solve/connection_laplacian.h"

#include "tvf/core/error.h"
#include "tvf/mesh/intrinsic_triangulation.h"
#include "solve/one_blas_thread.h"

// GCC 12 sees a null outer-index pointer in the Ref that Eigen's CholmodSupport makes of a
// compressed matrix (viewAsCholmod), which cannot occur: DirichletSolver's matrix is L's
// compressed copy. The warning points into Eigen's headers, so it is silenced from here
// to the end of the file.
#pragma GCC diagnostic push
#pragma GCC diagnostic ignored "-Wnull-dereference"
#include <Eigen/CholmodSupport>
#include <Eigen/SparseCholesky>
#include <Eigen/SparseLU>

#include <algorithm>
#include <cmath>
#include <mutex>

namespace tvf {

namespace {

// Weight of halfedge h = i→j seen from i (both halves for symmetric weights); cotan
// weights come from the intrinsic triangulation instead.
double halfedge_weight(const Mesh& mesh, int h, LaplacianWeights weights) {
  switch (weights) {
    case LaplacianWeights::cotan: break;  // the intrinsic triangulation's (connection_laplacian)
    case LaplacianWeights::uniform: return 1.0;
    case LaplacianWeights::mean_value: {
      // Angles at i on either side of edge ij: in h's face (between h and i→k) and in the
      // twin's face (between i→l and h).
      double s = std::tan(0.5 * mesh.corner_angle(h));
      if (const int t = mesh.twin(h); t >= 0) s += std::tan(0.5 * mesh.corner_angle(Mesh::next(t)));
      return s / mesh.edge_length(h);
    }
  }
  TVF_CHECK(false, "unknown weights");
}

}  // namespace

ConnectionLaplacian connection_laplacian(const TangentBundle& bundle, LaplacianWeights weights) {
  const Mesh& mesh = bundle.mesh();
  const int nv = mesh.num_vertices();
  ConnectionLaplacian lap;
  lap.weights = weights;
  lap.hermitian = weights != LaplacianWeights::mean_value;
  lap.weight_sum = Eigen::VectorXd::Zero(nv);
  std::vector<Eigen::Triplet<cplx>> t;
  t.reserve(static_cast<size_t>(nv + 2 * mesh.num_halfedges()));
  // Row i gets, for every neighbour j, w_ij on the diagonal and −w_ij·r_ji at (i, j).
  // Boundary edges have one halfedge; their reverse direction is handled from it.
  auto add = [&](int i, int j, double w, cplx r_ji) {
    lap.weight_sum[i] += w;
    t.emplace_back(i, j, -w * r_ji);
  };
  if (weights == LaplacianWeights::cotan) {
    // On the intrinsic Delaunay triangulation (same vertices): w_ij ≥ 0 on every edge.
    const IntrinsicTriangulation idt(bundle);
    lap.intrinsic_flips = idt.flips();
    lap.mollification = idt.mollification();
    lap.clamped_edges = idt.clamped_edges();
    lap.min_input_weight = idt.min_input_weight();
    for (int h = 0; h < idt.num_halfedges(); ++h) {
      const int tw = idt.twin(h);
      if (tw >= 0 && tw < h) continue;  // each edge once
      const double w = idt.edge_weight(h);
      const cplx r_ij = idt.transport(h);
      add(idt.tail(h), idt.head(h), w, std::conj(r_ij));
      add(idt.head(h), idt.tail(h), w, r_ij);
    }
  }
  for (int h = 0; weights != LaplacianWeights::cotan && h < mesh.num_halfedges(); ++h) {
    const int i = mesh.tail(h), j = mesh.head(h);
    const int tw = mesh.twin(h);
    const cplx r_ij = bundle.transport(h);  // T_i → T_j
    if (lap.hermitian) {
      if (tw >= 0 && tw < h) continue;  // each edge once
      const double w = halfedge_weight(mesh, h, weights);
      add(i, j, w, std::conj(r_ij));
      add(j, i, w, r_ij);
    } else {
      add(i, j, halfedge_weight(mesh, h, weights), std::conj(r_ij));
      if (tw < 0) {
        // The reverse halfedge j→i does not exist: its weight from j's side, whose two
        // angles beside the edge reduce to the one in this face.
        const double s = std::tan(0.5 * mesh.corner_angle(Mesh::next(h)));
        add(j, i, s / mesh.edge_length(h), r_ij);
      }
    }
  }
  for (int v = 0; v < nv; ++v) t.emplace_back(v, v, lap.weight_sum[v]);
  lap.matrix.resize(nv, nv);
  lap.matrix.setFromTriplets(t.begin(), t.end());
  lap.matrix.makeCompressed();
  return lap;
}

struct DirichletSolver::Impl {
  Eigen::SparseMatrix<cplx> a;  // L's pattern; values rewritten per solve
  Eigen::SimplicialLDLT<Eigen::SparseMatrix<cplx>> ldlt;
  Eigen::SparseLU<Eigen::SparseMatrix<cplx>> lu;
  // Constructed only when used: each holds a cholmod_common (CHOLMOD's workspace).
  std::unique_ptr<Eigen::CholmodSupernodalLLT<Eigen::SparseMatrix<cplx>, Eigen::Lower>> cholmod;
};

namespace {

// From this many vertices automatic takes CHOLMOD (measured: docs/benchmarks.md, "Sparse
// factorizations": at 4,225 vertices the simplicial LDLᴴ is as fast or faster, from
// 10,242 on CHOLMOD is faster, by 1.3× to 2.7× at 20,000).
constexpr Eigen::Index kCholmodVertices = 8000;

DirichletFactorization resolve(const ConnectionLaplacian& laplacian, DirichletFactorization f) {
  if (f == DirichletFactorization::automatic)
    return laplacian.hermitian && laplacian.matrix.rows() >= kCholmodVertices ? DirichletFactorization::cholmod
                                                                               : DirichletFactorization::simplicial;
  TVF_CHECK(f != DirichletFactorization::cholmod || laplacian.hermitian,
            "CHOLMOD's LLᴴ needs Hermitian (cotan or uniform) weights");
  return f;
}

}  // namespace

DirichletSolver::DirichletSolver(const ConnectionLaplacian& laplacian, DirichletFactorization factorization)
    : laplacian_(laplacian), factorization_(resolve(laplacian, factorization)), impl_(std::make_unique<Impl>()) {
  analyze();
}

DirichletSolver::DirichletSolver(const DirichletSolver& other)
    : laplacian_(other.laplacian_), factorization_(other.factorization_), impl_(std::make_unique<Impl>()) {
  analyze();
}

int graph_components(const ConnectionLaplacian& laplacian, std::vector<int>& component) {
  // Breadth first over the pattern (L's columns: the pattern is symmetric).
  const Eigen::Index n = laplacian.matrix.rows();
  component.assign(static_cast<size_t>(n), -1);
  int count = 0;
  std::vector<Eigen::Index> queue;
  for (Eigen::Index s = 0; s < n; ++s) {
    if (component[static_cast<size_t>(s)] >= 0) continue;
    component[static_cast<size_t>(s)] = count;
    queue.assign(1, s);
    while (!queue.empty()) {
      const Eigen::Index c = queue.back();
      queue.pop_back();
      for (Eigen::SparseMatrix<cplx>::InnerIterator it(laplacian.matrix, c); it; ++it) {
        if (component[static_cast<size_t>(it.row())] >= 0) continue;
        component[static_cast<size_t>(it.row())] = count;
        queue.push_back(it.row());
      }
    }
    ++count;
  }
  return count;
}

DirichletSolver::~DirichletSolver() = default;

void DirichletSolver::analyze() {
  impl_->a = laplacian_.matrix;
  num_components_ = graph_components(laplacian_, component_);
  if (factorization_ == DirichletFactorization::cholmod) {
    impl_->cholmod = std::make_unique<Eigen::CholmodSupernodalLLT<Eigen::SparseMatrix<cplx>, Eigen::Lower>>();
    // Failures come back through info() and the report; CHOLMOD prints nothing.
    impl_->cholmod->cholmod().print = 0;
    impl_->cholmod->analyzePattern(impl_->a);
    TVF_CHECK(impl_->cholmod->info() == Eigen::Success, "CHOLMOD's symbolic analysis failed (status {})",
              impl_->cholmod->cholmod().status);
  } else if (laplacian_.hermitian) {
    impl_->ldlt.analyzePattern(impl_->a);
  } else {
    impl_->lu.analyzePattern(impl_->a);
  }
}

SolveReport DirichletSolver::solve(std::span<const char> constrained, std::span<const cplx> values,
                                   std::span<cplx> out) {
  return solve(constrained, values, out, {});
}

SolveReport DirichletSolver::solve(std::span<const char> constrained, std::span<const cplx> values,
                                   std::span<cplx> out, std::span<const double> penalty) {
  const Eigen::Index n = laplacian_.matrix.rows();
  TVF_CHECK(penalty.empty() || static_cast<Eigen::Index>(penalty.size()) == n, "penalty of size {} for {} vertices",
            penalty.size(), n);
  TVF_CHECK(static_cast<Eigen::Index>(constrained.size()) == n && static_cast<Eigen::Index>(values.size()) == n &&
                static_cast<Eigen::Index>(out.size()) == n,
            "sizes {} {} {} for {} vertices", constrained.size(), values.size(), out.size(), n);
  SolveReport report;
  report.method = factorization_ == DirichletFactorization::cholmod ? "sparse Cholesky (CHOLMOD supernodal LLᴴ)"
                   : laplacian_.hermitian                               ? "sparse Cholesky (LDLᴴ)"
                                                                        : "sparse LU";
  // Components without a constraint (hard or soft) are held at zero (their minimiser;
  // where their connection is flat, L is singular there and the factorization would fail).
  std::vector<char> component_fixed(static_cast<size_t>(num_components_), 0);
  int fixed_count = 0;
  bool any = false;
  for (Eigen::Index v = 0; v < n; ++v) {
    const bool soft = !penalty.empty() && penalty[static_cast<size_t>(v)] > 0;
    if (constrained[static_cast<size_t>(v)] || soft) {
      component_fixed[static_cast<size_t>(component_[static_cast<size_t>(v)])] = 1;
      any = true;
    }
    if (constrained[static_cast<size_t>(v)]) ++fixed_count;
  }
  if (!any) {
    // No constraint: the zero field is the minimiser.
    std::fill(out.begin(), out.end(), cplx(0, 0));
    report.success = true;
    return report;
  }
  std::vector<char> fixed_here;
  std::vector<cplx> values_here;
  if (std::find(component_fixed.begin(), component_fixed.end(), char{0}) != component_fixed.end()) {
    fixed_here.assign(constrained.begin(), constrained.end());
    values_here.assign(values.begin(), values.end());
    for (Eigen::Index v = 0; v < n; ++v)
      if (!component_fixed[static_cast<size_t>(component_[static_cast<size_t>(v)])]) {
        fixed_here[static_cast<size_t>(v)] = 1;
        values_here[static_cast<size_t>(v)] = cplx(0, 0);
      }
    constrained = fixed_here;
    values = values_here;
  }
  auto failed = [&](const std::string& why) {
    report.failure = fmt::format(
        "factoring the connection Laplacian ({} weights; {} vertices, {} of them fixed) by {} failed: {}",
        laplacian_.weights == LaplacianWeights::cotan     ? "cotan"
        : laplacian_.weights == LaplacianWeights::uniform ? "uniform"
                                                          : "mean-value",
        n, fixed_count, report.method, why);
    return report;
  };
  const char* not_pd = laplacian_.weights == LaplacianWeights::cotan
                           ? "the matrix is not positive definite (it should be by construction on the intrinsic "
                             "Delaunay triangulation: please report the mesh)"
                           : "the matrix is not positive definite";

  // A = L with constrained rows and columns replaced by identity (same pattern);
  // b_F = −L_FC z_C, b_C = z_C.
  Eigen::SparseMatrix<cplx>& a = impl_->a;
  const Eigen::SparseMatrix<cplx>& l = laplacian_.matrix;
  Eigen::VectorXcd b = Eigen::VectorXcd::Zero(n);
  for (Eigen::Index col = 0; col < n; ++col) {
    const bool col_fixed = constrained[static_cast<size_t>(col)] != 0;
    Eigen::SparseMatrix<cplx>::InnerIterator it_a(a, col);
    for (Eigen::SparseMatrix<cplx>::InnerIterator it(l, col); it; ++it, ++it_a) {
      const Eigen::Index row = it.row();
      const bool row_fixed = constrained[static_cast<size_t>(row)] != 0;
      if (row_fixed || col_fixed) {
        it_a.valueRef() = (row == col) ? cplx(1, 0) : cplx(0, 0);
        if (!row_fixed && col_fixed) b[row] -= it.value() * values[static_cast<size_t>(col)];
      } else {
        it_a.valueRef() = it.value();
      }
    }
    if (col_fixed) b[col] = values[static_cast<size_t>(col)];
  }
  if (!penalty.empty()) {
    // Soft constraints at free vertices: μ on the diagonal (the pattern holds it), μ·c on
    // the right-hand side.
    for (Eigen::Index v = 0; v < n; ++v) {
      const double mu = penalty[static_cast<size_t>(v)];
      if (mu <= 0 || constrained[static_cast<size_t>(v)]) continue;
      a.coeffRef(v, v) += mu;
      b[v] += mu * values[static_cast<size_t>(v)];
    }
  }

  Eigen::VectorXcd z;
  if (factorization_ == DirichletFactorization::cholmod) {
    const detail::OneBlasThread one_thread;
    impl_->cholmod->factorize(a);
    if (impl_->cholmod->info() != Eigen::Success)
      return failed(impl_->cholmod->cholmod().status == CHOLMOD_NOT_POSDEF
                        ? std::string(not_pd)
                        : fmt::format("CHOLMOD status {}", impl_->cholmod->cholmod().status));
    z = impl_->cholmod->solve(b);
  } else if (laplacian_.hermitian) {
    impl_->ldlt.factorize(a);
    if (impl_->ldlt.info() != Eigen::Success) return failed("a zero pivot (the matrix is singular)");
    z = impl_->ldlt.solve(b);
  } else {
    impl_->lu.factorize(a);
    if (impl_->lu.info() != Eigen::Success) return failed("the matrix is singular (" + impl_->lu.lastErrorMessage() + ")");
    z = impl_->lu.solve(b);
  }
  const double bn = b.norm();
  report.residual = bn > 0 ? (a * z - b).norm() / bn : 0.0;
  report.success = std::isfinite(report.residual);
  if (!report.success) return failed("the solution is not finite");
  for (Eigen::Index v = 0; v < n; ++v) out[static_cast<size_t>(v)] = z[v];
  return report;
}

#pragma GCC diagnostic pop

}  // namespace tvf
