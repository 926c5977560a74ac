#pragma once
// Key frames (DESIGN §10, paper §6): the static fields the space-time optimization holds
// fixed. A key frame's field is the static constrained design of its elements (each
// imposes its own field within solver.region_radius, as in the constrained generator) and
// streamlines (the tangents of each streamline, at the vertices of the faces it crosses,
// with magnitude `speed`), or the frame of a given field file at the key frame's time.
#include "tvf/scene/design_space.h"
#include "tvf/scene/scene.h"
#include "tvf/solve/connection_laplacian.h"

#include <vector>

namespace tvf {

// The frame a key frame at time t is held at: the nearest frame time.
int keyframe_frame(const Scene& scene, double t);

// Field (|V|, vertex bases) of scene.keyframes[k] on `space`. Throws tvf::Error naming
// keyframes[k] for a field file that does not match the domain.
std::vector<cplx> keyframe_field(const DesignSpace& space, const Scene& scene, size_t k,
                                 const ConnectionLaplacian& laplacian);

// Constraints of key frame k's own design (elements and streamlines) without solving:
// fixed[v] != 0 where the key frame prescribes a value.
void keyframe_constraints(const DesignSpace& space, const Scene& scene, size_t k,
                          std::vector<char>& fixed, std::vector<cplx>& values);

}  // namespace tvf
