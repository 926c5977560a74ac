#pragma once
// Streamline deformation (paper §7, Fig. 12; DESIGN §5.4), the part of the deform generator
// that moves representative streamlines: each deform.streamlines[k] is traced in V(t0) from
// its seed (both ways, integrate/streamline.h) and moved at time t by its keyed similarity
// transform about the seed (translate, rotate, scale; linear in t from the identity at t0):
// - planar domains: in the plane;
// - surfaces: in the log-map chart around the seed (log_map.h; the seed is the curve's
//   centre, traced both ways from it). A point with log coordinates w goes to
//   T + s·e^{iθ}·w, T the key's translate (a world vector) projected onto the tangent plane
//   at the seed, θ counter-clockwise about the outward normal, and back onto the surface by
//   ChartInverse (the exponential map). The chart is inverted within a disc of half the
//   domain's diameter; the curve is traced within half that radius (on a unit sphere about
//   50° from the seed), so it can be moved and stretched, and a moved point that leaves the
//   disc is an error naming the streamline's keys.
// The moved curve's speeds are the traced speeds times s. The deform generator constrains
// each frame's solve with the moved curves' tangents (element_regions.h,
// constrain_polyline).
#include "tvf/scene/design_space.h"
#include "tvf/scene/scene.h"

#include <memory>
#include <span>
#include <vector>

namespace tvf {

struct MovedStreamline {
  std::vector<Vec3> points;    // world positions on the domain, ordered along the flow
  std::vector<double> speeds;  // speed at each point
  size_t seed = 0;             // index of the (moved) seed in points
};

// The `translate` of a deform.streamlines key that moves the streamline's seed to `to`
// (the designer's drag): on planar domains to − seed (z = 0); on surfaces the log
// coordinates of `to` in the chart around the seed that at() moves the curve in, minus
// the seed's own, as a world vector in the tangent plane of the seed's face, so that the
// key carries the seed onto `to` (both snapped to the surface first). Throws tvf::Error
// (one sentence) when `to` lies outside the disc of half the domain's diameter around the
// seed in which the chart is inverted.
Vec3 seed_translation(const DesignSpace& space, const Vec3& seed, const Vec3& to);

// The local coordinates of `to` in the chart around `at` in which an element at `at` is
// designed (element_regions.h): on planar domains (to − at).xy; on surfaces its log
// coordinates minus at's own, in the frame of at's face (both snapped to the surface). Its
// modulus is the geodesic distance, its argument the direction a bifurcation's `angle`
// names (the designer's Bifurcation drag: angle = arg, scale = modulus). Throws tvf::Error
// as seed_translation does beyond half the domain's diameter.
cplx chart_coordinates(const DesignSpace& space, const Vec3& at, const Vec3& to);

class StreamlineDeformation {
public:
  // `base`: V(t0), |V| values in vertex bases. `space` and `scene` must outlive the object.
  // Throws tvf::Error naming the scene and "deform.streamlines[k].seed" when a seed cannot
  // be traced.
  StreamlineDeformation(const DesignSpace& space, const Scene& scene, std::span<const cplx> base);
  ~StreamlineDeformation();
  StreamlineDeformation(const StreamlineDeformation&) = delete;
  StreamlineDeformation& operator=(const StreamlineDeformation&) = delete;

  size_t size() const { return lines_.size(); }
  // The streamlines at time t, one per deform.streamlines entry. Thread-safe. Throws
  // tvf::Error naming "deform.streamlines[k].keys" when a moved point leaves the chart.
  std::vector<MovedStreamline> at(double t) const;

private:
  struct Line;
  const DesignSpace& space_;
  const Scene& scene_;
  std::vector<std::unique_ptr<Line>> lines_;
};

}  // namespace tvf
