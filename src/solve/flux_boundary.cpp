#include "tvf/solve/flux_boundary.h"

namespace tvf {

const char* to_string(FluxBoundary b) {
  switch (b) {
    case FluxBoundary::no_flux: return "no_flux";
    case FluxBoundary::open: return "open";
  }
  return "no_flux";
}

}  // namespace tvf
