#pragma once
// Fields for animation tools (DESIGN §12, "Export"; docs/user_guide.md, "Export for
// Houdini and Blender"). Both write one file per frame, NNNN the frame number from 0000,
// into a folder, staged and committed whole (core/atomic_output.h): an error leaves
// nothing behind.
//
// - OpenVDB (planar regular grids): velocity_NNNN.vdb, one Vec3f grid named "v" whose
//   voxel (ix, iy, 0) holds the world vector (vx, vy, 0) of grid vertex (ix, iy); the
//   transform maps voxel centres onto the vertices (voxel size = grid spacing, the
//   translation is the grid's min corner; a grid with different x and y spacing gets a
//   scale map with those spacings and z the x spacing). Every vertex is an active voxel.
//   Metadata: "time" (design time t of the frame, float), vector type
//   contravariant-relative (a velocity). Needs OpenVDB (Debian's libopenvdb-dev) at build
//   time; vdb_export_available() says whether this build has it.
// - PLY (any domain): velocity_NNNN.ply, binary little-endian, vertex properties
//   float x, y, z, vx, vy, vz (world vectors, the values of field.npy) and the faces as
//   "list uchar int vertex_indices"; a comment line carries the frame's time ("comment t
//   0.25").
#include "tvf/field/field.h"
#include "tvf/mesh/tangent_bundle.h"

#include <filesystem>
#include <vector>

namespace tvf {

// Whether this build can write OpenVDB files.
bool vdb_export_available();

// The regular lattice of a planar grid mesh (vertex index = iy·nx + ix): throws tvf::Error
// (naming `label`) when the mesh is not one.
struct GridLattice {
  int nx = 0, ny = 0;
  double x0 = 0, y0 = 0;  // position of vertex (0, 0)
  double hx = 0, hy = 0;  // spacing
};
GridLattice grid_lattice(const Mesh& mesh, const std::string& label);

// Writes DIR/velocity_NNNN.vdb for every frame; returns the paths. Throws tvf::Error
// (naming `label`) for a domain that is not a planar grid, or when this build has no
// OpenVDB.
std::vector<std::filesystem::path> write_vdb_sequence(const std::filesystem::path& dir, const TangentBundle& bundle,
                                                      const Field& field, const std::string& label = "field");

// Writes DIR/velocity_NNNN.ply for every frame; returns the paths.
std::vector<std::filesystem::path> write_ply_sequence(const std::filesystem::path& dir, const TangentBundle& bundle,
                                                      const Field& field);

}  // namespace tvf
