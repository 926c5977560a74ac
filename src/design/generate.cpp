#include "tvf/design/generate.h"

#include "tvf/core/error.h"
#include "tvf/design/element_field.h"

#include <tbb/parallel_for.h>

#include <chrono>
#include <cmath>
#include <mutex>
#include <unistd.h>

namespace tvf {

std::uint64_t field_memory_bytes(int frames, long long vertices) {
  // 16 bytes per complex double in memory, 12 per float32 world vector when exporting.
  return static_cast<std::uint64_t>(frames) * static_cast<std::uint64_t>(vertices) * 28u;
}

namespace {

std::uint64_t physical_memory_bytes() {
  const long pages = ::sysconf(_SC_PHYS_PAGES);
  const long page = ::sysconf(_SC_PAGE_SIZE);
  return pages > 0 && page > 0 ? static_cast<std::uint64_t>(pages) * static_cast<std::uint64_t>(page)
                               : std::uint64_t{1} << 34;
}

}  // namespace

void check_field_memory(const Scene& scene, long long vertices) {
  const int frames = scene.time.frames;
  const std::uint64_t need = field_memory_bytes(frames, vertices);
  const std::uint64_t have = physical_memory_bytes();
  if (need > have / 10 * 8)
    throw_input_error(scene.label(), "time.frames",
                      fmt::format("{} frames × {} vertices need {:.1f} GiB, more than 80 % of the {:.1f} GiB "
                                  "of memory this machine has",
                                  frames, vertices, static_cast<double>(need) / (1u << 30),
                                  static_cast<double>(have) / (1u << 30)));
}

namespace {

// An element placed at one frame: local field plus where it is.
struct Placed {
  LocalField field;
  Vec3 position;
};

}  // namespace

std::vector<std::string> design_warnings(const Scene& scene) {
  std::vector<std::string> out;
  const double span = scene.time.t1 - scene.time.t0;
  const double dt = span / std::max(1, scene.time.frames - 1);
  for (size_t i = 0; i < scene.elements.size(); ++i) {
    const auto* s = std::get_if<SingularElement>(&scene.elements[i]);
    if (!s || s->path.size() < 2) continue;
    for (const PathPoint* end : {&s->path.front(), &s->path.back()}) {
      const bool inside = end->t > scene.time.t0 + 1e-12 && end->t < scene.time.t1 - 1e-12;
      if (!inside) continue;
      // Provided if a bifurcation element sits there, or another singular path of opposite
      // index ends or begins at the same space-time point.
      bool provided = false;
      const int index = s->jacobian.determinant() > 0 ? 1 : -1;
      for (size_t k = 0; k < scene.elements.size() && !provided; ++k) {
        if (k == i) continue;
        if (const auto* b = std::get_if<BifurcationElement>(&scene.elements[k])) {
          provided = std::abs(b->at.t - end->t) <= 2 * dt + b->time_scale &&
                     (b->at.position - end->position).norm() <= 3 * b->scale;
        } else if (const auto* o = std::get_if<SingularElement>(&scene.elements[k])) {
          const int oi = o->jacobian.determinant() > 0 ? 1 : -1;
          if (oi == index || o->path.size() < 2) continue;
          for (const PathPoint* oe : {&o->path.front(), &o->path.back()})
            provided = provided || (std::abs(oe->t - end->t) <= 2 * dt &&
                                    (oe->position - end->position).norm() <= 1e-3 + 0.05 * span);
        }
      }
      if (!provided)
        out.push_back(fmt::format(
            "{}: elements[{}]: the singular path {} at t = {} inside the time range; a "
            "singularity appears or vanishes only together with one of opposite index, so "
            "add a bifurcation element or a path of opposite index meeting it there",
            scene.label(), i, end == &s->path.front() ? "begins" : "ends", end->t));
    }
  }
  return out;
}

Field generate_basis_sum(const DesignSpace& space, const Scene& scene,
                         const GenerateOptions& options, GenerateReport* report) {
  const auto start = std::chrono::steady_clock::now();
  const Mesh& mesh = space.mesh();
  const int nv = mesh.num_vertices();
  const int nframes = scene.time.frames;
  check_field_memory(scene, nv);

  std::vector<CompiledElement> elements;
  elements.reserve(scene.elements.size());
  for (const Element& e : scene.elements) elements.emplace_back(e);
  const double d = scene.falloff / (space.diameter() * space.diameter());

  Field field(scene.time, nv);
  std::mutex progress_mutex;
  int done = 0;

  auto solve_frame = [&](int j) {
    const double t = scene.time.time(j);
    std::span<cplx> out = field.frame(j);
    std::fill(out.begin(), out.end(), cplx(0, 0));
    LocalChart chart;
    for (const CompiledElement& el : elements) {
      if (!el.active(t)) continue;
      ElementState st = el.at(t);
      if (space.planar()) {
        // Local coordinates are the plane's own: w = x − p, frame = global.
        for (int v = 0; v < nv; ++v) {
          const Vec3& x = mesh.position(v);
          const cplx w(x.x() - st.position.x(), x.y() - st.position.y());
          out[static_cast<size_t>(v)] += std::exp(-d * std::norm(w)) * st.field(w);
        }
        continue;
      }
      const SurfacePoint p = space.locate(st.position);
      if (st.field.kind == LocalField::Kind::regular)
        st.field.velocity = space.bundle().world_to_face(p.face, st.velocity);
      space.log_map().compute(p, chart);
      for (int v = 0; v < nv; ++v) {
        const cplx w = chart.coords[static_cast<size_t>(v)];
        const double fall = std::exp(-d * std::norm(w));
        if (fall < 1e-300) continue;
        out[static_cast<size_t>(v)] += fall * st.field(w) * chart.frame[static_cast<size_t>(v)];
      }
    }
    if (options.progress) {
      std::lock_guard lock(progress_mutex);
      options.progress(++done, nframes);
    }
  };

  if (options.parallel) {
    tbb::parallel_for(0, nframes, solve_frame);
  } else {
    for (int j = 0; j < nframes; ++j) solve_frame(j);
  }

  if (report) {
    report->seconds = std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
    report->frames = nframes;
    report->vertices = nv;
    auto w = design_warnings(scene);
    report->warnings.insert(report->warnings.end(), w.begin(), w.end());
  }
  return field;
}

Field generate(const DesignSpace& space, const Scene& scene, const GenerateOptions& options,
               GenerateReport* report) {
  if (!scene.edits.empty())
    throw_input_error(scene.label(), "edits",
                      "topological edits are not available in this version of tvf; remove the "
                      "'edits' entries to generate the unedited design");
  switch (scene.generator) {
    case Generator::basis: return generate_basis_sum(space, scene, options, report);
    case Generator::constrained:
    case Generator::spacetime:
    case Generator::deform:
      throw_input_error(scene.label(), "generator",
                        fmt::format("the '{}' generator is not available in this version of tvf "
                                    "(available: basis)",
                                    to_string(scene.generator)));
  }
  TVF_CHECK(false, "unknown generator");
}

}  // namespace tvf
