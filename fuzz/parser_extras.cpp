// The one symbol the readers' sources need from outside them: the name of a flux boundary
// (defined with the projector in src/solve/hodge_projection.cpp, which would bring the
// solvers along). Compiled only into the parser targets' library (fuzz/CMakeLists.txt);
// it must name the values as hodge_projection.cpp does.
#include "tvf/solve/hodge_projection.h"

namespace tvf {

const char* to_string(FluxBoundary b) { return b == FluxBoundary::open ? "open" : "no_flux"; }

}  // namespace tvf
