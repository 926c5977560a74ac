#include "tvf/design/keyframes.h"

#include "design/element_regions.h"

#include "tvf/core/error.h"
#include "tvf/design/element_field.h"
#include "tvf/field/field_io.h"
#include "tvf/field/field_sampler.h"

#include <cmath>

namespace tvf {

int keyframe_frame(const Scene& scene, double t) {
  const TimeSampling& ts = scene.time;
  if (ts.frames <= 1) return 0;
  const double u = (t - ts.t0) / (ts.t1 - ts.t0) * (ts.frames - 1);
  return std::clamp(static_cast<int>(std::lround(u)), 0, ts.frames - 1);
}

namespace {

// The state of a key frame's static element.
ElementState static_state(const KeyframeElement& e) {
  ElementState st;
  st.active = true;
  st.position = e.at;
  if (e.kind == "regular") {
    st.velocity = e.vector;
    st.field.kind = LocalField::Kind::regular;
    st.field.velocity = cplx(e.vector.x(), e.vector.y());
  } else {
    st.field.kind = LocalField::Kind::linear;
    st.field.matrix = e.type ? jacobian_of(*e.type) : e.jacobian;
  }
  return st;
}

}  // namespace

void keyframe_constraints(const DesignSpace& space, const Scene& scene, size_t k,
                          std::vector<char>& fixed, std::vector<cplx>& values) {
  const Mesh& mesh = space.mesh();
  const auto nv = static_cast<size_t>(mesh.num_vertices());
  fixed.assign(nv, 0);
  values.assign(nv, cplx(0, 0));
  const Keyframe& key = scene.keyframes[k];
  const double d = scene.falloff / (space.diameter() * space.diameter());
  const double radius = scene.solver.region_radius;

  // Elements: each imposes its own field near itself, as in the constrained generator.
  LocalChart chart;
  detail::ElementOnDomain placed;
  for (const KeyframeElement& e : key.elements) {
    detail::place_state(space, static_state(e), d, chart, placed);
    detail::constrain_region(mesh, placed, radius, fixed, values);
  }

  // Streamlines: their tangents, with magnitude `speed`.
  for (const KeyframeStreamline& s : key.streamlines)
    detail::constrain_polyline(space, s.points, std::vector<double>(s.points.size(), s.speed), fixed,
                               values);
}

std::vector<cplx> keyframe_field(const DesignSpace& space, const Scene& scene, size_t k,
                                 const ConnectionLaplacian& laplacian) {
  const Keyframe& key = scene.keyframes[k];
  const auto nv = static_cast<size_t>(space.mesh().num_vertices());
  std::vector<cplx> out(nv, cplx(0, 0));
  if (!key.field.empty()) {
    const std::string path = scene.resolve_path(key.field);
    const FieldFile file = load_field_file(path);
    if (file.mesh.num_vertices() != space.mesh().num_vertices() ||
        file.mesh.num_faces() != space.mesh().num_faces())
      throw_input_error(scene.label(), fmt::format("keyframes[{}].field", k),
                        fmt::format("'{}' holds a field on {} vertices and {} faces, but the domain "
                                    "has {} vertices and {} faces",
                                    path, file.mesh.num_vertices(), file.mesh.num_faces(),
                                    space.mesh().num_vertices(), space.mesh().num_faces()));
    const TangentBundle bundle(file.mesh);
    const FieldSampler sampler(bundle, file.field);
    for (size_t v = 0; v < nv; ++v) out[v] = sampler.at_vertex(static_cast<int>(v), key.t);
    return out;
  }
  std::vector<char> fixed;
  std::vector<cplx> values;
  keyframe_constraints(space, scene, k, fixed, values);
  DirichletSolver solver(laplacian);
  const SolveReport r = solver.solve(fixed, values, out);
  if (!r.success)
    throw_input_error(scene.label(), fmt::format("keyframes[{}]", k),
                      "the key frame's constrained design could not be solved: " + r.failure);
  return out;
}

}  // namespace tvf
