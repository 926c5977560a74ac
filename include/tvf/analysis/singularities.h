#pragma once
// Singularities of one frame (DESIGN §6, paper §4). A face is singular where the winding
// of its three corner vectors, transported into the face frame, is non-zero (index ±1).
// Its position is the zero of the face's linear interpolant, its Jacobian the gradient of
// that interpolant in the face frame, and the eigenvalues of the Jacobian give its type.
//
// Degenerate cases — a corner vector that is exactly zero, or a zero of the interpolant
// that lies on an edge or a vertex — are decided by simulation of simplicity: a zero
// vector at vertex v is perturbed to ε^(v+1)·(1, 0) style infinitesimals ordered by the
// global vertex index, so every zero is claimed by exactly one face (none lost, none
// counted twice). See docs/analysis.md.
//
// The discrete index (docs/analysis.md, "Singularities"). For a halfedge i→j let
// a_ij = arg(z_j / (r_ij z_i)) ∈ (−π, π] be the angle the field turns along the edge
// relative to the connection (TangentBundle::transport), evaluated once per edge in the
// direction lower → higher vertex index and negated for the other direction, so both faces
// of an edge use the same number. With Ω_f = Σ_corners s_v·α − π the curvature of the
// connection inside face f (s_v = 2π / angle_sum(v) at interior vertices, 1 on the
// boundary; the holonomy of the transports around f), the index of f is
//     index_f = (a_01 + a_12 + a_20 + Ω_f) / 2π,
// an integer (Knöppel et al. 2013). It equals the winding number of the three corner
// vectors transported into the face frame whenever that winding is well defined, and the
// antisymmetry of a_ij makes Σ_f index_f = Σ_f Ω_f / 2π = χ exactly on every closed mesh,
// for every field (Poincaré–Hopf). Zero vertex values and edges with exactly opposite
// vectors (a_ij = ±π) are decided by simulation of simplicity: vertex v's value is
// perturbed to z_v + δ_{2v} + i·δ_{2v+1} with δ_k = ε^(2^k), so the lower the vertex index,
// the larger its perturbation.
//
// Types (classify_jacobian): det J < 0 is a saddle; otherwise, with eigenvalues
// λ = τ/2 ± √(τ²/4 − det J) (τ = trace), complex eigenvalues with |Re λ| ≤ 0.1·|Im λ| are a
// center, complex eigenvalues with |Im λ| ≤ 0.1·|Re λ| count as real, other complex ones
// are a repelling (τ > 0) or attracting (τ < 0) focus, and real ones a source (τ ≥ 0) or a
// sink. A face whose index and det J disagree in sign (rounding, or a zero that sits on
// the face's boundary) gets the type its index implies: saddle for −1, source or sink by
// the trace for +1.
#include "tvf/field/field.h"
#include "tvf/field/field_sampler.h"
#include "tvf/mesh/tangent_bundle.h"

#include <array>
#include <span>
#include <string>
#include <vector>

namespace tvf {

enum class SingularityType { source, sink, saddle, center, repelling_focus, attracting_focus };
const char* to_string(SingularityType t);  // exact names of DESIGN §9

struct Singularity {
  int frame = 0;
  double t = 0.0;
  SurfacePoint where;          // face and barycentric coordinates of the zero
  Vec3 position;               // world position
  int index = 0;               // +1 or −1
  SingularityType type = SingularityType::source;
  Mat2 jacobian = Mat2::Zero();  // in the face frame (face_e1, face_e2)
};

// Singularities of one frame given its vertex values (|V|, each in its vertex basis),
// one per face of non-zero index, in increasing face order. Throws tvf::Error when a
// value is not finite.
std::vector<Singularity> find_singularities(const TangentBundle& bundle,
                                            std::span<const cplx> values);
// The same with every face's Ω_f given (face_curvatures; empty: computed here), for a
// caller that finds the singularities of many fields on one mesh (Ω_f is the mesh's, and
// three quarters of the arctangents of a call): the same result to the bit.
std::vector<Singularity> find_singularities(const TangentBundle& bundle,
                                            std::span<const cplx> values,
                                            std::span<const double> curvature);
// Singularities of frame j of a field (frame and t filled in).
std::vector<Singularity> find_singularities(const TangentBundle& bundle, const Field& field,
                                            int frame);

// Classification of a Jacobian (index from the sign of its determinant, type from its
// eigenvalues; |Im λ| small relative to |Re λ| counts as real, |Re λ| small relative to
// |Im λ| as a center). Exposed for tests and for the element catalogue.
SingularityType classify_jacobian(const Mat2& jacobian);

// Relative thresholds of classify_jacobian (see above). A designed center or source is
// never exact in a sampled field: neighbouring elements and the discretisation tilt its
// eigenvalues by a few percent (measured on the examples: 2–6 %), so the thresholds are
// 10 %: a spiral that turns less than 0.1 rad per e-fold of growth reads as a node.
inline constexpr double kCenterTolerance = 0.1;   // |Re λ| ≤ this·|Im λ|: center
inline constexpr double kRealTolerance = 0.1;     // |Im λ| ≤ this·|Re λ|: real eigenvalues

// Index of every face (|F| entries: 0 for regular faces, ±1 for singular ones; ±2 and more
// only on faces whose curvature Ω_f approaches π, i.e. meshes far coarser than any
// design needs). The sum over a region of faces is the index of its boundary loop, which
// is what pair cancellation needs.
std::vector<int> face_indices(const TangentBundle& bundle, std::span<const cplx> values);

// The Jacobian of the field's linear interpolant on face f, in the face frame (face_e1,
// face_e2): the vertex values carried into the face (corner_to_face); on a surface the
// covariant derivative. Its trace is the face's divergence.
Mat2 face_jacobian(const TangentBundle& bundle, std::span<const cplx> values, int face);
// The same from the face's three corner values already carried into the face frame.
Mat2 face_linear_jacobian(const TangentBundle& bundle, int face, const std::array<cplx, 3>& w);

// Ω_f above: the rotation of a vector transported counter-clockwise around face f by the
// bundle's connection (radians; positive where the surface is positively curved), i.e.
// the argument of the product of the three transports, lifted to the real line next to
// the rescaled angle excess Σ s_v·α − π. Over a closed mesh the sum is 2π·χ.
double face_curvature(const TangentBundle& bundle, int face);
// Ω_f of every face, in face order.
std::vector<double> face_curvatures(const TangentBundle& bundle);

}  // namespace tvf
