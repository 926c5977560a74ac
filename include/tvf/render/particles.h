#pragma once
// Particles with self-spin (DESIGN §8; paper §9, Fig. 15): oriented sprites (leaves)
// carried by a time-varying field on a planar domain along its pathlines
// (integrate/pathline.h), each keeping a constant angle between its up direction and the
// advection direction at its position: up = R(angle)·V/|V|. As the flow turns, the
// sprites turn with it — the spinning of the paper's leaves. Where the field vanishes
// (|V| below 1e-12 of its largest |V|) a sprite keeps its last orientation. A sprite
// carried out of the domain comes back at a random place of the least occupied cell of a
// coarse grid, so the count stays constant and the picture evenly covered.
#include "tvf/field/field.h"
#include "tvf/field/field_sampler.h"
#include "tvf/integrate/dye.h"
#include "tvf/mesh/tangent_bundle.h"
#include "tvf/render/image.h"
#include "tvf/render/painterly.h"
#include "tvf/render/texture_animation.h"

#include <array>
#include <cmath>
#include <cstdint>
#include <functional>
#include <memory>
#include <optional>
#include <string>
#include <vector>

namespace tvf {

struct ParticleOptions {
  int count = 2000;
  double size = 10.0;            // sprite length in pixels
  double spin = std::nan("");    // angle (radians) from the advection direction to up; NaN: random per sprite
  int image_size = 800;          // pixels on the long side
  std::uint64_t seed = 1;
  std::uint32_t background = 0x00C8DCE4;
};

struct Particle {
  long id = 0;                   // respawns get new ids
  SurfacePoint where;
  Vec2 position;                 // domain coordinates
  double angle = 0;              // constant angle from the advection direction to up
  Vec2 up{1, 0};                 // unit, domain coordinates
  std::uint32_t colour = 0;
};

class ParticleSystem {
public:
  // Throws tvf::Error on a surface domain or options out of range (naming the option).
  ParticleSystem(const TangentBundle& bundle, const Field& field, const ParticleOptions& options = {});
  ~ParticleSystem();
  ParticleSystem(const ParticleSystem&) = delete;
  ParticleSystem& operator=(const ParticleSystem&) = delete;

  // Carries the particles from the current time to t (the first call places them at t).
  void advance(double t);
  double time() const;
  const std::vector<Particle>& particles() const;
  long respawned() const;
  int width() const;
  int height() const;
  Image picture() const;

private:
  struct Impl;
  std::unique_ptr<Impl> impl_;
};

struct ParticleAnimationOptions {
  ParticleOptions particles;
  int frames = 0;                 // pictures over the field's time range; 0: the field's frames
  std::string frames_dir, video;
  double fps = 25.0;
  // How far the field carries things per picture: the velocities are multiplied by this, so
  // over the clip they travel as the field would carry them over time_scale × its time range,
  // while the field itself still changes at its own pace. > 0.
  double time_scale = 1.0;
  SurfaceView surface;            // surfaces only (render/surface_particles.h): the camera
  // Dye injected at each seed from the first picture on (integrate/dye.h: released every
  // dye_release_spacing, carried frame to frame by the same time-scaled field as the
  // leaves, dropped when it leaves the domain) and drawn over the leaves in every picture
  // as smoke in the seed's colour, fading with age (render/dye_pictures.h). Planar
  // domains: x, y in the domain (z ignored); surfaces: a point on or near the surface
  // (within three edge lengths), moved onto it. tvf::Error before anything is written
  // otherwise.
  std::vector<Vec3> dye_seeds;
  // Timelines: segments [a, b] at the field's first time carried with the dye and drawn
  // in light blue (TextureAnimationOptions::timelines).
  std::vector<std::array<Vec3, 2>> timelines;
  double dye_release_spacing = 0.0;  // time; 0: a quarter of the pictures' spacing
  std::function<void(int done, int total)> progress;
};

// The dye of a particle animation of `pictures` pictures (nothing without seeds): the
// injector write_particle_animation uses, for callers that draw their own pictures.
std::optional<DyeInjector> particle_dye(const TangentBundle& bundle, const Field& carried,
                                        const ParticleAnimationOptions& options, int pictures);

// On a surface domain the leaves are carried on the surface (render/surface_particles.h).
AnimationReport write_particle_animation(const TangentBundle& bundle, const Field& field,
                                         const ParticleAnimationOptions& options);

}  // namespace tvf
