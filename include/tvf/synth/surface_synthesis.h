#pragma once
// Field-guided texture synthesis on a mesh surface (paper §9, Figs. 3 and 9): the same
// texture optimization as the plane (synth/texture_optimization.h, options in
// synth/planar_synthesis.h), on samples of the surface: the vertices of its faces
// subdivided `density` times per edge (mesh/face_subdivision.h; density 1: the mesh's own
// vertices), so that the texture can be finer than the mesh. The field is resampled at the
// samples through FieldSampler (in the original face, then in the sample's tangent basis);
// the synthesis, its meshes and pictures then use the sample mesh, and "vertex" below means
// a vertex of it. Cost grows with the samples (about 20 µs of CPU per sample and frame).
//
// Neighbourhoods: around every vertex, a size × size grid of taps `spacing` apart in the
// tangent plane, its rows along the field's direction at the vertex (the exemplar's x
// axis) and its columns along that direction turned clockwise (seen from outside, so the
// picture is not mirrored). The grid is laid on the surface by walking
// (integrate/surface_walk.h): from the vertex along the rows, then from each row point
// along the columns, each step one spacing long and carried into the faces it crosses by
// the discrete connection — the grid follows geodesics, it is not a projection. A tap
// reads the vertex values of the face it lands in with barycentric weights.
//
// Levels: the same vertices at every level; level l uses spacing texel·2^l and the
// exemplar halved l times (the multi-resolution of Kwatra et al. 2005 by neighbourhood
// scale, since a mesh has no pyramid of its own). The first frame runs every level coarse
// to fine from random exemplar pixels; later frames start from the previous frame
// advected along the field (a backward walk by the midpoint rule, barycentric read) and
// run the finest `frame_levels` levels with it as a soft target.
//
// The samples are per-vertex colours (or heights) of the sample mesh: meshes with colours go to PLY files
// (synth/terrain.h's write_colored_ply); pictures come from a SurfaceRenderer, a function
// (mesh, per-vertex colours) → Image that the caller supplies (the mesh renderer).
#include "tvf/field/field.h"
#include "tvf/mesh/face_subdivision.h"
#include "tvf/mesh/tangent_bundle.h"
#include "tvf/render/image.h"
#include "tvf/synth/exemplar.h"
#include "tvf/synth/planar_synthesis.h"
#include "tvf/synth/texture_optimization.h"

#include <functional>
#include <memory>
#include <string>
#include <vector>

namespace tvf {

// The field at the vertices of a subdivision of its mesh (`samples` the subdivided mesh's
// bundle): FieldSampler in the original face at each frame, projected onto the new vertex's
// tangent plane with its length kept. Used by SurfaceSynthesizer for density > 1.
Field resample_field(const TangentBundle& bundle, const Field& field, const TangentBundle& samples,
                     const FaceSubdivision& subdivision);

class SurfaceSynthesizer {
public:
  // Throws tvf::Error on options out of range or an exemplar too small for the levels.
  SurfaceSynthesizer(const TangentBundle& bundle, const Field& field, const Exemplar& exemplar,
                     const SynthesisOptions& options = {});
  ~SurfaceSynthesizer();

  int channels() const;
  double texel() const;  // world length of one exemplar pixel at the finest level
  int density() const;   // samples per original edge (options.density, or the automatic one)
  // The mesh of the samples (the input mesh when density is 1) and its tangent bundle.
  const Mesh& sample_mesh() const;
  const TangentBundle& sample_bundle() const;
  const SynthesisFrameReport& advance(double t);
  double time() const;
  // samples × channels floats, sample-major (the sample mesh's vertex order).
  const std::vector<float>& values() const;
  // RGB colours per sample (gray for one channel).
  std::vector<Vec3> colours() const;
  // The neighbourhoods of the finest level at the current time (for tests and tools).
  const Neighbourhoods& neighbourhoods() const;

private:
  struct Impl;
  std::unique_ptr<Impl> impl_;
};

// A picture of a mesh with per-vertex colours (RGB in [0, 1]); supplied by the caller.
using SurfaceRenderer = std::function<Image(const Mesh& mesh, const std::vector<Vec3>& colours)>;

struct SurfaceSynthesisAnimationOptions {
  SynthesisOptions synthesis;
  int frames = 0;                // pictures over the field's time range; 0: the field's frames
  bool terrain = false;          // 1-channel exemplar as heights that displace the mesh
  double height_scale = 0.03;    // terrain: displacement of height 1 as a fraction of the
                                 // mesh's bounding-box diagonal
  std::string meshes_dir;        // a mesh per frame (frame_00000.ply …, colours per vertex)
  std::string mesh_format = "ply";  // ply (with colours) or obj (terrain only: no colours)
  SurfaceRenderer renderer;      // pictures (frames_dir / video) need one
  std::string frames_dir;
  std::string video;
  double fps = 25.0;
  std::function<void(int done, int total)> progress;
};

// Writes per-frame meshes (the sample mesh) and, with a renderer, PNG frames and/or an MP4
// (the renderer is handed the sample mesh and its colours). Every output
// appears complete or not at all. Throws tvf::Error on bad options or a failed write.
SynthesisAnimationReport write_surface_synthesis(const TangentBundle& bundle, const Field& field,
                                                 const Exemplar& exemplar,
                                                 const SurfaceSynthesisAnimationOptions& options);

}  // namespace tvf
