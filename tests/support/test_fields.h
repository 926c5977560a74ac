#pragma once
// Fields with closed forms, built directly at the vertices (STYLE 19: defined once, shared
// by the integrate tests and the CLI tests).
#include "tvf/field/field.h"
#include "tvf/mesh/tangent_bundle.h"

#include <functional>

namespace tvf::test {

// V(x, t) given in world coordinates, projected into each vertex's tangent basis.
Field field_from(const TangentBundle& bundle, TimeSampling time, const std::function<Vec3(const Vec3&, double)>& v);

// The double gyre of Shadden, Lekien & Marsden 2005 on [0, 2] × [0, 1]:
//   u = −πA sin(πf) cos(πy),  v = πA cos(πf) sin(πy) ∂f/∂x,
//   f = a(t)x² + b(t)x, a = ε sin ωt, b = 1 − 2ε sin ωt; A = 0.1, ε = 0.25, ω = 2π/10.
Vec3 double_gyre(const Vec3& x, double t);

}  // namespace tvf::test
