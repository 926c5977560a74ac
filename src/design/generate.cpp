#include "tvf/design/generate.h"

#include "tvf/core/error.h"
#include "tvf/design/element_field.h"
#include "design/element_regions.h"
#include "tvf/design/keyframe_topology.h"
#include "tvf/design/keyframes.h"
#include "tvf/design/streakline_design.h"
#include "tvf/edit/field_editor.h"
#include "tvf/solve/connection_laplacian.h"
#include "tvf/solve/dirichlet_frames.h"
#include "tvf/solve/distributed.h"
#include "tvf/solve/spacetime.h"
#include "solve/petsc_spacetime.h"

#include <tbb/enumerable_thread_specific.h>
#include <tbb/parallel_for.h>

#include <algorithm>
#include <chrono>
#include <cmath>
#include <exception>
#include <mutex>
#include <numbers>
#include <string>

namespace tvf {

using namespace detail;

struct GenerateCache::State {
  std::uint64_t domain = 0;  // content hash of the mesh the Laplacian was made on
  bool has_domain = false;
  Weights weights = Weights::cotan;
  // Declared before what refers to it, so that it is destroyed after them.
  std::unique_ptr<ConnectionLaplacian> laplacian;
  std::unique_ptr<DirichletSolver> prototype;
  std::unique_ptr<tbb::enumerable_thread_specific<DirichletSolver>> dirichlet;
  std::unique_ptr<DirichletFrames> frame_blocks;
  int frames = 0;
  double temporal_weight = 0;
  std::unique_ptr<SpaceTimeSolver> spacetime;
  std::vector<cplx> last;  // the last space-time solution (frames × |V|), or empty
  // The key frames' fields (designed on `laplacian`) by what they depend on (keyframe_key),
  // most recently used first: a change elsewhere in the scene designs no key frame again.
  std::vector<std::pair<std::string, std::vector<cplx>>> keyframes;
  int warm = 0, reused = 0, reused_keyframes = 0;

  void clear() {
    keyframes.clear();
    spacetime.reset();
    dirichlet.reset();
    prototype.reset();
    frame_blocks.reset();
    laplacian.reset();
    last.clear();
    has_domain = false;
  }
};

GenerateCache::GenerateCache() : state_(std::make_unique<State>()) {}
GenerateCache::~GenerateCache() = default;
void GenerateCache::clear() { state_->clear(); }
int GenerateCache::warm_starts() const { return state_->warm; }
int GenerateCache::reused_laplacians() const { return state_->reused; }
int GenerateCache::reused_keyframes() const { return state_->reused_keyframes; }

namespace {

// FNV-1a over the mesh's positions and faces: two meshes with the same hash are (with
// overwhelming probability) the same domain, so their Laplacians are equal.
std::uint64_t mesh_hash(const Mesh& mesh) {
  std::uint64_t h = 1469598103934665603ull;
  auto add = [&](const void* data, size_t bytes) {
    const auto* b = static_cast<const unsigned char*>(data);
    for (size_t i = 0; i < bytes; ++i) h = (h ^ b[i]) * 1099511628211ull;
  };
  for (const Vec3& p : mesh.positions()) add(p.data(), 3 * sizeof(double));
  for (const Face& f : mesh.faces()) add(f.data(), sizeof(Face));
  const int n[2] = {mesh.num_vertices(), mesh.num_faces()};
  add(n, sizeof n);
  return h;
}

// The Laplacian of the space and weights: the cache's when it was made from the same,
// else a new one (kept in the cache when there is one, else in `local`). A new domain or
// weights drop everything the cache built on the old Laplacian.
const ConnectionLaplacian& laplacian_for(const DesignSpace& space, Weights weights, GenerateCache* cache,
                                         std::unique_ptr<ConnectionLaplacian>& local) {
  if (!cache) {
    local = std::make_unique<ConnectionLaplacian>(connection_laplacian(space.bundle(), to_laplacian_weights(weights)));
    return *local;
  }
  GenerateCache::State& c = cache->state();
  const std::uint64_t h = mesh_hash(space.mesh());
  if (c.laplacian && c.has_domain && c.domain == h && c.weights == weights) {
    ++c.reused;
    return *c.laplacian;
  }
  c.clear();
  c.laplacian = std::make_unique<ConnectionLaplacian>(connection_laplacian(space.bundle(), to_laplacian_weights(weights)));
  c.domain = h;
  c.has_domain = true;
  c.weights = weights;
  return *c.laplacian;
}

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
          // A Hopf template creates no singularity: its focus is there at all times.
          provided = !is_hopf(b->type) && std::abs(b->at.t - end->t) <= 2 * dt + b->time_scale &&
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
  // Streaklines (streakline_design.h) constrain a solve; they have no basis field.
  if (scene.generator == Generator::basis || scene.generator == Generator::deform)
    for (size_t i = 0; i < scene.elements.size(); ++i)
      if (std::holds_alternative<StreaklineElement>(scene.elements[i]))
        out.push_back(fmt::format("{}: elements[{}]: a streakline is reproduced by the constrained and spacetime "
                                  "generators only; the {} generator leaves it out",
                                  scene.label(), i, to_string(scene.generator)));
  return out;
}

std::vector<std::string> domain_warnings(const DesignSpace& space, const Scene& scene) {
  std::vector<std::string> out;
  const double h = space.mesh().mean_edge_length();
  // A sketched streakline whose parts come too close for the dye to keep to one of them
  // (kSketchApartEdges), for the generators that reproduce it.
  if (scene.generator == Generator::constrained || scene.generator == Generator::spacetime)
    for (size_t i = 0; i < scene.elements.size(); ++i) {
      const auto* sl = std::get_if<StreaklineElement>(&scene.elements[i]);
      if (!sl) continue;
      std::vector<Vec3> p;
      for (const Vec3& x : sl->points) p.push_back(surface_position(space.mesh(), space.locate(x)));
      const SketchSelfApproach a = sketch_self_approach(p, h);
      const double apart = sl->attach > 0 ? kSketchApartEdges : kSketchApartEdgesUnattached;
      if (!(a.distance < apart * h)) continue;
      auto point = [&](const Vec3& x) {
        return space.planar() ? fmt::format("({:.3g}, {:.3g})", x.x(), x.y())
                              : fmt::format("({:.3g}, {:.3g}, {:.3g})", x.x(), x.y(), x.z());
      };
      out.push_back(fmt::format(
          "{}: elements[{}].points: the sketch comes within {:.3g} mean edge lengths of itself, at {} and {} "
          "({:.3g} edge lengths apart along it), and the traced dye keeps to one part of it only from about "
          "{:g}{}: there it will not follow the sketch; draw those parts further apart{} or use a finer mesh",
          scene.label(), i, a.distance / h, point(a.a), point(a.b), a.along / h, apart,
          sl->attach > 0 ? "" : " without `attach` (1 with it)", sl->attach > 0 ? "" : ", give `attach` > 0"));
    }
  for (size_t i = 0; i < scene.elements.size(); ++i) {
    const auto* b = std::get_if<BifurcationElement>(&scene.elements[i]);
    if (!b) continue;
    // (Edges to 3 digits: 5.99 is not "6.0 … from about 6".)
    if (const double edges = b->scale / h; edges < template_resolved_edges(b->type))
      out.push_back(fmt::format("{}: elements[{}]: the template's scale {:.3g} spans {:.3g} mean edge lengths, and the "
                                "mesh resolves a {} template from about {:g}: {}; give a larger scale or a finer mesh",
                                scene.label(), i, b->scale, edges,
                                is_hopf(b->type) ? "Hopf" : "saddle–node", template_resolved_edges(b->type),
                                is_hopf(b->type) ? "its event may come late (by a part of its time scale) or not at all"
                                                 : "its pair may be lost among the other elements' fields"));
    if (space.planar()) continue;
    const double curvature = space.curvature_within(b->at.position, 0.5 * b->scale);
    if (curvature > kTemplateMostCurvature)
      out.push_back(fmt::format("{}: elements[{}]: the surface within half the template's scale ({:.3g}) of its "
                                "point holds a total curvature of {:.2f} (over π: it closes round, as at the end of "
                                "a tail or a finger), so its {} will not be as designed; place it where the surface "
                                "is flatter, or make its scale smaller",
                                scene.label(), i, 0.5 * b->scale, curvature,
                                is_hopf(b->type) ? "cycle and event" : "pair and event"));
  }
  return out;
}

Field generate_basis_sum(const DesignSpace& space, const Scene& scene,
                         const GenerateOptions& options, GenerateReport* report) {
  const auto start = std::chrono::steady_clock::now();
  const int nv = space.mesh().num_vertices();
  check_field_memory(scene, nv);
  const std::vector<CompiledElement> elements = compile(scene);
  const double d = scene.falloff / (space.diameter() * space.diameter());

  Field field(scene.time, nv);
  for_each_frame(scene.time.frames, options, [&](int j) {
    const double t = scene.time.time(j);
    std::span<cplx> out = field.frame(j);
    std::fill(out.begin(), out.end(), cplx(0, 0));
    LocalChart chart;
    ElementOnDomain placed;
    for (const CompiledElement& el : elements) {
      if (!el.active(t)) continue;
      place_element(space, el, t, d, chart, placed);
      for (size_t v = 0; v < out.size(); ++v) out[v] += placed.value[v];
    }
  }, &field);
  if (report) report->method = "basis field summation";
  finish_report(report, scene, nv, start);
  return field;
}

// The width of the constrained generator's constraint ramps, in mean edge lengths: wide
// enough that a vertex fades in over more than one frame's step of a steadily moving element.
constexpr double constraint_ramp_edges = 2.0;

// Frames solved with one shared factorization (DirichletFrames): consecutive frames in
// fixed blocks of this many, so that the field does not depend on the thread or rank count.
// Measured (docs/benchmarks.md, issue 15): fewer frames share too little, more make the
// changing set, whose Schur complement every frame factors, too large.
constexpr int frames_per_block = 25;
// A block holds its frames' constraints twice while it is solved (the generator's and
// DirichletFrames' own, about 50 bytes a vertex a frame): on large meshes fewer frames a
// block keep that under this many bytes (25 frames up to 160,000 vertices; 4 at 10⁶).
constexpr double block_constraint_bytes = 200e6;

namespace {

// The constraints of frame j (issue 15's smooth ramps, and streaklines).
void frame_constraints(const DesignSpace& space, const Scene& scene, const std::vector<CompiledElement>& elements,
                       const ConnectionLaplacian& laplacian, const StreaklineConstraints& streaklines, int j,
                       double ramp, SmoothConstraints& c, std::vector<KeptChart>* kept = nullptr) {
  const double d = scene.falloff / (space.diameter() * space.diameter());
  const double t = scene.time.time(j);
  constrain_elements_smoothly(space, scene, elements, t, d, laplacian.weight_sum, ramp, c, kept);
  streaklines.constrain(t, c.fixed, c.values);
}

}  // namespace

Field generate_constrained(const DesignSpace& space, const Scene& scene,
                           const GenerateOptions& options, GenerateReport* report) {
  const auto start = std::chrono::steady_clock::now();
  const Mesh& mesh = space.mesh();
  const int nv = mesh.num_vertices();
  check_field_memory(scene, nv);
  const std::vector<CompiledElement> elements = compile(scene);
  std::unique_ptr<ConnectionLaplacian> own_laplacian;
  const ConnectionLaplacian& laplacian = laplacian_for(space, scene.solver.weights, options.cache, own_laplacian);
  const StreaklineConstraints streaklines(space, scene);
  const double ramp = constraint_ramp_edges * mesh.mean_edge_length();
  Field field(scene.time, nv);
  std::mutex report_mutex;
  double worst_residual = 0;
  bool all_ok = true;
  std::string method, failure;
  int failed_frame = -1;
  auto record = [&](int j, const SolveReport& r) {
    std::lock_guard lock(report_mutex);
    worst_residual = std::max(worst_residual, r.residual);
    if (!r.success && (failed_frame < 0 || j < failed_frame)) {
      failed_frame = j;
      failure = r.failure;
    }
    all_ok = all_ok && r.success;
    method = r.method;
  };
  const int frames = scene.time.frames;
  int block = 1;  // frames a rank's unit of work holds (distributed_share_frames)

  if (laplacian.hermitian) {
    // Blocks of consecutive frames sharing one factorization (solve/dirichlet_frames.h).
    block = std::clamp(static_cast<int>(block_constraint_bytes / (50.0 * nv)), 1, frames_per_block);
    std::unique_ptr<DirichletFrames> own_frames;
    const DirichletFrames* solver = nullptr;
    if (options.cache) {
      GenerateCache::State& c = options.cache->state();
      if (!c.frame_blocks) c.frame_blocks = std::make_unique<DirichletFrames>(laplacian);
      solver = c.frame_blocks.get();
    } else {
      own_frames = std::make_unique<DirichletFrames>(laplacian);
      solver = own_frames.get();
    }
    const int blocks = (frames + block - 1) / block;
    const int first = options.first_frame_done && options.first_frame >= 0 && options.first_frame < frames
                          ? options.first_frame
                          : -1;
    std::mutex progress_mutex;
    int done = 0;
    auto run = [&](int b) {
      if (!distributed_owns_frame(b)) return;  // another rank's block, under mpirun
      check_cancelled(options);
      const int j0 = b * block, count = std::min(block, frames - j0);
      std::vector<SmoothConstraints> c(static_cast<size_t>(count));
      // The frames' constraints (on surfaces mostly log maps), at once when parallel; a
      // static element's log map made once a block and thread (a chart made again for
      // the same point is the same chart, so the values do not depend on the threads).
      tbb::enumerable_thread_specific<std::vector<KeptChart>> kept;
      auto gather = [&](int k) {
        if (k > 0) check_cancelled(options);
        frame_constraints(space, scene, elements, laplacian, streaklines, j0 + k, ramp, c[static_cast<size_t>(k)],
                          &kept.local());
      };
      if (options.parallel) {
        tbb::parallel_for(0, count, gather);
      } else {
        for (int k = 0; k < count; ++k) gather(k);
      }
      std::vector<DirichletProblem> problems;
      std::vector<std::span<cplx>> out;
      for (int k = 0; k < count; ++k) {
        const SmoothConstraints& ck = c[static_cast<size_t>(k)];
        problems.push_back({ck.fixed, ck.values, ck.penalty});
        out.push_back(field.frame(j0 + k));
      }
      // Progress as each frame is solved; a cancellation stops the block there.
      auto solved = [&](size_t k) {
        if (options.progress) {
          std::lock_guard lock(progress_mutex);
          options.progress(++done, frames);
        }
        check_cancelled(options);
        if (j0 + static_cast<int>(k) == first) options.first_frame_done(first, field.frame(first));
      };
      const bool shown_here = first >= j0 && first < j0 + count;
      const std::vector<SolveReport> r = solver->solve(problems, out, nullptr, solved,
                                                       shown_here ? static_cast<size_t>(first - j0) : static_cast<size_t>(-1),
                                                       options.parallel);
      for (int k = 0; k < count; ++k) {
        if (r[static_cast<size_t>(k)].success) {
          record(j0 + k, r[static_cast<size_t>(k)]);
          continue;
        }
        // Not expected (every frame's matrix is positive definite); the frame alone then,
        // with its own factorization, which says why if it fails too.
        DirichletSolver alone(laplacian);
        const SmoothConstraints& ck = c[static_cast<size_t>(k)];
        record(j0 + k, alone.solve(ck.fixed, ck.values, field.frame(j0 + k), ck.penalty));
      }
    };
    // The block holding the frame a viewer shows first (GenerateOptions::first_frame) runs
    // before the others, and that frame is published as soon as it is solved; the blocks'
    // bounds stay the same, so the field does not depend on which frame is shown.
    if (first >= 0) run(first / block);
    auto rest = [&](int b) {
      if (first < 0 || b != first / block) run(b);
    };
    if (options.parallel) {
      tbb::parallel_for(0, blocks, rest);
    } else {
      for (int b = 0; b < blocks; ++b) rest(b);
    }
  } else {
    // Mean-value weights: one LU factorization per frame (per-thread solvers, symbolic
    // analysis done once: the cache's, or this call's).
    std::unique_ptr<DirichletSolver> own_prototype;
    std::unique_ptr<tbb::enumerable_thread_specific<DirichletSolver>> own_solvers;
    tbb::enumerable_thread_specific<DirichletSolver>* kept = nullptr;
    if (options.cache) {
      GenerateCache::State& c = options.cache->state();
      if (!c.dirichlet) {
        c.prototype = std::make_unique<DirichletSolver>(laplacian);
        c.dirichlet = std::make_unique<tbb::enumerable_thread_specific<DirichletSolver>>(*c.prototype);
      }
      kept = c.dirichlet.get();
    } else {
      own_prototype = std::make_unique<DirichletSolver>(laplacian);
      own_solvers = std::make_unique<tbb::enumerable_thread_specific<DirichletSolver>>(*own_prototype);
      kept = own_solvers.get();
    }
    tbb::enumerable_thread_specific<DirichletSolver>& solvers = *kept;
    for_each_frame(frames, options, [&](int j) {
      if (!distributed_owns_frame(j)) return;  // another rank's, under mpirun (solve/distributed.h)
      SmoothConstraints c;
      frame_constraints(space, scene, elements, laplacian, streaklines, j, ramp, c);
      record(j, solvers.local().solve(c.fixed, c.values, field.frame(j), c.penalty));
    }, &field);
  }
  if (!distributed_all(all_ok))
    throw_input_error(scene.label(), "generator",
                      all_ok ? std::string("the constrained solve of a frame failed on another rank")
                             : fmt::format("the constrained solve of frame {} failed: {}", failed_frame, failure));
  distributed_share_frames(field.data(), static_cast<size_t>(nv), frames, block);
  worst_residual = distributed_max(worst_residual);
  if (report) {
    report->method = "constrained optimization per frame, " + method;
    if (distributed_active())
      report->method += fmt::format(", frames shared by {} {}", distributed_ranks(),
                                    distributed_ranks() == 1 ? "rank" : "ranks");
    report->residual = worst_residual;
  }
  finish_report(report, scene, nv, start);
  return field;
}

namespace {

void check_spacetime_scene(const Scene& scene, int nv) {
  check_field_memory(scene, nv);
  if (scene.solver.weights == Weights::mean_value)
    throw_input_error(scene.label(), "solver.weights",
                      "the spacetime generator needs symmetric weights (cotan or uniform): "
                      "mean-value weights make the system non-Hermitian");
}

// Which entries of the space-time system are fixed, to what (spacetime_problem's work,
// on a given Laplacian).
// With solver.keyframe_topology "matched", what each key-frame interval does goes into
// `intervals` (when given).
void spacetime_constraints(const DesignSpace& space, const Scene& scene, const ConnectionLaplacian& laplacian,
                           const GenerateOptions& options, std::vector<char>& fixed, std::vector<cplx>& values,
                           std::vector<KeyframeIntervalReport>* intervals = nullptr);

}  // namespace

SpaceTimeProblem spacetime_problem(const DesignSpace& space, const Scene& scene,
                                   const GenerateOptions& options) {
  check_spacetime_scene(scene, space.mesh().num_vertices());
  SpaceTimeProblem problem{connection_laplacian(space.bundle(), to_laplacian_weights(scene.solver.weights)), {}, {}};
  spacetime_constraints(space, scene, problem.laplacian, options, problem.fixed, problem.values);
  return problem;
}

namespace {

// What a key frame's designed field depends on besides the domain and the Laplacian: its
// elements and streamlines, the scene's falloff and region radius (keyframe_constraints),
// as bytes. Empty for a key frame read from a field file (whose content may change).
std::string keyframe_key(const Scene& scene, size_t k) {
  const Keyframe& key = scene.keyframes[k];
  if (!key.field.empty()) return {};
  std::string out;
  auto add = [&](const auto& v) { out.append(reinterpret_cast<const char*>(&v), sizeof v); };
  add(scene.falloff);
  add(scene.solver.region_radius);
  add(key.elements.size());
  for (const KeyframeElement& e : key.elements) {
    add(e.kind.size());
    out += e.kind;
    add(e.type ? static_cast<int>(*e.type) : -1);
    for (int i = 0; i < 4; ++i) add(e.jacobian(i / 2, i % 2));
    for (int i = 0; i < 3; ++i) add(e.at[i]), add(e.vector[i]);
  }
  add(key.streamlines.size());
  for (const KeyframeStreamline& l : key.streamlines) {
    add(l.speed);
    add(l.points.size());
    for (const Vec3& p : l.points)
      for (int i = 0; i < 3; ++i) add(p[i]);
  }
  return out;
}

// Key frame k's field: the cache's when the cache holds it for this Laplacian, else
// designed (keyframe_field) and kept there (the last generation's and a few before, for
// an undo).
std::vector<cplx> cached_keyframe_field(const DesignSpace& space, const Scene& scene, size_t k,
                                        const ConnectionLaplacian& laplacian, GenerateCache* cache) {
  const std::string key = cache && cache->state().laplacian.get() == &laplacian ? keyframe_key(scene, k) : std::string();
  if (key.empty()) return keyframe_field(space, scene, k, laplacian);
  auto& kept = cache->state().keyframes;
  auto at = std::find_if(kept.begin(), kept.end(), [&](const auto& e) { return e.first == key; });
  if (at == kept.end()) {
    kept.emplace(kept.begin(), key, keyframe_field(space, scene, k, laplacian));
    constexpr size_t kKeptKeyframes = 8;
    if (kept.size() > kKeptKeyframes) kept.pop_back();
  } else {
    std::rotate(kept.begin(), at, at + 1);
    ++cache->state().reused_keyframes;
  }
  return kept.front().second;
}

// The space-time system's constraints frame by frame: key frames (whole frames held
// fixed), then at every other frame the elements' regions, the matched topology's moving
// constraints and the streaklines. Built once (the key frames' fields, the plan), then
// frame(j) is safe to call from several threads. options.cancel stops the building (the
// key frames' solves, the plan) as it stops the solve.
class SpaceTimeConstraints {
public:
  SpaceTimeConstraints(const DesignSpace& space, const Scene& scene, const ConnectionLaplacian& laplacian,
                       std::vector<KeyframeIntervalReport>* intervals, const GenerateOptions& options)
      : space_(space), scene_(scene), key_of_(static_cast<size_t>(scene.time.frames), -1),
        elements_(compile(scene)), d_(scene.falloff / (space.diameter() * space.diameter())),
        streaklines_(space, scene) {
    for (size_t k = 0; k < scene.keyframes.size(); ++k) {
      const auto j = static_cast<size_t>(keyframe_frame(scene, scene.keyframes[k].t));
      if (key_of_[j] >= 0)
        throw_input_error(scene.label(), fmt::format("keyframes[{}].t", k),
                          fmt::format("t = {} falls on frame {}, which another key frame already holds; "
                                      "use more frames or move the key frame",
                                      scene.keyframes[k].t, j));
      key_of_[j] = static_cast<int>(k);
      check_cancelled(options);
      key_fields_.push_back(cached_keyframe_field(space, scene, k, laplacian, options.cache));
    }
    // Topology kept between key frames (keyframe_topology.h): moving constraints and
    // templates, added at every other frame.
    if (scene.solver.keyframe_topology == KeyframeTopology::matched) {
      plan_.emplace(
          space, scene, key_fields_, [&options] { check_cancelled(options); },
          [&options](size_t k, size_t n) {
            if (options.stage)
              options.stage(fmt::format("planning the topology between key frames (interval {} of {})", k + 1, n));
          });
      if (intervals) *intervals = plan_->intervals();
    }
  }

  // Frame j's fixed marks and values, |V| each, zero on entry.
  void frame(int j, std::span<char> fixed, std::span<cplx> values) const {
    if (const int k = key_of_[static_cast<size_t>(j)]; k >= 0) {
      std::fill(fixed.begin(), fixed.end(), char{1});
      const std::vector<cplx>& key = key_fields_[static_cast<size_t>(k)];
      std::copy(key.begin(), key.end(), values.begin());
      return;
    }
    const double t = scene_.time.time(j);
    constrain_elements(space_, scene_, elements_, t, d_, fixed, values, &charts_.local());
    if (plan_) plan_->constrain(space_, scene_, t, d_, fixed, values);
    streaklines_.constrain(t, fixed, values);
  }

private:
  const DesignSpace& space_;
  const Scene& scene_;
  std::vector<int> key_of_;  // per frame: the key frame there, or −1
  std::vector<std::vector<cplx>> key_fields_;
  std::optional<KeyframeTopologyPlan> plan_;
  std::vector<CompiledElement> elements_;
  // Each thread's last log map of every element: an element that stays put has the same
  // chart at every frame (made once per thread instead of at each of the frames).
  mutable tbb::enumerable_thread_specific<std::vector<KeptChart>> charts_;
  double d_;
  StreaklineConstraints streaklines_;
};

void spacetime_constraints(const DesignSpace& space, const Scene& scene, const ConnectionLaplacian& laplacian,
                           const GenerateOptions& options, std::vector<char>& fixed, std::vector<cplx>& values,
                           std::vector<KeyframeIntervalReport>* intervals) {
  const auto n = static_cast<size_t>(space.mesh().num_vertices());
  const auto frames = static_cast<size_t>(scene.time.frames);
  const SpaceTimeConstraints constraints(space, scene, laplacian, intervals, options);
  fixed.assign(n * frames, 0);
  values.assign(n * frames, cplx(0, 0));
  GenerateOptions quiet = options;
  quiet.progress = nullptr;
  for_each_frame(scene.time.frames, quiet, [&](int j) {
    constraints.frame(j, std::span<char>(fixed.data() + static_cast<size_t>(j) * n, n),
                      std::span<cplx>(values.data() + static_cast<size_t>(j) * n, n));
  });
}

// The space-time solve's end, in one process and on the ranks alike: a solve short of the
// tolerance is the scene's error; the report names the method, its residual and
// iterations, the key-frame intervals and their collisions as warnings.
void require_converged(const Scene& scene, const SolveReport& r) {
  if (!r.success)
    throw_input_error(scene.label(), "solver.tolerance",
                      fmt::format("the space-time solve stopped at relative residual {:.2e} after {} "
                                  "iterations, short of the tolerance {:.1e}",
                                  r.residual, r.iterations, scene.solver.tolerance));
}

// A node the surface guide leaves turning (KeyframeIntervalReport::Match::phase_turns):
// the designer should know that it passes through the other types, and what takes it out.
std::string keyframe_turn_warning(const KeyframeIntervalReport& k, const KeyframeIntervalReport::Match& m) {
  const auto at = [](const Vec3& p) {
    const auto r = [](double v) { return std::round(v * 1000) / 1000 + 0.0; };  // no "-0.000"
    return fmt::format("({:.3f}, {:.3f}, {:.3f})", r(p.x()), r(p.y()), r(p.z()));
  };
  const std::string what = fmt::format("between keyframes[{}] and keyframes[{}] the {} carried from {} to {} is not "
                                       "held to its type: ",
                                       k.from_keyframe, k.to_keyframe, to_string(m.type), at(m.from), at(m.to));
  // The key frame the plan offers (its elements where it carries them half-way), else
  // the advice alone.
  std::string advice = "a key frame between them can hold it (as in example 26's knot_sphere_middle.json)";
  if (k.middle_keyframe) {
    std::string held;
    for (const KeyframeElement& e : k.middle_keyframe->keyframe.elements)
      held += fmt::format("{}the {} at {}", held.empty() ? "" : ", ", e.type ? to_string(*e.type) : "singular element",
                          at(e.at));
    advice = fmt::format("a key frame at t = {:.4g} holding {}, where the plan carries them then, can hold it "
                         "(keyframe_topology.json's \"middle_keyframe\"; the designer's \"add this key frame\")",
                         k.middle_keyframe->keyframe.t, held);
  }
  if (m.phase_turns != 0)
    return what + fmt::format("it turns {} whole turn{} on the way (through every node type: source, center, sink, center); {}",
                              std::abs(m.phase_turns), std::abs(m.phase_turns) == 1 ? "" : "s", advice);
  return what + fmt::format("it turns up to {:.2f} rad from it on the way (past a center to the other stability and back){}",
                            m.phase_swing, k.middle_keyframe ? "; " + advice : std::string());
}

// Pairs created or cancelled within a few frames of a key frame (solver.bifurcation_times
// set near one): between the event and the key frame the pair's singularities appear (or
// leave their places) and travel to where the key frame holds them, in those frames, and
// the field changes that much faster there. Example 26 (60 frames): the frame-to-frame
// change's max/median 1.5 with the creation 12 frames before the key frame, 2.9 at 6,
// 5.1 at 3, 9.7 at 1.2 (docs/benchmarks.md).
constexpr double kPairEventFrames = 4;
std::optional<std::string> pair_event_warning(const KeyframeIntervalReport& k, const Scene& scene) {
  // A fallback interval places no template: its pairs are the free solve's, not planned.
  if (scene.time.frames < 2 || k.fallback) return std::nullopt;
  const double dt = scene.time.time(1) - scene.time.time(0);
  for (const bool created : {false, true}) {
    if ((created ? k.created : k.cancelled).empty()) continue;
    // Cancelled pairs leave the first key frame's places before t_c; created ones reach the
    // second's after it.
    const double room = created ? k.t1 - k.bifurcation_t : k.bifurcation_t - k.t0;
    if (room >= kPairEventFrames * dt) continue;
    const int key = created ? k.to_keyframe : k.from_keyframe;
    const double farthest = created ? k.t1 - kPairEventFrames * dt : k.t0 + kPairEventFrames * dt;
    // The time given (solver.bifurcation_times), or the interval's middle: then the interval
    // itself is short.
    const bool given = static_cast<size_t>(k.from_keyframe) < scene.solver.bifurcation_times.size();
    const std::string advice =
        given ? fmt::format("set the time {} frames or more from the key frame (t {} {:.4g}) or use more frames",
                            kPairEventFrames, created ? "≤" : "≥", farthest)
              : "use more frames or key frames farther apart";
    return fmt::format(
        "{}: {}: between keyframes[{}] and keyframes[{}] the pairs are {} at t = {:.4g}, {:.2g} frames {} "
        "keyframes[{}] (t = {:.4g}): they {} within those frames, so the field changes abruptly there; {}",
        scene.label(),
        given ? fmt::format("solver.bifurcation_times[{}]", k.from_keyframe) : std::string("solver.keyframe_topology"),
        k.from_keyframe, k.to_keyframe, created ? "created" : "cancelled", k.bifurcation_t, room / dt,
        created ? "before" : "after", key, created ? k.t1 : k.t0,
        created ? "appear and reach their places in the key frame" : "leave their places in the key frame and meet",
        advice);
  }
  return std::nullopt;
}

void report_spacetime(GenerateReport* report, const Scene& scene, int nv, std::chrono::steady_clock::time_point start,
                      const std::string& method, const SolveReport& r,
                      std::vector<KeyframeIntervalReport> intervals) {
  if (report) {
    report->method = "spatio-temporal optimization, " + method;
    report->residual = r.residual;
    report->iterations = r.iterations;
    report->keyframe_intervals = std::move(intervals);
  }
  finish_report(report, scene, nv, start);
  if (report)
    for (const KeyframeIntervalReport& k : report->keyframe_intervals) {
      if (!k.collision.empty()) report->warnings.push_back(k.collision);
      if (auto w = pair_event_warning(k, scene)) report->warnings.push_back(std::move(*w));
      for (const KeyframeIntervalReport::Match& m : k.matched)
        if (m.phase_turns != 0 || m.phase_swing > std::numbers::pi / 2)
          report->warnings.push_back(keyframe_turn_warning(k, m));
    }
}

// The spacetime generator under mpirun (solve/distributed.h), method cg or auto: no rank
// holds the whole problem. The vertices are partitioned first (the solve's partition);
// the constraints are evaluated by frames, rank r taking its turn of `chunk` frames at a
// time, and each evaluated frame is sent out in shares (petsc_scatter_frame); every rank
// interpolates its own lines in time (the first guess) and solves on its shares; the
// result is gathered on rank 0 alone (the assembled outputs need it whole), and with
// K > 1 ranks each keeps its share for its pieces of the VTK series. Ranks other than 0
// return a field of no vertices.
Field generate_spacetime_shares(const DesignSpace& space, const Scene& scene, const ConnectionLaplacian& laplacian,
                                const GenerateOptions& options, GenerateReport* report,
                                std::chrono::steady_clock::time_point start) {
  const int nv = space.mesh().num_vertices();
  const auto n = static_cast<size_t>(nv);
  const auto nf = static_cast<size_t>(scene.time.frames);
  std::vector<KeyframeIntervalReport> intervals;
  const SpaceTimeConstraints constraints(space, scene, laplacian, &intervals, options);
  VertexShares shares = petsc_vertex_shares(laplacian);
  const size_t nl = shares.owned.size();
  const auto ranks = static_cast<size_t>(shares.ranks), rank = static_cast<size_t>(shares.rank);
  std::vector<char> fixed(nl * nf, 0);
  std::vector<cplx> z(nl * nf, cplx(0, 0));
  {
    // Frames evaluated `chunk` at a time per rank (in parallel on its threads), a scratch of
    // chunk whole frames; rank r evaluates frames base + r·chunk … of each round.
    constexpr size_t kScratchEntries = size_t{1} << 22;
    const size_t chunk = std::clamp<size_t>(kScratchEntries / std::max<size_t>(n, 1), 1, 16);
    std::vector<char> f(chunk * n);
    std::vector<cplx> v(chunk * n);
    for (size_t base = 0; base < nf; base += ranks * chunk) {
      check_cancelled(options);
      std::exception_ptr failure;
      auto evaluate = [&](size_t c) {
        const size_t j = base + rank * chunk + c;
        if (j >= nf) return;
        const std::span<char> fj(f.data() + c * n, n);
        const std::span<cplx> vj(v.data() + c * n, n);
        std::fill(fj.begin(), fj.end(), char{0});
        std::fill(vj.begin(), vj.end(), cplx(0, 0));
        constraints.frame(static_cast<int>(j), fj, vj);
      };
      try {
        if (options.parallel)
          tbb::parallel_for(size_t{0}, chunk, evaluate);
        else
          for (size_t c = 0; c < chunk; ++c) evaluate(c);
      } catch (...) {
        failure = std::current_exception();
      }
      // Every rank must reach the frames' scatter, or none: one that failed stops all.
      if (!distributed_all(!failure)) {
        if (failure) std::rethrow_exception(failure);
        throw Error(fmt::format("{}: the constraints of a frame could not be evaluated on another rank",
                                scene.label()));
      }
      for (size_t q = 0; q < ranks * chunk && base + q < nf; ++q) {
        const size_t j = base + q, c = q % chunk;
        petsc_scatter_frame(shares, static_cast<int>(q / chunk), std::span<const char>(f.data() + c * n, n),
                            std::span<const cplx>(v.data() + c * n, n), std::span<char>(fixed.data() + j * nl, nl),
                            std::span<cplx>(z.data() + j * nl, nl));
      }
    }
  }
  // The first guess on the rank's own lines, the fixed values kept in it (the solve reads
  // them from there).
  interpolate_lines_in_time(fixed, z, z, nl, nf);
  SpaceTimeOptions st;
  st.tolerance = scene.solver.tolerance;
  st.parallel = options.parallel;
  st.distributed = true;
  st.method = scene.solver.method == SolverMethod::cg ? SpaceTimeMethod::cg : SpaceTimeMethod::automatic;
  check_cancelled(options);
  const SolveReport r = petsc_spacetime_solve_shares(laplacian, shares, scene.time.frames,
                                                     scene.solver.temporal_weight, fixed, z, st);
  std::vector<char>().swap(fixed);
  require_converged(scene, r);
  // The gather step: the whole field on rank 0 only.
  Field field(scene.time, rank == 0 ? nv : 0);
  petsc_gather_to_root(shares, z, scene.time.frames, field.data());
  if (ranks > 1) petsc_keep_share(std::move(shares), std::move(z), scene.time.frames);
  if (options.progress) options.progress(scene.time.frames, scene.time.frames);
  report_spacetime(report, scene, nv, start, r.method, r, std::move(intervals));
  return field;
}

}  // namespace

Field generate_spacetime(const DesignSpace& space, const Scene& scene,
                         const GenerateOptions& options, GenerateReport* report) {
  const auto start = std::chrono::steady_clock::now();
  const int nv = space.mesh().num_vertices();
  check_spacetime_scene(scene, nv);
  std::unique_ptr<ConnectionLaplacian> own_laplacian;
  const ConnectionLaplacian& laplacian = laplacian_for(space, scene.solver.weights, options.cache, own_laplacian);
  // Under mpirun (solve/distributed.h) each rank builds and keeps its share only (no warm
  // start: a `tvf generate` solves once); the "modes" method (whose applicability is a
  // check on the whole fixed set) and bicgstab take the replicated path below.
  if (distributed_active() &&
      (scene.solver.method == SolverMethod::automatic || scene.solver.method == SolverMethod::cg))
    return generate_spacetime_shares(space, scene, laplacian, options, report, start);
  SpaceTimeProblem problem;  // its laplacian stays empty: `laplacian` is used
  std::vector<KeyframeIntervalReport> intervals;
  spacetime_constraints(space, scene, laplacian, options, problem.fixed, problem.values, &intervals);
  Field field(scene.time, nv);
  // The solver object: the cache's when it was made for these frames and temporal weight
  // (it keeps its set-up and the temporal modes of its last solve), else a new one.
  std::unique_ptr<SpaceTimeSolver> own_solver;
  const SpaceTimeSolver* solver_ptr = nullptr;
  bool warm = false;
  if (options.cache) {
    GenerateCache::State& c = options.cache->state();
    if (!c.spacetime || c.frames != scene.time.frames || c.temporal_weight != scene.solver.temporal_weight) {
      c.spacetime = std::make_unique<SpaceTimeSolver>(laplacian, scene.time.frames, scene.solver.temporal_weight);
      c.frames = scene.time.frames;
      c.temporal_weight = scene.solver.temporal_weight;
      c.last.clear();
    }
    solver_ptr = c.spacetime.get();
    warm = c.last.size() == field.data().size();
  } else {
    own_solver = std::make_unique<SpaceTimeSolver>(laplacian, scene.time.frames, scene.solver.temporal_weight);
    solver_ptr = own_solver.get();
  }
  const SpaceTimeSolver& solver = *solver_ptr;
  if (warm) {
    // Warm start: the last solution, with this problem's fixed values where it fixes them.
    GenerateCache::State& c = options.cache->state();
    std::copy(c.last.begin(), c.last.end(), field.data().begin());
    for (size_t k = 0; k < problem.fixed.size(); ++k)
      if (problem.fixed[k]) field.data()[k] = problem.values[k];
    ++c.warm;
  } else {
    solver.interpolate_in_time(problem.fixed, problem.values, field.data());
  }
  SpaceTimeOptions st;
  st.tolerance = scene.solver.tolerance;
  st.parallel = options.parallel;
  st.distributed = true;  // all ranks' solve under mpirun (solve/distributed.h)
  switch (scene.solver.method) {
    case SolverMethod::automatic: st.method = SpaceTimeMethod::automatic; break;
    case SolverMethod::cg: st.method = SpaceTimeMethod::cg; break;
    case SolverMethod::bicgstab: st.method = SpaceTimeMethod::bicgstab_jacobi; break;
    case SolverMethod::modes:
      if (!solver.modes_apply(problem.fixed))
        throw_input_error(scene.label(), "solver.method",
                          "\"modes\" needs the same fixed vertices at every frame between two key frames "
                          "(key frames and elements that stay put); a moving element needs \"cg\" or \"auto\"");
      st.method = SpaceTimeMethod::modes;
      break;
  }
  check_cancelled(options);
  // Under mpirun the solve is PETSc's (solve/distributed.h), which reads the fixed values
  // from z itself (the first guess holds them at every fixed entry): the separate copy of
  // frames × |V| values is freed before it, one replicated field fewer on every rank.
  const bool shared_solve = distributed_active() && st.method != SpaceTimeMethod::bicgstab_jacobi;
  if (shared_solve) std::vector<cplx>().swap(problem.values);
  const std::span<const cplx> values = shared_solve ? std::span<const cplx>(field.data()) : problem.values;
  const SolveReport r = solver.solve(problem.fixed, values, field.data(), st);
  check_cancelled(options);
  if (options.progress) options.progress(scene.time.frames, scene.time.frames);
  require_converged(scene, r);
  if (options.cache) options.cache->state().last.assign(field.data().begin(), field.data().end());
  report_spacetime(report, scene, nv, start, r.method + (warm ? " (warm start)" : ""), r, std::move(intervals));
  return field;
}

Field generate(const DesignSpace& space, const Scene& scene, const GenerateOptions& options,
               GenerateReport* report) {
  // The first frame's values are final only when nothing changes frames afterwards.
  GenerateOptions o = options;
  if (!scene.edits.empty() || scene.incompressible) o.first_frame_done = nullptr;
  Field field = generate_unedited(space, scene, o, report);
  check_cancelled(options);
  if (report) {
    auto w = domain_warnings(space, scene);
    report->warnings.insert(report->warnings.end(), w.begin(), w.end());
  }
  // Under mpirun the spacetime generator leaves the field whole on rank 0 alone (the
  // others keep their shares: solve/distributed.h): the edits and the projection are rank 0's.
  if (field.num_vertices() != space.mesh().num_vertices()) return field;
  // The scene's edits, in order, on the generated field (DESIGN §7; edit/field_editor.h).
  const auto start = std::chrono::steady_clock::now();
  const std::vector<EditReport> edits = apply_scene_edits(space, scene, field);
  if (report && !edits.empty()) {
    for (const EditReport& e : edits) report->edits.push_back(e.summary);
    report->seconds += std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
  }
  // Last: the divergence-free projection, so that neither the generator nor an edit can
  // leave divergence in the field the scene asks to be incompressible.
  if (scene.incompressible && options.project) {
    IncompressibleOptions io;
    io.boundary = *scene.incompressible;
    io.parallel = options.parallel;
    IncompressibleReport r = make_incompressible(space.bundle(), field, io);
    if (report) {
      report->seconds += r.seconds;
      report->incompressible = std::move(r);
    }
  }
  return field;
}

void check_cancelled(const GenerateOptions& options) {
  if (options.cancel && options.cancel->load(std::memory_order_relaxed)) throw GenerationCancelled();
}

void check_scene_on_domain(const DesignSpace& space, const Scene& scene, const std::string& label) {
  if (space.planar()) return;
  const std::string name = label.empty() ? scene.label() : label;
  const Mesh& mesh = space.mesh();
  const double far = 0.25 * space.diameter();
  auto check = [&](const Vec3& x, const std::string& where) {
    const double d = (surface_position(mesh, space.locate(x)) - x).norm();
    if (!(d <= far))
      throw_input_error(name, where,
                        fmt::format("({}, {}, {}) is {:.3g} from the surface, more than a quarter of its size ({:.3g}, "
                                    "its bounding box's diagonal over 4): points are moved onto the surface, but one "
                                    "this far off lands wherever the nearest part of it happens to be; give a point "
                                    "on the surface (was the scene made for another mesh, or in other units?)",
                                    x.x(), x.y(), x.z(), d, far));
  };
  auto elements = [&](const std::vector<Element>& list, const std::string& prefix) {
    for (size_t i = 0; i < list.size(); ++i) {
      const std::string at = fmt::format("{}[{}]", prefix, i);
      if (const auto* e = std::get_if<SingularElement>(&list[i]))
        for (size_t k = 0; k < e->path.size(); ++k) check(e->path[k].position, fmt::format("{}.path[{}]", at, k));
      else if (const auto* r = std::get_if<RegularElement>(&list[i]))
        for (size_t k = 0; k < r->pathline.size(); ++k)
          check(r->pathline[k].position, fmt::format("{}.pathline[{}]", at, k));
      else if (const auto* b = std::get_if<BifurcationElement>(&list[i]))
        check(b->at.position, at + ".at");
      else if (const auto* sl = std::get_if<StreaklineElement>(&list[i]))
        for (size_t k = 0; k < sl->points.size(); ++k) check(sl->points[k], fmt::format("{}.points[{}]", at, k));
    }
  };
  elements(scene.elements, "elements");
  for (size_t k = 0; k < scene.keyframes.size(); ++k) {
    const Keyframe& f = scene.keyframes[k];
    for (size_t j = 0; j < f.elements.size(); ++j)
      check(f.elements[j].at, fmt::format("keyframes[{}].elements[{}].at", k, j));
    for (size_t j = 0; j < f.streamlines.size(); ++j)
      for (size_t m = 0; m < f.streamlines[j].points.size(); ++m)
        check(f.streamlines[j].points[m], fmt::format("keyframes[{}].streamlines[{}].points[{}]", k, j, m));
  }
  if (scene.deform) {
    elements(scene.deform->base, "deform.base.elements");
    for (size_t j = 0; j < scene.deform->streamlines.size(); ++j)
      check(scene.deform->streamlines[j].seed, fmt::format("deform.streamlines[{}].seed", j));
  }
  // Sketched streaklines that meet themselves: the scene reader refuses them on planar
  // domains; on a surface the sketch is known only once it is snapped onto it.
  check_surface_sketches(space, scene, name);
}

Field generate_unedited(const DesignSpace& space, const Scene& scene, const GenerateOptions& options,
                        GenerateReport* report) {
  check_cancelled(options);
  check_scene_on_domain(space, scene);
  switch (scene.generator) {
    case Generator::basis: return generate_basis_sum(space, scene, options, report);
    case Generator::constrained: return generate_constrained(space, scene, options, report);
    case Generator::spacetime: return generate_spacetime(space, scene, options, report);
    case Generator::deform: return generate_deform(space, scene, options, report);
  }
  TVF_CHECK(false, "unknown generator");
}

}  // namespace tvf
