#pragma once
// Dense, temporally coherent texture animation on a triangle-mesh surface (DESIGN §8;
// paper §9, Figs. 3 and 9), the surface counterpart of texture_animation.h, shown from a
// camera through the offscreen OpenGL renderer (mesh_renderer.h).
//
// The texture lives on texture samples: the vertices of the mesh with every face split
// regularly into n² small triangles (n from the wanted sample spacing in pixels of the
// picture), so that samples lie about `spacing` pixels apart on the screen whatever the
// mesh's own resolution. Each sample is a point of the mesh (face, barycentric
// coordinates). Every frame, as on the plane (IBFV, van Wijk 2002),
//     T_k(p) = (1 − α)·T_{k−1}(p − d_k(p)) + α·N_k(p):
// the sample's source p − d_k(p) is found by walking back along the surface
// (integrate/surface_walk.h) with the midpoint rule, its value interpolated linearly in the
// small triangle holding it; N_k is a noise of cubic cells (noise_scale pixels; default
// the sample spacing, or size/512 when larger) of world
// space that switch on and off with random phases over noise_period frames, averaged along
// the step. The pictures are a short line integral convolution of T along the field on the
// surface (walks of the unit direction), contrast stretched, as the vertex colours of the
// subdivided mesh, lit by a headlight.
#include "tvf/analysis/topology.h"
#include "tvf/field/field.h"
#include "tvf/field/field_sampler.h"
#include "tvf/mesh/face_subdivision.h"
#include "tvf/mesh/tangent_bundle.h"
#include "tvf/render/mesh_renderer.h"
#include "tvf/render/texture_animation.h"

#include <cstdint>
#include <vector>

namespace tvf {

// The simulation on the surface. TextureOptions' lengths in pixels (noise_scale,
// pixels_per_frame, lic) are pixels of the picture at the framed distance; `size` is the
// picture's side (square). Throws tvf::Error on a planar domain (use TextureAnimator) or
// options out of range (naming them).
class SurfaceTextureAnimator {
public:
  SurfaceTextureAnimator(const TangentBundle& bundle, const Field& field, const TextureOptions& options = {},
                         const SurfaceView& view = {});

  int width() const { return size_; }
  int height() const { return size_; }
  const Camera& camera() const { return camera_; }
  double pixels_per_unit() const { return ppu_; }
  int subdivision() const { return n_; }
  // The texture samples: world positions, places on the mesh, and small triangles.
  const std::vector<Vec3>& sample_positions() const { return positions_; }
  const std::vector<SurfacePoint>& sample_points() const { return points_; }
  const std::vector<Face>& sample_triangles() const { return triangles_; }

  // As TextureAnimator::advance: one frame from the current time to t (the first call
  // warms up at t).
  void advance(double t);
  double time() const { return t_; }
  // The texture at the samples (about [0, 1]).
  const std::vector<float>& texture() const { return tex_; }
  // The texture's value at a point of the mesh (linear in the small triangle holding it).
  float texture_at(const SurfacePoint& p) const;
  // The shown values: the line integral convolution of the texture (or the texture when
  // lic is 0), contrast stretched into [0, 1].
  std::vector<float> shown() const;
  // Vertex colours (gray) of the subdivided mesh for the current frame.
  std::vector<std::uint32_t> colors() const;

private:
  // The sample at lattice point (i, j) of face f (FaceSubdivision's grid).
  int sample_of(int f, int i, int j) const {
    return grid_[static_cast<size_t>(f) * static_cast<size_t>(per_face_) +
                 static_cast<size_t>(FaceSubdivision::local_index(n_, i, j))];
  }
  float noise(const Vec3& a, const Vec3& b, long step) const;

  const TangentBundle& bundle_;
  const Field& field_;
  TextureOptions o_;
  SurfaceView view_;
  Camera camera_;
  int size_ = 800;
  double ppu_ = 1, p90_ = 0, time_scale_ = 0, cell_ = 1;
  int n_ = 1, per_face_ = 3;
  std::vector<int> grid_;             // per face, (n+1)(n+2)/2 sample ids
  std::vector<Vec3> positions_;
  std::vector<SurfacePoint> points_;
  std::vector<Face> triangles_;
  std::vector<float> tex_, next_;
  std::vector<cplx> values_;          // vertex values of the current step
  long step_ = 0;
  double t_ = 0;
  bool started_ = false;
  std::uint64_t seed_hash_ = 0;  // the noise seed, mixed
};

// The same animation computed in image space, for speed (Laramee, Jobard & Hauser 2003,
// "Image space based visualization of unsteady flow on surfaces"; van Wijk's IBFVS): the
// surface is rasterized once, for the fixed camera, into a grid of texels (the picture's
// pixels, or one every `spacing` pixels), each holding the place on the mesh it sees
// (face, perspective-correct barycentric coordinates, world position; -1 where no surface
// is seen). Every frame the field is interpolated at the texels and projected onto the
// picture plane; the texture is advected there as on the plane,
//     T_k(x) = (1 − α)·T_{k−1}(x − d_k(x)) + α·N_k(x),
// d_k the screen image of the surface displacement (midpoint rule, bilinear reads over
// texels that see the surface), with the world-space noise of SurfaceTextureAnimator.
// A source that falls off the surface, or onto another layer of it (its texel sees a
// point farther from the expected one than the step plus two texels), keeps the texel's
// own value: texture is born at silhouettes and occlusions. The line integral convolution
// walks the projected unit direction for the same world length as on the surface. Memory
// and work per frame are a few arrays of the picture's size, whatever the mesh and the
// number of frames. Shading, anti-aliased silhouettes and overlays come from the offscreen
// renderer (composite()).
class SurfaceImageAnimator {
public:
  SurfaceImageAnimator(const TangentBundle& bundle, const Field& field, const TextureOptions& options = {},
                       const SurfaceView& view = {});

  int width() const { return size_; }
  int height() const { return size_; }
  int grid() const { return g_; }  // texels on a side
  const Camera& camera() const { return camera_; }
  double pixels_per_unit() const { return ppu_; }
  // Per texel (row-major, top row first): the face seen (-1: none) and the point seen.
  const std::vector<int>& texel_faces() const { return face_; }
  Vec3 texel_position(size_t k) const { return pos_[k].cast<double>(); }

  void advance(double t);  // as SurfaceTextureAnimator::advance
  double time() const { return t_; }
  const std::vector<float>& texture() const { return tex_; }  // per texel, about [0, 1]
  // Per texel: the line integral convolution of the texture, contrast stretched into
  // [0, 1]; texels that see no surface take the mean of those around them that do (0.5
  // when none), for the anti-aliased silhouette.
  std::vector<float> shown() const;
  // The picture: per pixel dark + g·(lit − dark), with lit
  // and dark the renderer's pictures of the mesh in white and in black (same camera,
  // width() × height()) and g the shown value there (bilinear when grid() ≠ width()).
  Image composite(const Image& lit, const Image& dark) const;

private:
  void velocities(double t, double dt);
  bool bilinear2(double x, double y, const std::vector<float>& v, Vec2& out) const;
  template <class Get>
  bool bilinear(double x, double y, Get&& get, float& out) const;

  const TangentBundle& bundle_;
  const Field& field_;
  TextureOptions o_;
  SurfaceView view_;
  Camera camera_;
  int size_ = 512, g_ = 512;
  double ppu_ = 1, p90_ = 0, time_scale_ = 0, cell_ = 1, focal_ = 1;
  Eigen::Matrix3d rot_ = Eigen::Matrix3d::Identity();  // world → view axes
  std::vector<int> face_;
  std::vector<Eigen::Vector3f> bary_, pos_, eye_;   // eye_: view-space position
  std::vector<float> vel_, dir_, step_len_;          // per texel: 2 + 2 + 1
  std::vector<Eigen::Vector3f> world_;               // field per vertex, world, this step
  std::vector<float> phase_, cell_texels_;          // per texel: noise cell phase, cells per texel
  std::vector<float> tex_, next_;
  long step_ = 0;
  double t_ = 0;
  bool started_ = false;
  std::uint64_t seed_hash_ = 0;
};

// The renderer's lines for the singularity paths up to time t (trails in the colours of
// their types, with a dark casing) and markers for the singularities of the field at t.
std::vector<RenderLine> singularity_path_lines(const Topology& topology, double t, double width);
std::vector<RenderMarker> singularity_markers(const TangentBundle& bundle, const Field& field, double t,
                                              double radius);
// Streamlines of the field at t from `seeds` evenly spread over the surface (dark lines).
std::vector<RenderLine> surface_streamline_lines(const TangentBundle& bundle, const Field& field, double t,
                                                 int seeds, double width, std::uint64_t seed = 1);

// The animation on a surface: write_texture_animation's work for a surface domain, after
// it has checked the options; pictures first..last of total over the field's time range.
TextureAnimationReport write_surface_texture_animation(const TangentBundle& bundle, const Field& field,
                                                       const TextureAnimationOptions& options, int first, int last,
                                                       int total);

}  // namespace tvf
