#pragma once
// Temporal coherence (paper §9, Fig. 18; DESIGN §6): y_i = Σ_k ‖V_k(t_{i+1}) − V_k(t_i)‖
// over all vertices k, for i = 0..N−2. Vectors are compared in each vertex's own basis
// (the basis does not change over time, so this is the world-space difference).
#include "tvf/field/field.h"

#include <string>
#include <vector>

namespace tvf {

std::vector<double> coherence(const Field& field);

// CSV with header "frame,t,coherence": row i holds i, t_i and y_i.
std::string coherence_csv(const Field& field, const std::vector<double>& y);

}  // namespace tvf
