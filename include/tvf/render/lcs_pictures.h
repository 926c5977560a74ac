#pragma once
// Pictures of the Lagrangian descriptors (integrate/ftle.h, integrate/streakline.h):
//  - a per-vertex scalar (an FTLE frame) colour-mapped (magma: black, purple, orange, pale
//    yellow) with a colour bar and its range under the picture. Planar domains are drawn
//    with Cairo pixel by pixel (the domain's bounding box scaled to `size` pixels on its
//    long side, y up, values interpolated barycentrically in each face; NaN drawn in
//    nan_color); surfaces through MeshRenderer (mesh_renderer.h) with the values as vertex
//    colours, seen as SurfaceView says.
//  - curves (streaklines, timelines) over the field at time t: on planar domains over the
//    LIC texture of the field at t (TextureAnimator warmed up at t), on surfaces over the
//    mesh in light gray; seeds marked as discs.
#include "tvf/field/field.h"
#include "tvf/mesh/tangent_bundle.h"
#include "tvf/render/image.h"
#include "tvf/render/texture_animation.h"

#include <cmath>
#include <cstdint>
#include <span>
#include <string>
#include <utility>
#include <vector>

namespace tvf {

// The magma colour map at s in [0, 1] (clamped), 0x00RRGGBB.
std::uint32_t magma(double s);

// The 1st and 99th percentiles of the finite values (0, 1 when there are none): the colour
// range scalar_picture takes by default; give it to every frame of a series so that the
// frames compare.
std::pair<double, double> colour_range(std::span<const float> values);

struct ScalarPictureOptions {
  int size = 800;                        // pixels on the long side
  double lo = std::nan(""), hi = std::nan("");  // colour range; NaN: the 1st / 99th percentile
  std::uint32_t nan_color = 0x9A9A9A;    // where the value is NaN (the flow left the domain)
  bool legend = true;                    // a colour bar with the range and the label, below
  std::string label;                     // e.g. "forward FTLE, t = 0, T = 10"
  SurfaceView surface;                   // surfaces: the camera
};

// Throws tvf::Error on a size outside [16, 16384] or values of the wrong size.
Image scalar_picture(const TangentBundle& bundle, std::span<const float> values, const ScalarPictureOptions& options);

struct CurvePictureOptions {
  int size = 800;
  std::uint32_t color = 0xE8402A;  // the curves
  double line_width = 0.0;         // pixels; 0: size / 300 (at least 1.5)
  bool dots = true;                // a dot at every point of a curve (the released particles)
  // Curves drawn first, under the others, three times as wide and without dots (a sketched
  // streakline the traced one should follow: tvf streaklines --element).
  std::vector<std::vector<Vec3>> under;
  std::uint32_t under_color = 0x3FD0F0;
  TextureOptions texture;          // planar: the LIC texture under the curves (its size is `size`)
  SurfaceView surface;             // surfaces: the camera
  // Surfaces: look from the curves' side, along the mean of the surface's normals at their
  // points and the `under` curves' (the whole mesh still framed; surface.direction where they wrap round it so
  // that the normals cancel), instead of surface.direction alone, whose fixed default hid
  // a timeline on the bunny's neck. Off when the caller gives a view (tvf streaklines --view).
  bool face_curves = true;
};

// Draws curves (planar world positions; consecutive points joined, a dark casing under the
// coloured line, dots at the points when `dots`) and seeds (white discs) onto a picture of
// `animator` (texture_animation.h). Used by curve_picture and by the texture animation's
// streakline overlay.
void draw_curves(Image& image, const TextureAnimator& animator, const std::vector<std::vector<Vec3>>& curves,
                 std::span<const Vec3> seeds, std::uint32_t color, double line_width, bool dots);

// Curves (world positions; consecutive points joined) and seeds over the field at time t.
Image curve_picture(const TangentBundle& bundle, const Field& field, double t,
                    const std::vector<std::vector<Vec3>>& curves, std::span<const Vec3> seeds,
                    const CurvePictureOptions& options);

}  // namespace tvf
