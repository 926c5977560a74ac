#pragma once
// Pictures of a triangle mesh from a camera (DESIGN §8): per-vertex colours shaded by a
// headlight, with optional lines (streamlines, singularity paths) and round markers
// (singularities) drawn over it, rendered offscreen with OpenGL ES 3 through EGL on Mesa
// (the surfaceless platform, so no display or GPU is needed: llvmpipe renders on the
// CPU; docs/architecture.md, "Surface rendering") into an Image.
//
// Reusable for any coloured surface (texture animation, synthesized textures, terrain):
//     MeshRenderer renderer;                       // one OpenGL context
//     renderer.set_mesh(positions, faces);         // geometry, uploaded once
//     renderer.set_colors(colors);                 // per vertex, as often as they change
//     Image img = renderer.render(Camera::framing(lo, hi, {1, 0.5, 1}, {0, 0, 1}), opts);
// A MeshRenderer may be used from any thread, one call at a time (it makes its context
// current for each call and releases it after).
#include "tvf/core/types.h"
#include "tvf/mesh/mesh.h"
#include "tvf/render/image.h"

#include <cstdint>
#include <memory>
#include <span>
#include <vector>

namespace tvf {

// A perspective camera: eye looking at target, `up` giving the picture's up direction,
// fov_y the vertical field of view in degrees.
struct Camera {
  Vec3 eye{0, 0, 5};
  Vec3 target{0, 0, 0};
  Vec3 up{0, 1, 0};
  double fov_y = 30.0;

  // A camera that looks at the centre of the box [lo, hi] from `direction` (from the
  // target towards the eye), at the distance where the box's bounding sphere fits the
  // smaller of the picture's two fields of view for a picture of aspect width/height,
  // with `margin` (1: touching) around it. `up` is made perpendicular to direction
  // (another axis is used if they are parallel). Throws tvf::Error on a zero direction.
  static Camera framing(const Vec3& lo, const Vec3& hi, const Vec3& direction, const Vec3& up,
                        double aspect = 1.0, double fov_y = 30.0, double margin = 1.08);
  // The same, looking at the centre of the points' bounding box from the nearest distance
  // at which every point is inside the picture with `margin` (1.08: 8 % of the half-width
  // free around the farthest-out point): tighter than the box's bounding sphere.
  static Camera framing(std::span<const Vec3> points, const Vec3& direction, const Vec3& up, double aspect = 1.0,
                        double fov_y = 30.0, double margin = 1.08);

  // Column-vector matrices: clip = projection · view · (x, 1).
  Eigen::Matrix4d view() const;
  Eigen::Matrix4d projection(double aspect, double near, double far) const;
  // Where a world point lands in a width × height picture: pixel x (right), y (down)
  // from the top-left corner, and the distance along the viewing direction.
  Vec3 project(const Vec3& x, int width, int height) const;
};

// A polyline drawn over the mesh, `width` pixels wide, with an optional dark casing (a
// line twice as wide drawn under it, so coloured lines stay readable on any colour).
struct RenderLine {
  std::vector<Vec3> points;
  std::uint32_t color = 0x000000;  // 0xRRGGBB
  double width = 2.0;              // pixels
  bool casing = false;
  // Drawn under every other line: without writing depth, after the casings and before the
  // others (a sketch under the curve traced from it). The mesh still hides it.
  bool underlay = false;
};

// A disc facing the camera, `radius` pixels, with a black outline `outline` pixels wide.
struct RenderMarker {
  Vec3 position{0, 0, 0};
  std::uint32_t color = 0x000000;
  double radius = 5.0;
  double outline = 1.3;  // 0: none (the dots along a curve: outlined, they were a black band)
};

struct RenderOptions {
  int width = 800;
  int height = 800;
  std::uint32_t background = 0xFFFFFF;
  int samples = 4;          // multisample anti-aliasing (0 or 1: none); clamped to what OpenGL offers
  bool lighting = true;     // headlight diffuse shading of the vertex colours
  double ambient = 0.35;    // light on faces seen edge-on, in [0, 1]
  bool two_sided = true;    // back faces lit like front faces (open meshes)
};

class MeshRenderer {
public:
  // Creates the offscreen OpenGL context. Throws tvf::Error when offscreen OpenGL cannot
  // be had (naming what failed: no EGL surfaceless platform, no OpenGL ES 3 context).
  MeshRenderer();
  ~MeshRenderer();
  MeshRenderer(const MeshRenderer&) = delete;
  MeshRenderer& operator=(const MeshRenderer&) = delete;

  // Geometry: positions and triangles (indices into positions); vertex normals are the
  // area-weighted face normals. Colours are reset to mid gray. Throws tvf::Error on an
  // index out of range or a position that is not finite.
  void set_mesh(std::span<const Vec3> positions, std::span<const Face> faces);
  void set_mesh(const Mesh& mesh) { set_mesh(mesh.positions(), mesh.faces()); }
  // One colour per vertex (0xRRGGBB). Throws tvf::Error on a size mismatch.
  void set_colors(std::span<const std::uint32_t> colors);
  int num_vertices() const;

  // The mesh (if any), then the lines and markers, from `camera`. Lines and markers are
  // hidden where the mesh is in front of them (they are drawn with a small depth bias so
  // that those lying on the surface show). Throws tvf::Error on bad options.
  Image render(const Camera& camera, const RenderOptions& options, std::span<const RenderLine> lines = {},
               std::span<const RenderMarker> markers = {});

  // The OpenGL renderer's name (e.g. "llvmpipe (LLVM 15.0.6, 256 bits)").
  std::string renderer_name() const;

private:
  struct Impl;
  std::unique_ptr<Impl> impl_;
};

// Grey value v in [0, 1] times an RGB colour: helpers for building vertex colours.
inline std::uint32_t scale_color(std::uint32_t c, double v) {
  auto ch = [&](int shift) {
    const double x = static_cast<double>((c >> shift) & 0xFFu) * v;
    return static_cast<std::uint32_t>(x < 0 ? 0 : x > 255 ? 255 : x + 0.5);
  };
  return (ch(16) << 16) | (ch(8) << 8) | ch(0);
}

}  // namespace tvf
