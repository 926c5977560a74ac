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

// The distributed form (`mpirun -n K`, K > 1; docs/file_formats.md "VTK series"): each rank
// writes its piece of every frame, DIR/<stem>_NNNN_pR.vtu (R = `rank`): the vertices that
// `owner` (per vertex) gives it, the faces whose lowest vertex it owns, and the halo
// vertices of those faces that other ranks own. Point data "vector" and "magnitude" as
// above, "vertex" (Int32, the vertex's index in the whole mesh) and "vtkGhostType" (UInt8:
// 0 for the rank's own vertices, 1 = VTK's DUPLICATEPOINT for halo vertices).
void write_vtk_series_piece(const std::string& dir, const std::string& stem, const TangentBundle& bundle,
                            const Field& field, std::span<const int> owner, int rank);
// The same from the piece's values alone (a rank that holds only its share of the field):
// `values` is frames × the piece's points, frame-major, the points those that
// vtk_piece_points gives (the rank's own vertices and its faces' halo vertices, ascending).
std::vector<int> vtk_piece_points(const Mesh& mesh, std::span<const int> owner, int rank);
void write_vtk_series_piece(const std::string& dir, const std::string& stem, const TangentBundle& bundle,
                            const TimeSampling& time, std::span<const int> owner, int rank,
                            std::span<const cplx> values);
// Then one process writes DIR/<stem>_NNNN.pvtu (the `ranks` pieces of frame NNNN) and
// DIR/<stem>.pvd listing the .pvtu files with their times.
void write_vtk_parallel_series(const std::string& dir, const std::string& stem, const std::vector<double>& times,
                               int ranks);

// A per-vertex scalar of every frame: frames × |V| values, frame-major (e.g. FTLE).
struct VtkScalarArray {
  std::string name;
  std::span<const float> values;
};
// Writes DIR/<stem>.pvd and DIR/<stem>_NNNN.vtu with the arrays as point data (Float32;
// NaN kept as NaN), one .vtu per time, NNNN its entry of `numbers` (the field's frame, where
// only some frames are written) or, without them, 0, 1, ….
void write_vtk_scalar_series(const std::string& dir, const std::string& stem, const Mesh& mesh,
                             const std::vector<double>& times, const std::vector<VtkScalarArray>& arrays,
                             std::span<const int> numbers = {});

}  // namespace tvf
