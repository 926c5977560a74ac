#pragma once
// Field-guided texture synthesis on a planar domain (paper §9, Figs. 3 and 9 in the
// plane): texture optimization (synth/texture_optimization.h) over a pixel grid whose
// neighbourhoods are turned so that the exemplar's x axis follows the field's direction,
// animated with the temporal coherence of Kwatra et al. 2007: each frame starts from the
// previous frame advected along the field (semi-Lagrangian, midpoint rule, bilinear) and
// keeps it as a soft target, so the texture moves with the flow instead of being
// synthesized anew.
//
// Pixels: the domain's bounding box scaled to `size` pixels on its long side, y up in the
// domain and down in the image; pixel (i, j) has its centre at
// (xmin + (i + ½)/s, ymax − (j + ½)/s), s = pixels per unit. One exemplar pixel is one
// output pixel (scale the exemplar to change the texture's size). Pixels outside a
// non-rectangular domain are synthesized like the others and drawn in `background`.
//
// Levels: a pyramid of grids (each half the last), the exemplar halved with them. The
// first frame is made coarse to fine from exemplar pixels at random; later frames run
// only the finest `frame_levels` levels, each started from the advected previous frame
// plus the change the coarser level made (so fine detail is carried, not blurred).
//
// Renewal: the deformation of the carried texture since it was formed (the Jacobian of the
// advection map, composed frame to frame) is tracked per pixel; where its singular values
// say that elements were stretched or squeezed by more than max_distortion along some axis
// (the shear of a vortex's rim, the spreading of a source, the squeeze of a sink), cells of
// the picture cross-fade to fresh exemplar texture over renew_frames frames while it moves
// on with the flow (see renew_deformed in the source).
#include "tvf/field/field.h"
#include "tvf/mesh/tangent_bundle.h"
#include "tvf/render/image.h"
#include "tvf/synth/exemplar.h"
#include "tvf/synth/texture_optimization.h"

#include <cstdint>
#include <functional>
#include <memory>
#include <string>
#include <vector>

namespace tvf {

struct SynthesisOptions {
  int size = 512;               // planar: pixels on the long side of the domain
  int levels = 3;               // pyramid levels of the first frame (coarse to fine)
  int frame_levels = 2;         // levels run on each later frame (the finest ones)
  int neighbourhood = 7;        // neighbourhood size in samples (odd)
  int stride = 2;               // planar: neighbourhood centres every `stride` pixels
                                // (levels of at most 128² pixels use every pixel)
  int iterations_first = 5;     // E/M iterations per level on the first frame
  int iterations = 2;           // and on later frames
  double temporal_weight = 0.6; // λ: weight of the advected previous frame
  double pixels_per_frame = 0;  // motion: the typical (90th-percentile) speed moves this many
                                // pixels (surfaces: texels) per frame of the field;
                                // 0: size / 256 planar, on surfaces one mean edge length
                                // of the input mesh (whatever the sample density)
  double texel = 0;              // surfaces: world length of one exemplar pixel; 0: the
                                // samples' mean spacing (the sample mesh's mean edge length)
  int density = 0;              // surfaces: samples per mesh edge, every face split into
                                // density² triangles (1: a sample per vertex); 0: automatic,
                                // the smallest density giving 60,000 samples (at most 8)
  double max_distortion = 1.6;  // planar: renew texture stretched or squeezed along some axis
                                // by more than this factor since it formed (0: never)
  int renew_frames = 8;         // planar: frames of the cross-fade to fresh texture
  int pca_dimensions = 16;     // search: PCA dimensions, kd-tree candidates re-ranked in full,
  int candidates = 4;          // and nanoflann's approximation (synth/texture_optimization.h)
  float search_eps = 1.0f;
  std::uint64_t seed = 1;
  std::uint32_t background = 0x00FFFFFF;
};

// The exemplar at o.levels resolutions (finest first, each half the last) and a
// neighbourhood search index per level; throws tvf::Error when a level is smaller than a
// neighbourhood. Shared by planar and surface synthesis.
void build_exemplar_pyramid(const Exemplar& e, const SynthesisOptions& o, std::vector<Exemplar>& exemplars,
                            std::vector<std::unique_ptr<ExemplarIndex>>& indices);

// What one frame cost and how well it matches the exemplar.
struct SynthesisFrameReport {
  double seconds = 0;
  double patch_distance = 0;    // finest level's OptimizeReport::patch_distance
  double uncovered = 0;
  double reseeded = 0;          // planar: fraction of pixels that started renewing this frame
  double renewing = 0;          // planar: fraction of pixels cross-fading to fresh texture
  double distortion = 1;        // planar: 90th percentile over the domain of the carried
                                // texture's distortion max(σ1, 1/σ2) since it formed
  int levels = 0;
};

class PlanarSynthesizer {
public:
  // Throws tvf::Error on a domain that is not planar, an exemplar too small for the
  // levels, or options out of range (naming the option).
  PlanarSynthesizer(const TangentBundle& bundle, const Field& field, const Exemplar& exemplar,
                    const SynthesisOptions& options = {});
  ~PlanarSynthesizer();

  int width() const;
  int height() const;
  int channels() const;
  double pixels_per_unit() const;

  // Synthesizes the frame at time t: the first call from scratch, later calls by carrying
  // the last frame along the field from its time to t and optimizing.
  const SynthesisFrameReport& advance(double t);
  double time() const;
  // The texture: width × height × channels floats, row-major, top row first.
  const std::vector<float>& texture() const;
  // True for pixels whose centre lies in the domain.
  bool inside(int i, int j) const;
  // The field's unit direction at pixel (i, j) at the current time, in image coordinates
  // (x right, y down); (0, 0) outside the domain or where the field vanishes.
  std::array<float, 2> direction(int i, int j) const;
  // Colour (3 channels) or gray (1 channel) picture; outside pixels in `background`.
  Image picture() const;

private:
  struct Impl;
  std::unique_ptr<Impl> impl_;
};

// Hillshading of a height field (width × height values in [0, 1], rows top to bottom):
// a gray-brown relief lit from the north-west, `relief` pixels of height per unit value.
Image hillshade(const std::vector<float>& height, int width, int height_px, double relief);

// The rendering loop of `tvf render synth` on a planar domain.
struct SynthesisAnimationOptions {
  SynthesisOptions synthesis;
  int frames = 0;               // pictures over the field's time range; 0: the field's frames
  bool terrain = false;         // 1-channel exemplar as a height map: hillshaded pictures
  double relief = 0;            // terrain: hillshade relief (0: size / 8)
  std::string frames_dir;       // PNG frames frame_00000.png … (empty: none)
  std::string video;            // MP4 (empty: none)
  std::string meshes_dir;       // terrain: a displaced grid mesh per frame (empty: none)
  std::string mesh_format = "obj";  // obj or ply
  int mesh_resolution = 128;    // terrain meshes: vertices on the long side
  double height_scale = 0.1;    // terrain meshes: z of height 1, as a fraction of the domain's long side
  double fps = 25.0;
  std::function<void(int done, int total)> progress;
};

struct SynthesisAnimationReport {
  int frames = 0;
  int width = 0, height = 0;
  double seconds = 0;
  double first_frame_seconds = 0;
  double mean_frame_seconds = 0;   // of the frames after the first
  double mean_patch_distance = 0;  // over all frames
  std::vector<std::string> files;
};

// Writes PNG frames and/or an MP4 (and terrain meshes); every output appears complete or
// not at all. Throws tvf::Error on bad options or a failed write.
SynthesisAnimationReport write_planar_synthesis(const TangentBundle& bundle, const Field& field,
                                                const Exemplar& exemplar, const SynthesisAnimationOptions& options);

}  // namespace tvf
