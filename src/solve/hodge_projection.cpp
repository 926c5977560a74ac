#include "tvf/solve/hodge_projection.h"

#include "tvf/core/error.h"

#include <Eigen/SparseCholesky>
#include <fmt/format.h>
#include <tbb/parallel_for.h>

#include <chrono>
#include <cmath>
#include <numeric>

namespace tvf {

namespace {

using SpMat = Eigen::SparseMatrix<double>;

constexpr int kMaxIterations = 40;
// Relative residual ‖b − Aφ‖/‖b‖ at which CG stops: round-off level for A's conditioning.
constexpr double kTolerance = 1e-13;

int find_root(std::vector<int>& parent, int v) {
  while (parent[static_cast<size_t>(v)] != v) {
    parent[static_cast<size_t>(v)] = parent[static_cast<size_t>(parent[static_cast<size_t>(v)])];
    v = parent[static_cast<size_t>(v)];
  }
  return v;
}

// Real view of a complex vector: (Re z_0, Im z_0, Re z_1, …).
Eigen::Map<const Eigen::VectorXd> as_real(std::span<const cplx> z) {
  return {reinterpret_cast<const double*>(z.data()), static_cast<Eigen::Index>(2 * z.size())};
}
Eigen::Map<Eigen::VectorXd> as_real(std::span<cplx> z) {
  return {reinterpret_cast<double*>(z.data()), static_cast<Eigen::Index>(2 * z.size())};
}

}  // namespace

struct DivergenceFreeProjector::Impl {
  SpMat d;         // |V| × 2|V|: the weak divergence of every vertex
  SpMat du;        // the rows of the unknowns (tested vertices less one pin per free component)
  SpMat du_t;      // its transpose
  Eigen::VectorXd w_inv;  // 2|V|: 1/m_i twice
  SpMat a;        // D_u W⁻¹ D_uᵀ
  double epsilon = 0;
  Eigen::SimplicialLDLT<SpMat> ldlt;  // of A + εI
  int unknowns = 0;
};

DivergenceFreeProjector::DivergenceFreeProjector(const TangentBundle& bundle, FluxBoundary boundary)
    : boundary_(boundary), impl_(std::make_unique<Impl>()) {
  const Mesh& mesh = bundle.mesh();
  nv_ = mesh.num_vertices();
  const auto n = static_cast<size_t>(nv_);
  mass_.assign(n, 0.0);

  // D from the faces: (D z)_i −= A_f ⟨∇λ_i, X_f⟩ with A_f ∇λ_k = ½·i·e_k (e_k the edge
  // opposite corner k, counter-clockwise, in the face frame) and X_f = ⅓ Σ_c ρ_c z_c.
  std::vector<Eigen::Triplet<double>> t;
  t.reserve(static_cast<size_t>(mesh.num_faces()) * 18);
  std::vector<int> parent(n);
  std::iota(parent.begin(), parent.end(), 0);
  for (int f = 0; f < mesh.num_faces(); ++f) {
    const Face& face = mesh.face(f);
    const double area = mesh.face_area(f);
    cplx half_grad[3], rho[3];
    for (int k = 0; k < 3; ++k) {
      const Vec3 e = mesh.position(face[static_cast<size_t>((k + 2) % 3)]) -
                     mesh.position(face[static_cast<size_t>((k + 1) % 3)]);
      half_grad[k] = cplx(0, 1) * bundle.world_to_face(f, e);  // 2·A_f·∇λ_k
      rho[k] = bundle.corner_to_face(3 * f + k);
      mass_[static_cast<size_t>(face[static_cast<size_t>(k)])] += area / 3.0;
    }
    for (int k = 0; k < 3; ++k) {
      const int i = face[static_cast<size_t>(k)];
      for (int c = 0; c < 3; ++c) {
        const int v = face[static_cast<size_t>(c)];
        const cplx w = std::conj(half_grad[k]) * rho[c];  // Re(w z) = Re w·x − Im w·y
        t.emplace_back(i, 2 * v, -w.real() / 6.0);
        t.emplace_back(i, 2 * v + 1, w.imag() / 6.0);
      }
    }
    const int r0 = find_root(parent, face[0]);
    for (int k = 1; k < 3; ++k) {
      const int r = find_root(parent, face[static_cast<size_t>(k)]);
      if (r != r0) parent[static_cast<size_t>(r)] = r0;
    }
  }
  impl_->d.resize(nv_, 2 * nv_);
  impl_->d.setFromTriplets(t.begin(), t.end());
  impl_->d.makeCompressed();
  for (int v = 0; v < nv_; ++v)
    TVF_CHECK(mass_[static_cast<size_t>(v)] > 0, "vertex {} has no area", v);
  impl_->w_inv.resize(2 * nv_);
  for (int v = 0; v < nv_; ++v) impl_->w_inv[2 * v] = impl_->w_inv[2 * v + 1] = 1.0 / mass_[static_cast<size_t>(v)];

  // Tested vertices; a component tested everywhere has φ's constant free: pin one vertex.
  std::vector<char> has_boundary(n, 0);
  for (int v = 0; v < nv_; ++v)
    if (mesh.is_boundary_vertex(v)) has_boundary[static_cast<size_t>(find_root(parent, v))] = 1;
  tested_.assign(n, 1);
  if (boundary == FluxBoundary::open)
    for (int v = 0; v < nv_; ++v)
      if (mesh.is_boundary_vertex(v)) tested_[static_cast<size_t>(v)] = 0;
  std::vector<char> pinned_component(n, 0);
  std::vector<int> row(n, -1);
  int unknowns = 0;
  for (int v = 0; v < nv_; ++v) {
    if (!tested_[static_cast<size_t>(v)]) continue;
    const auto root = static_cast<size_t>(find_root(parent, v));
    const bool constant_free = boundary == FluxBoundary::no_flux || !has_boundary[root];
    if (constant_free && !pinned_component[root]) {
      pinned_component[root] = 1;  // φ = 0 here; its row of D z' = 0 follows from the others
      continue;
    }
    row[static_cast<size_t>(v)] = unknowns++;
  }
  impl_->unknowns = unknowns;
  std::vector<Eigen::Triplet<double>> tu;
  tu.reserve(t.size());
  for (const auto& e : t)
    if (const int r = row[static_cast<size_t>(e.row())]; r >= 0) tu.emplace_back(r, e.col(), e.value());
  impl_->du.resize(unknowns, 2 * nv_);
  impl_->du.setFromTriplets(tu.begin(), tu.end());
  impl_->du.makeCompressed();
  impl_->du_t = impl_->du.transpose();
  if (unknowns == 0) return;

  impl_->a = impl_->du * impl_->w_inv.asDiagonal() * impl_->du_t;
  // A may be nearly singular beyond the pinned constants: the averaged face gradient
  // cannot see a function that alternates over the three colours of a 3-colourable
  // patch (up and down triangles' gradients cancel at every vertex), so such meshes
  // (a torus grid, a symmetric icosphere) have modes with eigenvalues at 1e-9 of the
  // largest, or exactly 0. The right-hand side −D z never excites an exact null mode
  // (it lies in the range of D), so the solve factors A + εI (ε = 1e-10 of the largest
  // diagonal entry) and uses it to precondition conjugate gradients on A (project()).
  // A null-mode part of φ is harmless: its gradient Gφ is zero.
  impl_->epsilon = 1e-10 * impl_->a.diagonal().cwiseAbs().maxCoeff();
  SpMat shifted = impl_->a;
  for (Eigen::Index i = 0; i < shifted.rows(); ++i) shifted.coeffRef(i, i) += impl_->epsilon;
  impl_->ldlt.compute(shifted);
  if (impl_->ldlt.info() != Eigen::Success)
    throw Error(fmt::format("{}: the divergence-free projection cannot be set up on this mesh (the sparse "
                            "factorization failed)",
                            mesh.source()));
}

DivergenceFreeProjector::~DivergenceFreeProjector() = default;

std::vector<double> DivergenceFreeProjector::divergence(std::span<const cplx> z) const {
  TVF_CHECK(static_cast<int>(z.size()) == nv_, "{} values for {} vertices", z.size(), nv_);
  const Eigen::VectorXd d = impl_->d * as_real(z);
  return {d.data(), d.data() + d.size()};
}

std::vector<cplx> DivergenceFreeProjector::gradient(std::span<const double> phi) const {
  TVF_CHECK(static_cast<int>(phi.size()) == nv_, "{} values for {} vertices", phi.size(), nv_);
  const Eigen::Map<const Eigen::VectorXd> p(phi.data(), nv_);
  const Eigen::VectorXd g = -(impl_->w_inv.asDiagonal() * (impl_->d.transpose() * p));
  std::vector<cplx> out(static_cast<size_t>(nv_));
  for (int v = 0; v < nv_; ++v) out[static_cast<size_t>(v)] = cplx(g[2 * v], g[2 * v + 1]);
  return out;
}

double DivergenceFreeProjector::divergence_rms(std::span<const cplx> z) const {
  const std::vector<double> d = divergence(z);
  double num = 0, den = 0;
  for (size_t v = 0; v < d.size(); ++v) {
    if (!tested_[v]) continue;
    num += d[v] * d[v] / mass_[v];
    den += mass_[v];
  }
  return den > 0 ? std::sqrt(num / den) : 0.0;
}

ProjectionStats DivergenceFreeProjector::project(std::span<cplx> z) const {
  TVF_CHECK(static_cast<int>(z.size()) == nv_, "{} values for {} vertices", z.size(), nv_);
  ProjectionStats s;
  s.divergence_before = divergence_rms(z);
  if (impl_->unknowns > 0) {
    auto x = as_real(z);
    const Eigen::VectorXd b = -(impl_->du * x);
    const double bn = b.norm();
    if (bn > 0) {
      // Conjugate gradients on A, preconditioned by the factorization of A + εI: the
      // preconditioned spectrum is λ/(λ + ε), 1 but for the few near-null modes, which
      // CG resolves in as many extra steps.
      Eigen::VectorXd phi = impl_->ldlt.solve(b);
      Eigen::VectorXd r = b - impl_->a * phi;
      Eigen::VectorXd zr = impl_->ldlt.solve(r);
      Eigen::VectorXd p = zr;
      double rz = r.dot(zr);
      for (int step = 0; step < kMaxIterations && r.norm() > kTolerance * bn; ++step) {
        const Eigen::VectorXd ap = impl_->a * p;
        const double pap = p.dot(ap);
        if (!(pap > 0)) break;
        const double alpha = rz / pap;
        phi += alpha * p;
        r -= alpha * ap;
        zr = impl_->ldlt.solve(r);
        const double rz_next = r.dot(zr);
        p = zr + (rz_next / rz) * p;
        rz = rz_next;
      }
      x += impl_->w_inv.cwiseProduct(impl_->du_t * phi);
      s.residual = (impl_->du * x).norm() / bn;
    }
  }
  s.divergence_after = divergence_rms(z);
  return s;
}

IncompressibleReport make_incompressible(const TangentBundle& bundle, Field& field,
                                         const IncompressibleOptions& options) {
  const auto start = std::chrono::steady_clock::now();
  TVF_CHECK(field.num_vertices() == bundle.mesh().num_vertices(), "field of {} vertices on a mesh of {}",
            field.num_vertices(), bundle.mesh().num_vertices());
  const DivergenceFreeProjector projector(bundle, options.boundary);
  IncompressibleReport report;
  report.boundary = options.boundary;
  report.method = fmt::format("Hodge projection (weak divergence, adjoint gradient, sparse LDLᵀ of the "
                              "{}-vertex two-ring Laplacian, {} boundary)",
                              bundle.mesh().num_vertices(), to_string(options.boundary));
  const int frames = field.frames();
  report.before.assign(static_cast<size_t>(frames), 0.0);
  report.after.assign(static_cast<size_t>(frames), 0.0);
  std::vector<double> residual(static_cast<size_t>(frames), 0.0);
  auto one = [&](int j) {
    const ProjectionStats s = projector.project(field.frame(j));
    report.before[static_cast<size_t>(j)] = s.divergence_before;
    report.after[static_cast<size_t>(j)] = s.divergence_after;
    residual[static_cast<size_t>(j)] = s.residual;
  };
  if (options.parallel)
    tbb::parallel_for(0, frames, one);
  else
    for (int j = 0; j < frames; ++j) one(j);
  for (int j = 0; j < frames; ++j) {
    report.max_before = std::max(report.max_before, report.before[static_cast<size_t>(j)]);
    report.max_after = std::max(report.max_after, report.after[static_cast<size_t>(j)]);
    report.worst_residual = std::max(report.worst_residual, residual[static_cast<size_t>(j)]);
  }
  report.seconds = std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
  return report;
}

}  // namespace tvf
