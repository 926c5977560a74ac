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
#include "tvf/field/field.h"
#include "tvf/field/field_sampler.h"
#include "tvf/mesh/tangent_bundle.h"

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

// Singularities of one frame given its vertex values (|V|, each in its vertex basis).
std::vector<Singularity> find_singularities(const TangentBundle& bundle,
                                            std::span<const cplx> values);
// Singularities of frame j of a field (frame and t filled in).
std::vector<Singularity> find_singularities(const TangentBundle& bundle, const Field& field,
                                            int frame);

// Classification of a Jacobian (index from the sign of its determinant, type from its
// eigenvalues; |Im λ| small relative to |Re λ| counts as real, |Re λ| small relative to
// |Im λ| as a center). Exposed for tests and for the element catalogue.
SingularityType classify_jacobian(const Mat2& jacobian);

}  // namespace tvf
