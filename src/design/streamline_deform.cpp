#include "tvf/design/streamline_deform.h"

#include "tvf/core/error.h"
#include "tvf/integrate/streamline.h"
#include "tvf/mesh/chart_inverse.h"

#include <fmt/format.h>

#include <algorithm>
#include <optional>

namespace tvf {

namespace {

// A keyed similarity transform of a streamline at time t: translate, rotate, scale about
// the seed, interpolated linearly from the identity at t0. translate: (x, y) on planar
// domains, a world vector on surfaces.
struct Similarity {
  Vec3 translate = Vec3::Zero();
  double rotate = 0;
  double scale = 1;
};
Similarity similarity_at(const std::vector<StreamlineKey>& keys, double t0, double t) {
  double ta = t0;
  Similarity a;
  for (const StreamlineKey& k : keys) {
    const double tb = k.t;
    const Similarity b{k.translate, k.rotate, k.scale};
    if (t <= tb) {
      if (tb <= ta) return b;
      const double w = std::clamp((t - ta) / (tb - ta), 0.0, 1.0);
      return {(1 - w) * a.translate + w * b.translate, (1 - w) * a.rotate + w * b.rotate,
              (1 - w) * a.scale + w * b.scale};
    }
    ta = tb;
    a = b;
  }
  return a;
}

}  // namespace

namespace {

// chart_coordinates; `seed` says whom the error names (a streamline's seed, or a point).
cplx chart_coordinates_of(const DesignSpace& space, const Vec3& at, const Vec3& to, bool seed) {
  if (space.planar()) {
    const cplx w(to.x() - at.x(), to.y() - at.y());
    if (!std::isfinite(w.real()) || !std::isfinite(w.imag()))
      throw Error(fmt::format("the translation from ({:.4g}, {:.4g}) to ({:.4g}, {:.4g}) is too large to represent",
                              at.x(), at.y(), to.x(), to.y()));
    return w;
  }
  const SurfacePoint p = space.locate(at);
  LocalChart chart;
  space.log_map().compute(p, chart);
  const ChartInverse inverse(space.bundle(), chart, 0.5 * space.diameter());
  const SurfacePoint q = space.locate(to);
  const cplx w = inverse.coords(q);
  // Beyond the inverted faces (far from `at`, or past the cut locus) the chart's
  // coordinates do not lead back to the point.
  const auto back = inverse.locate(w);
  if (!back || (surface_position(space.mesh(), *back) - surface_position(space.mesh(), q)).norm() >
                   1e-3 * space.diameter())
    throw Error(seed ? fmt::format("the point ({:.4g}, {:.4g}, {:.4g}) is too far from the seed ({:.4g}, {:.4g}, "
                                   "{:.4g}): a streamline's seed moves within {:.3g} of it (half the domain's "
                                   "diameter), where its log-map chart is used",
                                   to.x(), to.y(), to.z(), at.x(), at.y(), at.z(), inverse.radius())
                     : fmt::format("the point ({:.4g}, {:.4g}, {:.4g}) is too far from ({:.4g}, {:.4g}, {:.4g}): the "
                                   "log-map chart around a point is used within {:.3g} of it (half the domain's "
                                   "diameter)",
                                   to.x(), to.y(), to.z(), at.x(), at.y(), at.z(), inverse.radius()));
  return w - inverse.coords(p);
}

}  // namespace

cplx chart_coordinates(const DesignSpace& space, const Vec3& at, const Vec3& to) {
  return chart_coordinates_of(space, at, to, false);
}

Vec3 seed_translation(const DesignSpace& space, const Vec3& seed, const Vec3& to) {
  const cplx w = chart_coordinates_of(space, seed, to, true);
  if (space.planar()) return {w.real(), w.imag(), 0.0};
  return space.bundle().face_to_world(space.locate(seed).face, w);
}

struct StreamlineDeformation::Line {
  Streamline traced;
  // Surfaces: the chart around the seed, its inverse and the traced points' log coordinates.
  SurfacePoint seed;
  LocalChart chart;
  std::optional<ChartInverse> inverse;
  std::vector<cplx> coords;
};

StreamlineDeformation::~StreamlineDeformation() = default;

StreamlineDeformation::StreamlineDeformation(const DesignSpace& space, const Scene& scene,
                                             std::span<const cplx> base)
    : space_(space), scene_(scene) {
  if (!scene.deform) return;
  const std::vector<DeformStreamline>& streamlines = scene.deform->streamlines;
  const Mesh& mesh = space.mesh();
  for (size_t k = 0; k < streamlines.size(); ++k) {
    const Vec3 x = streamlines[k].seed;
    auto line = std::make_unique<Line>();
    try {
      if (space.planar()) {
        line->traced = trace_streamline(space.bundle(), base, x);
      } else {
        line->seed = space.locate(x);
        space.log_map().compute(line->seed, line->chart);
        line->inverse.emplace(space.bundle(), line->chart, 0.5 * space.diameter());
        // Trace within the inner half of the chart's disc, so the moved curve has room.
        const ChartInverse& inverse = *line->inverse;
        const double reach = 0.5 * inverse.radius();
        StreamlineOptions options;
        options.accept = [&](const Vec3& p) { return std::abs(inverse.coords(space.locate(p))) <= reach; };
        line->traced = trace_streamline(space.bundle(), base, line->seed, options);
        for (const SurfacePoint& q : line->traced.where) line->coords.push_back(inverse.coords(q));
      }
    } catch (const Error& e) {
      throw_input_error(scene.label(), fmt::format("deform.streamlines[{}].seed", k), e.what());
    }
    if (line->traced.points.size() < 2)
      throw_input_error(scene.label(), fmt::format("deform.streamlines[{}].seed", k),
                        fmt::format("the streamline from {} stops at once (a singularity or the boundary of the "
                                    "base field there)",
                                    space.planar() ? fmt::format("({}, {})", x.x(), x.y())
                                                   : fmt::format("({}, {}, {})", x.x(), x.y(), x.z())));
    (void)mesh;
    lines_.push_back(std::move(line));
  }
}

std::vector<MovedStreamline> StreamlineDeformation::at(double t) const {
  const std::vector<DeformStreamline>& streamlines = scene_.deform->streamlines;
  const double t0 = scene_.time.t0;
  std::vector<MovedStreamline> out(lines_.size());
  for (size_t k = 0; k < lines_.size(); ++k) {
    const Line& line = *lines_[k];
    const Streamline& traced = line.traced;
    const Similarity sim = similarity_at(streamlines[k].keys, t0, t);
    const cplx rot = std::polar(sim.scale, sim.rotate);
    MovedStreamline& m = out[k];
    m.seed = traced.seed;
    for (size_t q = 0; q < traced.points.size(); ++q) m.speeds.push_back(sim.scale * traced.speeds[q]);
    if (space_.planar()) {
      const Vec3& seed = traced.points[traced.seed];
      for (const Vec3& p : traced.points) {
        const cplx rel(p.x() - seed.x(), p.y() - seed.y());
        const cplx moved = cplx(seed.x() + sim.translate.x(), seed.y() + sim.translate.y()) + rot * rel;
        m.points.emplace_back(moved.real(), moved.imag(), 0);
      }
      continue;
    }
    // In the chart around the seed: log coordinates w ↦ T + s·e^{iθ}·w, back to the surface.
    const cplx shift = space_.bundle().world_to_face(line.seed.face, sim.translate);
    const cplx origin = line.coords[traced.seed];
    for (size_t q = 0; q < traced.points.size(); ++q) {
      const cplx w = shift + origin + rot * (line.coords[q] - origin);
      const auto p = line.inverse->locate(w);
      if (!p)
        throw_input_error(scene_.label(), fmt::format("deform.streamlines[{}].keys", k),
                          fmt::format("at t = {:.3g} the moved streamline leaves the disc of radius {:.3g} around "
                                      "its seed in which its log-map chart is used; move or turn it less",
                                      t, line.inverse->radius()));
      m.points.push_back(surface_position(space_.mesh(), *p));
    }
  }
  return out;
}

}  // namespace tvf
