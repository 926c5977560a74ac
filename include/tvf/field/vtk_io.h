#pragma once
// VTK XML output that ParaView and VTK's own readers open (DESIGN §9): one
// UnstructuredGrid (.vtu) per frame with point data "vector" (world-space 3-vectors,
// Float32) and "magnitude", and a ParaView Data collection (.pvd) listing the frames with
// their times. Written by hand (the XML is small and fixed; linking libvtk for it would
// pull hundreds of MB into the library); tests read the files back with VTK's readers.
#include "tvf/field/field.h"
#include "tvf/mesh/tangent_bundle.h"

#include <span>
#include <string>
#include <vector>

namespace tvf {

// Writes DIR/<stem>.pvd and DIR/<stem>_NNNN.vtu (NNNN = frame, zero-padded to 4 or
// more digits). Raw binary appended data, UInt64 headers.
void write_vtk_series(const std::string& dir, const std::string& stem, const TangentBundle& bundle,
                      const Field& field);

// A per-vertex scalar of every frame: frames × |V| values, frame-major (e.g. FTLE).
struct VtkScalarArray {
  std::string name;
  std::span<const float> values;
};
// Writes DIR/<stem>.pvd and DIR/<stem>_NNNN.vtu with the arrays as point data (Float32;
// NaN kept as NaN), one .vtu per time.
void write_vtk_scalar_series(const std::string& dir, const std::string& stem, const Mesh& mesh,
                             const std::vector<double>& times, const std::vector<VtkScalarArray>& arrays);

}  // namespace tvf
