#pragma once
// Internal to the analysis module: the exact predicates that per-frame singularities
// (singularities.cpp) and space-time tracking (topology.cpp) share. They must be one
// function, not two copies: the tracking's frame crossings are required to be bit for bit
// the per-frame singularities.
#include "tvf/core/types.h"

#include <array>

namespace tvf::detail {

inline constexpr double kTwoPi = 2 * kPi;

inline double cross(cplx a, cplx b) { return a.real() * b.imag() - a.imag() * b.real(); }
inline cplx times_i(cplx z) { return {-z.imag(), z.real()}; }         // exact
inline cplx times_minus_i(cplx z) { return {z.imag(), -z.real()}; }   // exact

// The turn of the field along an edge, a = arg(z_hi · conj(r·z_lo)) ∈ [−π, π], z_lo at the
// lower vertex (in the global order), r the edge's transport, decided by simulation of
// simplicity where it is degenerate (see index_predicates.cpp and docs/analysis.md).
double edge_angle(cplx zi, cplx zj, cplx r);

// Barycentric coordinates of the point of the triangle (w0, w1, w2) ⊂ C closest to 0: the
// zero of the linear interpolant when 0 is inside.
Vec3 zero_barycentric(const std::array<cplx, 3>& w);

}  // namespace tvf::detail
