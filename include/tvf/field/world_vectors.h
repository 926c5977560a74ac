#pragma once
// Tangent coordinates → world-space 3-vectors, the form every export uses.
#include "tvf/field/field.h"
#include "tvf/mesh/tangent_bundle.h"

#include <vector>

namespace tvf {

// N × |V| × 3 floats, frame-major (the layout of field.npy).
std::vector<float> world_vectors_f32(const TangentBundle& bundle, const Field& field);
// One frame, |V| × 3 floats.
std::vector<float> world_vectors_f32(const TangentBundle& bundle, const Field& field, int frame);

}  // namespace tvf
