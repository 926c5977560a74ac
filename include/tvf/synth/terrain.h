#pragma once
// Evolving terrain (paper Fig. 12): a height map synthesized from a height-map exemplar
// (synth/planar_synthesis.h, synth/surface_synthesis.h) displaces a mesh, frame after
// frame; the meshes go to files that other tools (Blender, ParaView, MeshLab) read.
//  - Planar domains: a grid over the domain's bounding box whose z is the height.
//  - Surfaces: every vertex moves along its normal by its height.
// Heights are exemplar values in [0, 1]; `height_scale` says how far height 1 reaches as
// a fraction of the domain's size (long side of the box, or the bounding-box diagonal of a
// surface).
#include "tvf/mesh/mesh.h"
#include "tvf/mesh/tangent_bundle.h"
#include "tvf/core/atomic_output.h"

#include <memory>
#include <span>
#include <string>
#include <vector>

namespace tvf {

// A grid mesh of `resolution` vertices on the long side over [lo, hi], z = height·z_scale,
// the height read bilinearly from a w × h grid of values (rows top to bottom, i.e. y down
// from hi.y; pixel centres as in planar_synthesis.h).
Mesh height_field_mesh(std::span<const float> height, int w, int h, const Vec2& lo, const Vec2& hi, int resolution,
                       double z_scale);

// The mesh with vertex i moved by height[i]·amount along its normal (heights around 0.5
// move out and in by about the same amount: displacement (height − 0.5)·amount, so the
// mean surface stays where it was).
Mesh displace_along_normals(const TangentBundle& bundle, std::span<const float> height, double amount);

// Binary little-endian PLY with per-vertex colours (RGB in [0, 1], one per vertex),
// written atomically. Throws tvf::Error naming the file.
void write_colored_ply(const std::string& path, const Mesh& mesh, std::span<const Vec3> colours);

// Colours of a terrain for meshes and pictures: low ground green-brown, high ground sand.
Vec3 terrain_colour(double height);

struct TerrainMeshOptions {
  std::string format = "obj";  // obj or ply (PLY carries per-vertex colours by height)
  int resolution = 128;        // planar grids: vertices on the long side
  double height_scale = 0.1;   // height 1 as a fraction of the domain's size
};

// Per-frame meshes frame_00000.obj … in a folder; nothing appears until finish() (staged
// with core/atomic_output.h's OutputStage).
class TerrainMeshWriter {
public:
  // Throws tvf::Error for a bad format or resolution, or a folder that cannot be made.
  TerrainMeshWriter(const std::string& folder, const Mesh& domain, const TerrainMeshOptions& options);
  ~TerrainMeshWriter();
  // Planar: a height grid (w × h) over the domain's box.
  void add_grid(std::span<const float> height, int w, int h);
  // Surface: per-vertex heights, displaced along the normals of `bundle`.
  void add_surface(const TangentBundle& bundle, std::span<const float> height);
  std::vector<std::string> finish();

private:
  void save(const Mesh& mesh, std::span<const float> vertex_heights);
  std::string folder_;
  const Mesh& domain_;
  TerrainMeshOptions options_;
  std::unique_ptr<OutputStage> stage_;
  int count_ = 0;
};

}  // namespace tvf
