#pragma once
// The boundary condition of the divergence-free projection (hodge_projection.h): no flux
// through the boundary, or an open boundary. Its own header so that the scene model and
// its readers name it without the projector.

namespace tvf {

enum class FluxBoundary { no_flux, open };
// "no_flux" | "open" (the scene's "incompressible" boundary, DESIGN §12).
const char* to_string(FluxBoundary b);

}  // namespace tvf
