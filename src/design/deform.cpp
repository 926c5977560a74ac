// The deform generator (paper §7, DESIGN §5.4): V(t) = M(t) V(t0), and streamline
// deformation.
#include "design/element_regions.h"
#include "tvf/design/generate.h"
#include "tvf/design/hermite_path.h"
#include "tvf/scene/scene_json.h"
#include "tvf/design/streamline_deform.h"

#include <tbb/enumerable_thread_specific.h>

namespace tvf {

using namespace detail;

namespace {

// M(t) from matrix keys {t, m}: linear from the identity at t0 to the first key, then
// key to key, constant after the last.
Mat2 matrix_at(const std::vector<MatrixKey>& keys, double t0, double t) {
  double ta = t0;
  Mat2 ma = Mat2::Identity();
  for (const MatrixKey& k : keys) {
    const double tb = k.t;
    const Mat2& mb = k.m;
    if (t <= tb) {
      if (tb <= ta) return mb;
      const double w = std::clamp((t - ta) / (tb - ta), 0.0, 1.0);
      return (1 - w) * ma + w * mb;
    }
    ta = tb;
    ma = mb;
  }
  return ma;
}

// Transform keys {t, sx, sy, theta}, with the identity at t0 unless a key is there.
std::vector<TransformKey> transform_keys(const std::vector<TransformKey>& keys, double t0) {
  std::vector<TransformKey> out;
  out.reserve(keys.size() + 1);
  if (keys.empty() || keys.front().t > t0) out.push_back(TransformKey{t0, 1, 1, 0});
  for (const TransformKey& k : keys) out.push_back(k);
  return out;
}

cplx apply(const Mat2& m, cplx z) { return to_complex(m * to_vec2(z)); }

}  // namespace

Scene deform_base_scene(const Scene& scene) {
  TVF_CHECK(scene.deform.has_value(), "deform_base_scene needs a scene with a deform block");
  Scene base = scene;
  base.elements = scene.deform->base;
  base.generator = Generator::constrained;
  base.deform.reset();
  base.keyframes.clear();
  base.edits.clear();
  return base;
}

Mat2 deform_matrix(const Scene& scene, double t) {
  if (!scene.deform) return Mat2::Identity();
  const Deform& def = *scene.deform;
  const double t0 = scene.time.t0;
  if (def.matrix) return matrix_at(*def.matrix, t0, t);
  if (def.transform) return transform_matrix(interpolate_transform(transform_keys(*def.transform, t0), t));
  return Mat2::Identity();
}

Field generate_deform(const DesignSpace& space, const Scene& scene, const GenerateOptions& options,
                      GenerateReport* report) {
  const auto start = std::chrono::steady_clock::now();
  const Mesh& mesh = space.mesh();
  const int nv = mesh.num_vertices();
  const auto n = static_cast<size_t>(nv);
  check_field_memory(scene, nv);
  if (!scene.deform)
    throw_input_error(scene.label(), "deform", "the deform generator needs a deform block");
  const double t0 = scene.time.t0;

  // The base field V(t0): the static constrained design of deform.base's elements.
  const Scene base = deform_base_scene(scene);
  if (base.elements.empty())
    throw_input_error(scene.label(), "deform.base.elements",
                      "the base field has no elements, so there is nothing to deform");
  const std::vector<CompiledElement> base_elements = compile(base);
  const double d = scene.falloff / (space.diameter() * space.diameter());
  const ConnectionLaplacian laplacian =
      connection_laplacian(space.bundle(), to_laplacian_weights(scene.solver.weights));
  std::vector<char> base_fixed(n, 0);
  std::vector<cplx> base_values(n, cplx(0, 0)), v0(n);
  constrain_elements(space, base, base_elements, t0, d, base_fixed, base_values);
  DirichletSolver prototype(laplacian);
  {
    DirichletSolver s(prototype);
    if (const SolveReport r = s.solve(base_fixed, base_values, v0); !r.success)
      throw_input_error(scene.label(), "deform.base", "the base field could not be solved: " + r.failure);
  }

  // M(t): matrix keys, or (sx, sy, θ) keys interpolated linearly.
  auto m_at = [&](double t) { return deform_matrix(scene, t); };

  // Representative streamlines traced in V(t0), moved over time (streamline_deform.h).
  const StreamlineDeformation deformation(space, scene, v0);

  Field field(scene.time, nv);
  tbb::enumerable_thread_specific<DirichletSolver> solvers(prototype);
  std::mutex report_mutex;
  double worst = 0;
  bool ok = true;
  std::string failure;
  for_each_frame(scene.time.frames, options, [&](int j) {
    const double t = scene.time.time(j);
    const Mat2 m = m_at(t);
    std::span<cplx> out = field.frame(j);
    if (deformation.size() == 0) {
      for (size_t v = 0; v < n; ++v) out[v] = apply(m, v0[v]);
      return;
    }
    // Streamline deformation: the base elements' regions (transformed by M(t)) and the
    // moved streamlines' tangents constrain the frame's solve.
    std::vector<char> fixed(base_fixed);
    std::vector<cplx> values(n, cplx(0, 0));
    for (size_t v = 0; v < n; ++v)
      if (fixed[v]) values[v] = apply(m, v0[v]);
    for (const MovedStreamline& line : deformation.at(t)) constrain_polyline(space, line.points, line.speeds, fixed, values);
    const SolveReport r = solvers.local().solve(fixed, values, out);
    std::lock_guard lock(report_mutex);
    worst = std::max(worst, r.residual);
    if (!r.success && failure.empty()) failure = r.failure;
    ok = ok && r.success;
  }, &field);
  if (!ok) throw_input_error(scene.label(), "deform", "a frame's constrained solve failed: " + failure);
  if (report) {
    report->method = deformation.size() == 0 ? "time-varying transformation V(t) = M(t) V(t0)"
                                    : "streamline deformation, constrained solve per frame";
    report->residual = worst;
  }
  finish_report(report, scene, nv, start);
  return field;
}

}  // namespace tvf
