#pragma once
// Painterly animation (DESIGN §8; paper §9, Figs. 1 and 17): brush strokes over a user's
// picture, oriented along a time-varying field on a planar domain and carried by it.
//
// The domain's bounding box is stretched onto the picture. Strokes are placed one per
// cell of a grid whose cells hold `density` strokes' worth of paint (cell side
// √(width·length / density)), at a random point of the cell. Each frame:
//   - a stroke whose centre lies where the field applies (inside the domain and on the
//     white part of the mask; everywhere without a mask) is carried by the pathline
//     through its centre from the previous frame's time to this one (integrate/pathline.h),
//     so the strokes move coherently with the flow; strokes elsewhere stay put;
//   - coverage is kept even: a cell left without a stroke centre gets a new stroke, a cell
//     holding more than `max_per_cell` loses its oldest strokes;
//   - every stroke is drawn with Cairo as a curve along the streamline of the current
//     frame through its centre (integrate/streamline.h), `length` pixels long, `width`
//     pixels wide, round-capped, in the picture's colour at its centre (a little jitter
//     of brightness per stroke). Strokes where the field does not apply keep the shape
//     they had when they were made. Strokes are drawn in a fixed random depth order, over
//     the picture itself (which shows through any gap).
#include "tvf/field/field.h"
#include "tvf/field/field_sampler.h"
#include "tvf/integrate/dye.h"
#include "tvf/mesh/tangent_bundle.h"
#include "tvf/render/image.h"

#include <cstdint>
#include <functional>
#include <memory>
#include <string>
#include <vector>

namespace tvf {

struct PainterlyOptions {
  double stroke_width = 6.0;    // pixels
  double stroke_length = 24.0;  // pixels, along the streamline
  double density = 2.0;         // strokes covering a pixel on average, in (0, 50]
  int max_per_cell = 3;         // more stroke centres in a cell than this: the oldest go
  double jitter = 0.08;         // per-stroke brightness jitter (fraction), in [0, 1]
  std::uint64_t seed = 1;
};

struct BrushStroke {
  long id = 0;                  // order of creation
  float depth = 0;              // drawing order (ascending)
  Vec2 centre;                  // pixels
  std::vector<Vec2> path;       // pixels, the curve drawn
  std::uint32_t colour = 0;     // 0x00RRGGBB
  float shade = 1;              // brightness factor (jitter)
  bool moving = false;          // the field applies at its centre
};

class PainterlyAnimator {
public:
  // `mask`: empty (width 0) for none; any size (scaled onto the picture); the field applies
  // where its luminance is above one half. Throws tvf::Error on a surface domain or options
  // out of range (naming the option).
  PainterlyAnimator(const TangentBundle& bundle, const Field& field, Image picture, Image mask,
                    const PainterlyOptions& options = {});
  ~PainterlyAnimator();
  PainterlyAnimator(const PainterlyAnimator&) = delete;
  PainterlyAnimator& operator=(const PainterlyAnimator&) = delete;

  int width() const;
  int height() const;
  // Moves the strokes from the current time to t (the first call places them at t), then
  // rebalances coverage and reshapes the strokes along the field at t.
  void advance(double t);
  double time() const;
  const std::vector<BrushStroke>& strokes() const;
  // Strokes added and removed by rebalancing since construction.
  long added() const;
  long removed() const;
  // Whether the field applies at a pixel position.
  bool moves_at(const Vec2& pixel) const;
  // The current frame: the picture painted over with the strokes.
  Image picture() const;

private:
  struct Impl;
  std::unique_ptr<Impl> impl_;
};

struct PainterlyAnimationOptions {
  PainterlyOptions painterly;
  int frames = 0;                 // pictures over the field's time range; 0: the field's frames
  std::string frames_dir;         // PNG frames frame_00000.png … (empty: none)
  std::string video;              // MP4 file (empty: none)
  double fps = 25.0;
  // How far the field carries things per picture: the velocities are multiplied by this, so
  // over the clip they travel as the field would carry them over time_scale × its time range,
  // while the field itself still changes at its own pace. > 0.
  double time_scale = 1.0;
  std::function<void(int done, int total)> progress;
};

struct AnimationReport {
  int frames = 0;
  int width = 0, height = 0;
  double seconds = 0;
  std::vector<std::string> files;  // what was written
  std::vector<TimelineRecord> timelines;  // particles: each --timeline over the pictures
};

// Renders the animation to PNG frames and/or MP4. Throws tvf::Error on bad options or a
// failed write (nothing partial is left).
AnimationReport write_painterly_animation(const TangentBundle& bundle, const Field& field, const Image& picture,
                                          const Image& mask, const PainterlyAnimationOptions& options);

}  // namespace tvf
