#pragma once
// The dye of integrate/dye.h drawn over the renderers' pictures (issue 20): each seed's
// streakline as a line in the seed's colour through its particles (oldest first, broken
// where particles left the domain), and the seed as a disc. The dye fades with age: its
// opacity (planar) or its colour's distance from the ground (surfaces) falls linearly
// from 1 at the seed to 1 − fade at age fade_age and beyond, so the smoke thins out as it
// drifts away. Where the flow has pulled two consecutive particles farther apart than
// max_gap the line is broken (a straight chord across a stretched streak would cross
// places no dye has been); particles left alone between breaks are drawn as dots on
// planar pictures. Lines are stroked in runs of equal fading (16 steps). The injector's
// timelines are drawn the same way in light blue, unfaded.
//  - draw_dye: Cairo onto a planar picture (the particle and texture renderers), a
//    domain point x at pixel to_pixel(x).
//  - dye_overlay: lines and markers for MeshRenderer::render on surfaces (hidden where the
//    surface is in front of them).
#include "tvf/integrate/dye.h"
#include "tvf/render/image.h"
#include "tvf/render/mesh_renderer.h"

#include <cstdint>
#include <functional>
#include <vector>

namespace tvf {

// The colour of seed s (0xRRGGBB): red, blue, green, purple, orange, teal, then again.
std::uint32_t dye_colour(size_t s);

struct DyeStyle {
  double width = 2.0;               // line width, pixels
  double fade = 0.0;                // in [0, 1]: how much the oldest dye fades (0: not at all)
  double fade_age = 1.0;            // the age (time since release) of full fading; > 0
  bool casing = false;              // a dark line under the dye (readable over a texture)
  bool halo = false;                // planar: a wide faint line under the dye (smoke)
  double max_gap = 0.0;             // world distance between particles above which the line
                                    // is broken; 0: never
  std::uint32_t ground = 0xFFFFFF;  // surfaces: the colour fading dye turns towards
};

// Throws tvf::Error on a style out of range (naming the field).
void draw_dye(Image& image, const DyeInjector& dye, const std::function<Vec2(const Vec2&)>& to_pixel,
              const DyeStyle& style);
void dye_overlay(const DyeInjector& dye, const DyeStyle& style, std::vector<RenderLine>& lines,
                 std::vector<RenderMarker>& markers);

}  // namespace tvf
