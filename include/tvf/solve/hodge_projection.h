#pragma once
// Incompressible fields on demand: the projection of a per-vertex tangent field onto the
// divergence-free fields, V ← V − ∇φ (the exact part of the Hodge decomposition removed;
// the co-exact and harmonic parts stay), on planar grids and triangle-mesh surfaces.
//
// Discretization (the discrete sense in which "divergence-free" holds exactly):
//   - A vertex field z (z_i in T_i, TangentBundle's bases) is seen through its piecewise
//     linear interpolant (DESIGN §2): in face f the three corner vectors transported into
//     the face frame, whose mean X_f = ⅓ Σ_c ρ_c z_c is the field's average over the face.
//   - Divergence D: vertex fields → one number per vertex, the weak divergence of that
//     interpolant tested with the hat function λ_i:
//         (D z)_i = −Σ_{f ∋ i} A_f ⟨∇λ_i|_f, X_f⟩   ( = ∫ λ_i div X  − ∮_∂Ω λ_i X·n ),
//     an integrated quantity (units: field × length). d_i / m_i is the pointwise value,
//     m_i = ⅓ Σ_{f ∋ i} A_f the vertex area (barycentric lumped mass).
//   - Gradient G = −W⁻¹Dᵀ, the negative adjoint of D for the vertex inner product
//     ⟨u, v⟩_W = Σ_i m_i Re(ū_i v_i):  (G φ)_i = the area-weighted mean of the face
//     gradients ∇φ|_f of the faces around i, transported into T_i.
//   - Projection: φ solves  A φ = −D z  with A = −D G = D W⁻¹ Dᵀ (symmetric positive
//     semidefinite, a two-ring Laplacian), then z ← z − G φ. This is the W-orthogonal
//     projection onto ker D: D z' = 0 up to the solver's round-off, applying it twice
//     equals applying it once, and a field with D z = 0 is returned unchanged. The cotan
//     Laplacian Gᶠᵀ M Gᶠ is the same operator for face-constant fields; for vertex fields
//     it is not D∘G, so using it here would leave a projection that is not one
//     (docs/architecture.md).
//
// Boundary (planar domains and surfaces with boundary), the tested set of vertices:
//   - no_flux (default): every vertex is tested, so boundary rows include the flux through
//     the boundary; the result has zero divergence and zero normal flux (the Leray /
//     L²-orthogonal Hodge projection; φ has the natural Neumann condition). φ is fixed at
//     one vertex per connected component (its constant is free).
//   - open: only interior vertices are tested and φ = 0 on the boundary (Dirichlet): the
//     result is divergence-free inside and flow may cross the boundary, so a uniform
//     stream or a centre on a square window is left as it is.
// Closed components are the same under both.
#include "tvf/field/field.h"
#include "tvf/mesh/tangent_bundle.h"
#include "tvf/solve/flux_boundary.h"

#include <functional>
#include <memory>
#include <span>
#include <string>
#include <vector>

namespace tvf {

// Result of one projection (STYLE 5).
struct ProjectionStats {
  double divergence_before = 0.0;  // RMS pointwise divergence over the tested vertices
  double divergence_after = 0.0;
  double residual = 0.0;           // ‖D z'‖ / ‖D z‖ (0 when D z = 0)
};

class DivergenceFreeProjector {
public:
  // Builds D, the vertex areas and A, and factorizes A + εI once (sparse LDLᵀ, AMD
  // ordering; each solve refines iteratively against A itself, so A's near-null modes
  // cost accuracy nothing). Throws tvf::Error if the factorization fails.
  explicit DivergenceFreeProjector(const TangentBundle& bundle, FluxBoundary boundary = FluxBoundary::no_flux);
  ~DivergenceFreeProjector();
  DivergenceFreeProjector(const DivergenceFreeProjector&) = delete;
  DivergenceFreeProjector& operator=(const DivergenceFreeProjector&) = delete;

  FluxBoundary boundary() const { return boundary_; }
  int num_vertices() const { return nv_; }
  // Vertices whose divergence the projection zeroes (all for no_flux; interior ones and
  // those of closed components for open).
  const std::vector<char>& tested() const { return tested_; }
  std::span<const double> vertex_areas() const { return mass_; }

  // (D z)_i for every vertex (integrated weak divergence; see above).
  std::vector<double> divergence(std::span<const cplx> z) const;
  // (G φ)_i for every vertex, in T_i: the adjoint gradient, G = −W⁻¹Dᵀ.
  std::vector<cplx> gradient(std::span<const double> phi) const;
  // √(Σ_tested d_i²/m_i / Σ_tested m_i): the RMS of the pointwise divergence d_i/m_i.
  double divergence_rms(std::span<const cplx> z) const;

  // Projects one frame in place. Thread-safe: frames may be projected concurrently.
  ProjectionStats project(std::span<cplx> z) const;

private:
  struct Impl;
  FluxBoundary boundary_;
  int nv_ = 0;
  std::vector<char> tested_;
  std::vector<double> mass_;
  std::unique_ptr<Impl> impl_;
};

struct IncompressibleOptions {
  FluxBoundary boundary = FluxBoundary::no_flux;
  bool parallel = true;  // frames in parallel (TBB)
};

// What make_incompressible did, per frame and overall.
struct IncompressibleReport {
  FluxBoundary boundary = FluxBoundary::no_flux;
  std::string method;
  std::vector<double> before, after;  // RMS pointwise divergence per frame
  double max_before = 0.0, max_after = 0.0;
  double worst_residual = 0.0;  // largest ‖D z'‖ / ‖D z‖ over frames
  double seconds = 0.0;
};

// Projects every frame of `field` (factor once, frames solved in parallel).
IncompressibleReport make_incompressible(const TangentBundle& bundle, Field& field,
                                         const IncompressibleOptions& options = {});

}  // namespace tvf
