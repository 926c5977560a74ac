#pragma once
// Particles with self-spin on a triangle-mesh surface (DESIGN §8; paper §9, Fig. 15): the
// leaves of particles.h carried along the field's pathlines on the surface
// (integrate/pathline.h: RK4 steps walked across faces, integrate/surface_walk.h), so a
// leaf is always a point of the mesh (a face and barycentric coordinates). Its up
// direction keeps a constant angle to the advection direction in the tangent plane:
// up = cos(angle)·d + sin(angle)·(n × d), d = V/|V| in world coordinates, n the face's
// normal; where |V| is below 1e-12 of the largest |V| a leaf keeps its last up.
// Leaves are placed uniformly by area; one carried onto a boundary edge comes back at a
// random place by area. Pictures: the mesh seen from a camera (SurfaceView of
// texture_animation.h) in a pale ground colour, each leaf a tapered shape along its up
// direction drawn on the surface by the offscreen renderer (hidden where the surface is in
// front of it).
#include "tvf/field/field.h"
#include "tvf/field/field_sampler.h"
#include "tvf/mesh/tangent_bundle.h"
#include "tvf/render/image.h"
#include "tvf/render/mesh_renderer.h"
#include "tvf/render/particles.h"
#include "tvf/render/texture_animation.h"

#include <cstdint>
#include <memory>
#include <random>
#include <vector>

namespace tvf {

struct SurfaceLeaf {
  long id = 0;                 // respawns get new ids
  SurfacePoint where;
  Vec3 position{0, 0, 0};      // world, on the mesh
  Vec3 up{1, 0, 0};            // unit, world, in the plane of where.face
  double angle = 0;            // constant angle from the advection direction to up
  std::uint32_t colour = 0;
};

class SurfaceParticleSystem {
public:
  // options.size is the leaf length in pixels of the picture (image_size × image_size) at
  // the framed distance. Throws tvf::Error on a planar domain (ParticleSystem draws those)
  // or options out of range (naming the option).
  SurfaceParticleSystem(const TangentBundle& bundle, const Field& field, const ParticleOptions& options = {},
                        const SurfaceView& view = {});

  // Carries the leaves from the current time to t (the first call places them at t).
  void advance(double t);
  double time() const { return t_; }
  const std::vector<SurfaceLeaf>& leaves() const { return leaves_; }
  long respawned() const { return respawned_; }
  const Camera& camera() const { return camera_; }
  double pixels_per_unit() const { return ppu_; }
  // The leaves as the renderer's lines (a tapered body and a dark stem each).
  std::vector<RenderLine> leaf_lines() const;

private:
  SurfaceLeaf spawn(double t);
  void orient(SurfaceLeaf& leaf, double t) const;

  const TangentBundle& bundle_;
  const Field& field_;
  ParticleOptions o_;
  FieldSampler sampler_;
  Camera camera_;
  double ppu_ = 1, zero_speed_ = 0, t_ = 0;
  std::vector<double> cumulative_area_;
  std::vector<SurfaceLeaf> leaves_;
  std::mt19937_64 rng_;
  long next_id_ = 0, respawned_ = 0;
  bool started_ = false;
};

// write_particle_animation's work on a surface domain (it dispatches here).
AnimationReport write_surface_particle_animation(const TangentBundle& bundle, const Field& field,
                                                 const ParticleAnimationOptions& options);

}  // namespace tvf
