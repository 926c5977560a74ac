#pragma once
// Grass driven by a field (paper §9, Fig. 14): thousands of strands rooted on a planar
// domain (the ground, z = 0, z up), each a rigid skeleton of `segments` equal segments
// whose tip is pulled by an inverse-kinematics solve (FABRIK, Aristidou & Lasenby 2011)
// toward a target set by the field at its root:
//   - the wind strength s = min(1, |V(root, t)| / wind_speed)^response bends the strand so
//     that its tip tangent leans θ = s·bend from the vertical toward V (plus a small random
//     lean per strand, fixed for the whole animation); a response above 1 makes the grass
//     stiff, standing in a light breeze and lying down in a strong wind;
//   - the target is where the tip of a circular arc of the strand's length with that tip
//     angle would be: at angle θ/2 from the vertical, at distance L·sin(θ/2)/(θ/2).
// The solve starts from the previous frame's pose, so the animation is coherent. Roots
// never move and every segment keeps its length (each joint is placed at exactly that
// distance from the previous one along a unit vector).
//
// Rendering: lit lines with Cairo seen by a perspective camera over the ground (looking
// toward +y from the −y side, `elevation` degrees above the horizon; 90 is straight down):
// strands drawn far to near, each segment shaded by its tangent (Kajiya–Kay diffuse and
// specular for a sun high above, a little behind the viewer: bent strands catch it
// whichever way they lean, standing ones stay dark), darker toward the root, thinner toward
// the tip.
#include "tvf/field/field.h"
#include "tvf/mesh/tangent_bundle.h"
#include "tvf/render/image.h"
#include "tvf/render/painterly.h"

#include <cstdint>
#include <functional>
#include <memory>
#include <span>
#include <string>
#include <vector>

namespace tvf {

// FABRIK on a chain of joints with equal segment lengths: joints[0] is the root (kept),
// the last joint is pulled toward `target`. Stops when the tip is within `tolerance` of the
// target or after `max_iterations` (a target out of reach gives the straight chain
// pointing at it). Returns the iterations used.
struct IkResult {
  int iterations = 0;
  double tip_error = 0.0;  // |tip − target|
};
IkResult solve_fabrik(std::span<Vec3> joints, double segment_length, const Vec3& target, int max_iterations,
                      double tolerance);

struct GrassOptions {
  int count = 32000;
  int segments = 4;
  double length = 0.035;        // strand length, as a fraction of the domain's longer side
  double length_variation = 0.3;  // lengths spread uniformly over ±½ of this fraction
  double bend = 75.0;           // degrees: tip angle from the vertical at full wind
  double wind_speed = 0.0;      // |V| that bends fully; 0: the 99th percentile of |V| in the field
  double response = 1.0;        // exponent of the bend's response to |V| / wind_speed
  double lean = 8.0;            // degrees: random lean of each strand (0: none)
  int ik_iterations = 12;
  double ik_tolerance = 1e-3;   // tip error, as a fraction of the strand's length
  std::uint64_t seed = 1;
};

class Meadow {
public:
  // Throws tvf::Error on a surface domain, a field of another domain, or options out of
  // range (naming the option).
  Meadow(const TangentBundle& bundle, const Field& field, const GrassOptions& options = {});
  ~Meadow();
  Meadow(const Meadow&) = delete;
  Meadow& operator=(const Meadow&) = delete;

  // Solves every strand's pose for the field at time t (strands in parallel).
  void pose(double t);

  int strands() const;
  int joints_per_strand() const;                // segments + 1
  std::span<const Vec3> strand(int k) const;    // joints root → tip, world coordinates
  const Vec3& root(int k) const;
  double segment_length(int k) const;
  const Vec3& target(int k) const;              // the tip target of the last pose
  double wind_speed() const;                    // the |V| that bends fully
  const GrassOptions& options() const;
  const Mesh& mesh() const;

private:
  struct Impl;
  std::unique_ptr<Impl> impl_;
};

struct GrassRenderOptions {
  int image_size = 960;          // pixels on the long side
  double elevation = 50.0;       // camera degrees above the horizon (90: top-down)
  double field_of_view = 35.0;   // degrees, vertical
  double width = 0.05;           // blade width at the root, as a fraction of the strand length
  std::uint32_t sky = 0x00B8CCD8;
  std::uint32_t ground = 0x00302814;
};

// The camera and the drawing order of one meadow (fixed: roots do not move).
class GrassRenderer {
public:
  GrassRenderer(const Meadow& meadow, const GrassRenderOptions& options = {});
  ~GrassRenderer();
  GrassRenderer(const GrassRenderer&) = delete;
  GrassRenderer& operator=(const GrassRenderer&) = delete;
  int width() const;
  int height() const;
  // The meadow as it is posed now.
  Image picture() const;

private:
  struct Impl;
  std::unique_ptr<Impl> impl_;
};

struct GrassAnimationOptions {
  GrassOptions grass;
  GrassRenderOptions render;
  int frames = 0;                 // pictures over the field's time range; 0: the field's frames
  std::string frames_dir, video;  // PNG frames and/or MP4 (frame_output.h)
  double fps = 25.0;
  std::function<void(int done, int total)> progress;
};

// Poses and draws every picture; throws tvf::Error on bad options or a failed write
// (nothing partial is left).
AnimationReport write_grass_animation(const TangentBundle& bundle, const Field& field,
                                      const GrassAnimationOptions& options);

}  // namespace tvf
