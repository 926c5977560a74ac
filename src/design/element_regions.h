#pragma once
// Internal to the design module: placing elements on the domain and turning them into
// constraints, shared by the generators (generate.cpp, keyframes.cpp, deform.cpp).
#include "tvf/core/error.h"
#include "tvf/scene/design_space.h"
#include "tvf/design/element_field.h"
#include "tvf/design/generate.h"
#include "tvf/solve/connection_laplacian.h"

#include <tbb/parallel_for.h>

#include <algorithm>
#include <chrono>
#include <cmath>
#include <limits>
#include <mutex>
#include <span>
#include <vector>

namespace tvf::detail {

// One element at one time on the domain: its basis field (with falloff) at every vertex,
// in each vertex's basis, and every vertex's distance from the element (geodesic on
// surfaces).
struct ElementOnDomain {
  std::vector<cplx> value;
  std::vector<double> distance;
  SurfacePoint at;  // the face holding p(t) (surfaces only)
};

// A log map kept with the point it is for: placing an element at the same point again
// (a static element, frame after frame) reuses it instead of three solves.
struct KeptChart {
  LocalChart chart;
  SurfacePoint at;  // face −1: none yet
  double extent = 0;
};

// `extent`: where the caller reads the placed element (its value and distance) at most;
// finite, the log map is made on a patch around the element only (LogMap::compute_local,
// issue 15), and beyond it the distance is +∞ and the value 0. The basis summation reads
// the falloff everywhere and keeps the default, the whole mesh's chart.
inline void place_state(const DesignSpace& space, ElementState st, double d, LocalChart& chart,
                 ElementOnDomain& out, KeptChart* kept = nullptr,
                 double extent = std::numeric_limits<double>::infinity()) {
  const Mesh& mesh = space.mesh();
  const auto nv = static_cast<size_t>(mesh.num_vertices());
  out.value.resize(nv);
  out.distance.resize(nv);
  out.at = space.locate(st.position);
  if (space.planar()) {
    // Local coordinates are the plane's own: w = x − p, frame = global.
    for (size_t v = 0; v < nv; ++v) {
      const Vec3& x = mesh.position(static_cast<int>(v));
      const cplx w(x.x() - st.position.x(), x.y() - st.position.y());
      out.value[v] = std::exp(-d * std::norm(w)) * st.field(w);
      out.distance[v] = std::abs(w);
    }
    return;
  }
  if (st.field.kind == LocalField::Kind::regular)
    st.field.velocity = space.bundle().world_to_face(out.at.face, st.velocity);
  const LocalChart* used = &chart;
  if (kept) {
    if (kept->at.face != out.at.face || kept->at.bary != out.at.bary || kept->extent != extent) {
      space.log_map().compute_local(out.at, extent, kept->chart);
      kept->at = out.at;
      kept->extent = extent;
    }
    used = &kept->chart;
  } else {
    space.log_map().compute_local(out.at, extent, chart);
  }
  for (size_t v = 0; v < nv; ++v) {
    const cplx w = used->coords[v];
    if (!std::isfinite(w.real())) {  // beyond compute_local's patch
      out.value[v] = cplx(0, 0);
      out.distance[v] = std::numeric_limits<double>::infinity();
      continue;
    }
    const double fall = std::exp(-d * std::norm(w));
    out.value[v] = fall < 1e-300 ? cplx(0, 0) : fall * st.field(w) * used->frame[v];
    out.distance[v] = std::abs(w);
  }
}

inline void place_element(const DesignSpace& space, const CompiledElement& el, double t, double d,
                   LocalChart& chart, ElementOnDomain& out, KeptChart* kept = nullptr,
                   double extent = std::numeric_limits<double>::infinity()) {
  place_state(space, el.at(t), d, chart, out, kept, extent);
}

// Imposes a placed element's own field on its region (DESIGN §5.2): the vertices within
// `radius`, and however small the radius, the element's face and its corners'
// neighbours, so that the constraints enclose its singularity. Overlapping regions add.
inline void constrain_region(const Mesh& mesh, const ElementOnDomain& placed, double radius,
                      std::span<char> fixed, std::span<cplx> values) {
  auto add = [&](size_t v) {
    if (!fixed[v]) values[v] = cplx(0, 0);
    fixed[v] = 1;
    values[v] += placed.value[v];
  };
  for (size_t v = 0; v < values.size(); ++v)
    if (placed.distance[v] <= radius) add(v);
  // The face's corners and their neighbours, each once.
  std::vector<int> near;
  for (int c : mesh.face(placed.at.face)) {
    near.push_back(c);
    for (int h : mesh.outgoing(c)) near.push_back(mesh.head(h));
  }
  std::sort(near.begin(), near.end());
  near.erase(std::unique(near.begin(), near.end()), near.end());
  for (int v : near)
    if (placed.distance[static_cast<size_t>(v)] > radius) add(static_cast<size_t>(v));
}

// The region radius of an element: solver.region_radius, or for a bifurcation at least
// 2·scale, so the region holds the pair it creates or cancels.
inline double region_radius(const Scene& scene, const CompiledElement& el) {
  double radius = scene.solver.region_radius;
  if (const auto* b = std::get_if<BifurcationElement>(&el.element())) radius = std::max(radius, 2 * b->scale);
  return radius;
}

// All active elements' regions at time t. `kept` (one per element), when given, keeps each
// element's last log map for the next call (a static element's is then made once instead
// of at every frame).
inline void constrain_elements(const DesignSpace& space, const Scene& scene,
                        const std::vector<CompiledElement>& elements, double t, double d,
                        std::span<char> fixed, std::span<cplx> values, std::vector<KeptChart>* kept = nullptr) {
  LocalChart chart;
  ElementOnDomain placed;
  if (kept) kept->resize(elements.size());
  for (size_t e = 0; e < elements.size(); ++e) {
    const CompiledElement& el = elements[e];
    if (!el.active(t)) continue;
    const double radius = region_radius(scene, el);
    place_element(space, el, t, d, chart, placed, kept ? &(*kept)[e] : nullptr, radius);
    constrain_region(space.mesh(), placed, radius, fixed, values);
  }
}

// Constraints that move continuously with their elements (issue 15): a vertex within an
// element's region radius r is fixed to the element's field, as constrain_region fixes it;
// one in a ramp of width w beyond r is pulled toward that field with a weight
// ψ = smoothstep((r + w − ρ)/w) of its distance ρ, as the penalty μ = d_v ψ/(1 − ψ) (d_v
// the Laplacian's diagonal: at ψ = ½ the pull equals the vertex's ties to its neighbours;
// μ → ∞, the fixed value, as ρ → r). Hard regions switch discretely as an element moves
// across vertices, and the far field, a harmonic fill, jumps with them (direction turns of
// 70° per frame at 65² for a steadily moving vortex); the ramp makes every frame's
// constraints, and so its field, a continuous function of the element's position.
// Overlaps add as in constrain_region: where ramps meet, the values are averaged by ψ.
// `kept` (one per element), when given, keeps each element's last log map for the next
// call (a static element's is then made once).
struct SmoothConstraints {
  std::vector<char> fixed;
  std::vector<cplx> values;
  std::vector<double> penalty;
};

inline void constrain_elements_smoothly(const DesignSpace& space, const Scene& scene,
                                        const std::vector<CompiledElement>& elements, double t, double d,
                                        const Eigen::VectorXd& diagonal, double ramp, SmoothConstraints& out,
                                        std::vector<KeptChart>* kept = nullptr) {
  const Mesh& mesh = space.mesh();
  const auto nv = static_cast<size_t>(mesh.num_vertices());
  std::vector<double> psi(nv, 0.0);
  std::vector<cplx> sum(nv, cplx(0, 0));
  std::vector<char> core(nv, 0);
  LocalChart chart;
  ElementOnDomain placed;
  std::vector<char> near(nv, 0);
  if (kept) kept->resize(elements.size());
  for (size_t e = 0; e < elements.size(); ++e) {
    const CompiledElement& el = elements[e];
    if (!el.active(t)) continue;
    const double radius = region_radius(scene, el);
    place_element(space, el, t, d, chart, placed, kept ? &(*kept)[e] : nullptr, radius + ramp);
    // However small the radius, the element's face's corners and their neighbours are in
    // its core, so that the constraints enclose its singularity (as constrain_region).
    std::fill(near.begin(), near.end(), 0);
    for (int c : mesh.face(placed.at.face)) {
      near[static_cast<size_t>(c)] = 1;
      for (int h : mesh.outgoing(c)) near[static_cast<size_t>(mesh.head(h))] = 1;
    }
    for (size_t v = 0; v < nv; ++v) {
      const double rho = placed.distance[v];
      double w = 0;
      if (rho <= radius || near[v]) {
        w = 1;
        core[v] = 1;
      } else if (rho < radius + ramp) {
        const double x = (radius + ramp - rho) / ramp;
        w = x * x * (3 - 2 * x);
      }
      if (w <= 0) continue;
      psi[v] += w;
      sum[v] += w * placed.value[v];
    }
  }
  out.fixed.assign(nv, 0);
  out.values.assign(nv, cplx(0, 0));
  out.penalty.assign(nv, 0.0);
  for (size_t v = 0; v < nv; ++v) {
    if (psi[v] <= 0) continue;
    const double p = std::min(1.0, psi[v]);
    out.values[v] = sum[v] / p;
    if (core[v] || p >= 1) {
      out.fixed[v] = 1;
    } else {
      out.penalty[v] = diagonal[static_cast<Eigen::Index>(v)] * p / (1 - p);
    }
  }
}

// Runs solve_frame(j) for every frame, in parallel or not, reporting progress.
template <class F>
void for_each_frame(int frames, const GenerateOptions& options, F&& solve_frame, const Field* field = nullptr) {
  std::mutex progress_mutex;
  int done = 0;
  auto run = [&](int j) {
    check_cancelled(options);
    solve_frame(j);
    if (options.progress) {
      std::lock_guard lock(progress_mutex);
      options.progress(++done, frames);
    }
  };
  // The frame a viewer shows first (GenerateOptions::first_frame), when the caller gives
  // the field the frames are written to.
  const int first = field && options.first_frame_done && options.first_frame >= 0 && options.first_frame < frames
                        ? options.first_frame
                        : -1;
  if (first >= 0) {
    run(first);
    check_cancelled(options);
    options.first_frame_done(first, field->frame(first));
  }
  auto rest = [&](int j) {
    if (j != first) run(j);
  };
  if (options.parallel) {
    tbb::parallel_for(0, frames, rest);
  } else {
    for (int j = 0; j < frames; ++j) rest(j);
  }
}

inline LaplacianWeights to_laplacian_weights(Weights w) {
  switch (w) {
    case Weights::cotan: return LaplacianWeights::cotan;
    case Weights::uniform: return LaplacianWeights::uniform;
    case Weights::mean_value: return LaplacianWeights::mean_value;
  }
  TVF_CHECK(false, "unknown weights");
}

inline std::vector<CompiledElement> compile(const Scene& scene) {
  std::vector<CompiledElement> elements;
  elements.reserve(scene.elements.size());
  for (const Element& e : scene.elements) elements.emplace_back(e);
  return elements;
}

inline void finish_report(GenerateReport* report, const Scene& scene, int vertices,
                   std::chrono::steady_clock::time_point start) {
  if (!report) return;
  report->seconds = std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
  report->frames = scene.time.frames;
  report->vertices = vertices;
  auto w = design_warnings(scene);
  report->warnings.insert(report->warnings.end(), w.begin(), w.end());
}


// A polyline's tangents as constraints (DESIGN §10 key-frame streamlines, §5.4 streamline
// deformation): the unit direction of each segment, times the speed interpolated along it,
// at the corners of every face the segment crosses (sampled every quarter edge length),
// averaged where samples meet. Values add to those already fixed at a vertex.
inline void constrain_polyline(const DesignSpace& space, const std::vector<Vec3>& points,
                               const std::vector<double>& speeds, std::span<char> fixed,
                               std::span<cplx> values) {
  const Mesh& mesh = space.mesh();
  const size_t nv = values.size();
  std::vector<cplx> sum(nv, cplx(0, 0));
  std::vector<double> speed_sum(nv, 0.0);
  std::vector<int> count(nv, 0);
  const double step = 0.25 * mesh.mean_edge_length();
  for (size_t i = 0; i + 1 < points.size(); ++i) {
    const Vec3 a = points[i], b = points[i + 1];
    const double len = (b - a).norm();
    if (len == 0) continue;
    const Vec3 dir = (b - a) / len;
    const int steps = std::max(1, static_cast<int>(std::ceil(len / step)));
    for (int q = 0; q < steps; ++q) {
      const double u = (q + 0.5) / steps;
      const Vec3 x = a + (b - a) * u;
      const double speed = (1 - u) * speeds[i] + u * speeds[i + 1];
      const SurfacePoint p = space.locate(x);
      for (int c : mesh.face(p.face)) {
        const auto v = static_cast<size_t>(c);
        const cplx z = space.bundle().world_to_vertex(c, dir);
        if (std::abs(z) == 0) continue;
        sum[v] += z / std::abs(z);
        speed_sum[v] += speed;
        ++count[v];
      }
    }
  }
  for (size_t v = 0; v < nv; ++v) {
    if (count[v] == 0 || std::abs(sum[v]) == 0) continue;
    if (!fixed[v]) values[v] = cplx(0, 0);
    values[v] += speed_sum[v] / count[v] * normalized(sum[v]);
    fixed[v] = 1;
  }
}

}  // namespace tvf::detail
