#pragma once
// Dense, temporally coherent texture animation of a time-varying field on a planar
// domain (DESIGN §8; paper §9, Figs. 4, 6, 8), by texture advection in the manner of
// image-based flow visualization (IBFV, van Wijk 2002): each frame is the previous frame
// advected along the field plus a little fresh noise,
//     F_k(x) = (1 − α)·F_{k−1}(x − d_k(x)) + α·N_k(x),
// d_k the displacement of one frame (backward semi-Lagrangian step with the midpoint
// rule, bilinear sampling) and N_k a noise of cells (noise_scale pixels) that switch on
// and off, each with its own random phase, over noise_period frames. N_k is averaged
// along each pixel's step, so that injecting it once a frame leaves no stripes across
// the streaks. Texture therefore moves with the flow and streaks form along it; nothing
// jumps from frame to frame. Displacements follow the field's direction at one speed
// (TextureSpeed::uniform) or its speed, scaled once for the whole animation so that
// relative speeds across space and time are kept (TextureSpeed::physical).
//
// Pixels: the domain's bounding box scaled to `size` pixels on its long side, y up in the
// domain and down in the image; pixel (i, j) has its centre at
// (xmin + (i + ½)/s, ymax − (j + ½)/s), s = pixels per unit. Pixels outside the domain
// (planar meshes that are not rectangles) are drawn in `background`.
//
// The pictures shown are, by default, a short line integral convolution (Cabral & Leedom
// 1993) of the advected texture along the field: "LIC over advected noise". Advection
// gives the coherence in time, the convolution smooths the grain of IBFV's blending into
// the even streaks of the paper's figures (docs/architecture.md, "Texture animation").
#include "tvf/analysis/topology.h"
#include "tvf/core/error.h"
#include "tvf/field/field.h"
#include "tvf/integrate/dye.h"
#include "tvf/mesh/tangent_bundle.h"
#include "tvf/render/dye_pictures.h"
#include "tvf/render/image.h"

#include <array>
#include <atomic>
#include <cstdint>
#include <functional>
#include <optional>
#include <string>
#include <utility>
#include <vector>

namespace tvf {

struct PeriodicOrbits;  // integrate/periodic_orbits.h

// How far the texture moves where the field is fast or slow.
enum class TextureSpeed {
  uniform,   // every pixel moves pixels_per_frame along the field's direction, however
             // weak the field (only exact zeros, under 1e-12 of the typical speed, stay
             // still): streaks everywhere, also far out in an element's falloff, as in
             // the paper's pictures
  physical,  // proportional to |V|: the typical (90th-percentile) speed moves
             // pixels_per_frame per frame of the field
};

struct TextureOptions {
  int size = 1024;               // pixels on the long side
  double alpha = 0.1;            // weight of the fresh noise per frame (IBFV's α)
  double noise_scale = 0.0;      // noise cell size in pixels; 0: size / 256 (at least 1)
  int lic = -1;                  // the pictures are line integral convolutions of the
                                 // advected texture, lic pixels each way; -1: size / 64;
                                 // 0: the advected texture itself (faster, grainier)
  int noise_period = 16;         // frames of a noise cell's on/off cycle
  TextureSpeed speed = TextureSpeed::uniform;
  double pixels_per_frame = 0.0; // displacement per frame of the field (see TextureSpeed);
                                 // 0: size / 128
  int warmup = 0;                // frames advected at the first frame's time before the
                                 // first picture; 0: ⌈3/α⌉ (a steady texture from frame 0)
  double contrast = 1.0;         // output contrast (1: ±2.2 standard deviations fill 0–255)
  std::uint64_t seed = 1;        // noise seed
  std::uint32_t background = 0x00FFFFFF;
};

// Checks the options shared by the planar and the surface animators (one sentence naming
// the option, tvf::Error) and resolves lic = -1 (automatic) from the size; `max_size`
// bounds `size` (the surface renderer's offscreen buffers allow less than the plane).
void check_texture_options(TextureOptions& o, int max_size);

// The simulation: frame after frame of the animation. Throws tvf::Error on a domain that
// is not planar, or options out of range (naming the option).
class TextureAnimator {
public:
  TextureAnimator(const TangentBundle& bundle, const Field& field, const TextureOptions& options = {});

  int width() const { return width_; }
  int height() const { return height_; }
  double pixels_per_unit() const { return ppu_; }
  // The typical speed of the field (90th percentile of |V| over all frames and vertices).
  double typical_speed() const { return p90_; }
  // Image position (pixels, x right, y down) of a domain point, and back.
  Vec2 to_pixel(const Vec2& x) const;

  // Advances the texture by one frame from its current time to t (the first call
  // warms up at t and advects nothing before it). Frames may go backwards in time.
  void advance(double t);
  double time() const { return t_; }
  // The texture (width × height, row-major, top row first), values about [0, 1].
  const std::vector<float>& texture() const { return tex_; }
  // The current frame as a gray picture (contrast stretched). Reuses a buffer of the
  // animator: not to be called from two threads at once.
  Image picture() const;

private:
  void compute_velocity(double t, double dt);
  void blend(int k);
  // Mean and standard deviation of an image over the domain's pixels.
  std::pair<double, double> statistics(const std::vector<float>& image) const;

  const TangentBundle& bundle_;
  const Field& field_;
  TextureOptions o_;
  int width_ = 0, height_ = 0;
  double ppu_ = 1, time_scale_ = 1, p90_ = 0;
  Vec2 lo_, hi_;
  std::vector<int> face_;        // per pixel, -1 outside the domain
  std::vector<float> bary_;      // per pixel, 3 barycentric coordinates
  std::vector<float> vel_;       // displacement of one frame in pixels: all dx, then all dy
  std::vector<float> dir_;       // unit direction of the field: all x, then all y
  std::vector<float> tex_, next_;
  mutable std::vector<float> lic_;
  std::vector<float> phase_;     // per noise cell, in [0, 1)
  int cells_x_ = 0, cells_y_ = 0;
  std::vector<float> lattice_;   // noise cell intensities of the current step
  double cell_ = 1;
  long step_ = 0;
  double t_ = 0;
  bool started_ = false;
  double mean_ = 0.5, sd_ = 0.1;
};

// Singularity markers over a picture, in the paper's colours (green source, red sink,
// blue saddle, magenta center and foci): the singularities of the field at time t.
void draw_singularities(Image& image, const TextureAnimator& animator, const TangentBundle& bundle,
                        const Field& field, double t);

// The singularity paths up to time t drawn as trails (each path's samples with t' ≤ t),
// in the colour of their type: where every singularity has been so far (paper Fig. 8).
void draw_singularity_paths(Image& image, const TextureAnimator& animator, const Topology& topology, double t);

// The periodic orbits of the field frame nearest to t as closed curves (attracting orange,
// repelling teal, on a dark casing) and the Hopf events within two frame steps of t as
// black diamond outlines round the focus (integrate/periodic_orbits.h). Drawn after the
// singularity dots.
void draw_orbits(Image& image, const TextureAnimator& animator, const PeriodicOrbits& orbits, const Field& field,
                 double t);

// Evenly spaced streamlines of the field at time t (integrate/evenly_spaced.h), drawn as
// thin dark lines, `separation` apart in pixels (0: 3 % of the picture's long side).
// Placed anew for each picture, so in an animation they do not move with the texture:
// meant for still pictures.
void draw_streamlines(Image& image, const TextureAnimator& animator, const TangentBundle& bundle,
                      const Field& field, double t, double separation = 0.0);

// How a surface is looked at (render/surface_texture.h). The camera frames the mesh's
// bounding box from `direction` (from the mesh's centre towards the eye) with `up`
// pointing up in the picture.
struct SurfaceView {
  Vec3 direction{1.0, -0.6, 0.5};
  Vec3 up{0.0, 0.0, 1.0};
  double fov = 30.0;        // vertical field of view, degrees
  double spacing = 1.0;     // texture samples apart on the screen, pixels
  long max_samples = 4'000'000;  // the subdivision is capped so that samples stay below this
  bool lighting = true;     // headlight shading
};

struct TextureAnimationOptions {
  TextureOptions texture;
  int frames = 0;                 // pictures over the field's time range; 0: the field's frames
  int first = 0;                  // first and last picture written (inclusive); last -1: to the end
  int last = -1;
  bool overlay_singularities = false;
  bool overlay_paths = false;     // the singularity paths so far (analysis/topology.h)
  bool overlay_streamlines = false;  // evenly spaced streamlines of each frame
  // Planar domains: the periodic orbits of the field frame nearest to each picture's t
  // (integrate/periodic_orbits.h; attracting orange, repelling teal) and each Hopf event
  // as a black diamond outline within two frame steps of its time.
  bool overlay_orbits = false;
  // Dye released continuously from each seed since the start of the animation (picture 0,
  // whatever first is; a release every quarter of the pictures' spacing), carried from
  // picture to picture (integrate/dye.h) and drawn in each picture as its streakline, a
  // line in the seed's colour (red, blue, green, … : dye_colour) with a dark casing, the
  // seed a disc (render/dye_pictures.h): smoke injected into the flow. Planar domains: x, y
  // in the domain (z ignored); surfaces: a point on or near the surface (within three edge
  // lengths), moved onto it, the dye drawn on the surface (hidden behind it).
  std::vector<Vec3> streakline_seeds;
  // Timelines: segments [a, b] drawn at the field's first time (ends placed as the seeds;
  // on surfaces snapped onto it, trace_timeline), carried by the same flow as the dye and
  // drawn in light blue in every picture: material lines stretching with the flow.
  std::vector<std::array<Vec3, 2>> timelines;
  // How far the field carries the dye (> 0): its velocities times this, as the particle
  // renderer's time_scale (designed fields are often slow; the texture itself moves at
  // its own speed, TextureOptions::pixels_per_frame).
  double dye_time_scale = 1.0;
  std::string frames_dir;         // PNG frames frame_00000.png … (empty: none)
  std::string video;              // MP4 file (empty: none)
  // Every picture also handed here, in order (k, the picture), from whichever thread
  // makes it: pictures without files (the Python module's render_texture). With it set,
  // frames_dir and video may both be empty.
  std::function<void(int k, const Image& picture)> on_picture;
  SurfaceView surface;            // surfaces only (render/surface_texture.h): the camera, samples
  int streamline_seeds = 150;     // surfaces only: streamlines of the overlay
  double fps = 25.0;
  std::function<void(int done, int total)> progress;
  // When set, checked before each picture (from another thread: Python's progress
  // returning False, Ctrl-C): once true the animation stops with RenderCancelled, and
  // nothing is written (the PNG folder is staged, a partial MP4 removed).
  const std::atomic<bool>* cancel = nullptr;
};

// The dye of a texture animation of `pictures` pictures (TextureAnimationOptions::
// streakline_seeds; empty without seeds), released from the field's first time and
// carried by `carried` (the field, its velocities times dye_time_scale), and how
// it is drawn on pictures width × height pixels (pixels_per_unit: world to pixels at the
// framed distance; the line is broken where particles are over 24 pixels apart). Throws
// tvf::Error on a seed outside the domain or too far from the surface.
std::optional<DyeInjector> texture_dye(const TangentBundle& bundle, const Field& carried,
                                       const TextureAnimationOptions& options, int pictures);
// The field times options.dye_time_scale, when there are seeds and the scale is not 1
// (tvf::Error on a scale that is not a positive number).
std::optional<Field> texture_dye_field(const Field& field, const TextureAnimationOptions& options);
DyeStyle texture_dye_style(int width, int height, double pixels_per_unit);

// Thrown by write_texture_animation when TextureAnimationOptions::cancel became true.
class RenderCancelled : public Error {
public:
  RenderCancelled() : Error("rendering cancelled") {}
};
// Throws RenderCancelled when options.cancel is set and true.
inline void check_render_cancelled(const TextureAnimationOptions& options) {
  if (options.cancel && options.cancel->load()) throw RenderCancelled();
}

struct TextureAnimationReport {
  int frames = 0;                 // pictures made
  int width = 0, height = 0;
  double seconds = 0;             // total
  double warmup_seconds = 0;      // of which the warm-up and the first picture
  double texture_seconds = 0;     // and the texture and pictures of the other frames
  std::vector<std::string> files; // what was written
  std::vector<TimelineRecord> timelines;  // each of options.timelines over the pictures
};

// Renders the animation and writes PNG frames (into a folder that appears complete or not
// at all) and/or an MP4: on planar domains TextureAnimator's pictures, on surfaces
// SurfaceTextureAnimator's (render/surface_texture.h) seen through options.surface. Throws tvf::Error on bad options (naming them) or a failed write.
TextureAnimationReport write_texture_animation(const TangentBundle& bundle, const Field& field,
                                               const TextureAnimationOptions& options);

}  // namespace tvf
