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

#include <tbb/enumerable_thread_specific.h>
#include <tbb/parallel_for.h>

#include <algorithm>
#include <chrono>
#include <cmath>
#include <mutex>

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
  int warm = 0, reused = 0;

  void clear() {
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

void spacetime_constraints(const DesignSpace& space, const Scene& scene, const ConnectionLaplacian& laplacian,
                           const GenerateOptions& options, std::vector<char>& fixed, std::vector<cplx>& values,
                           std::vector<KeyframeIntervalReport>* intervals) {
  const int nv = space.mesh().num_vertices();
  const auto n = static_cast<size_t>(nv);
  const auto frames = static_cast<size_t>(scene.time.frames);
  fixed.assign(n * frames, 0);
  values.assign(n * frames, cplx(0, 0));

  // Key frames: whole frames held fixed.
  std::vector<char> is_key(frames, 0);
  const bool matched = scene.solver.keyframe_topology == KeyframeTopology::matched;
  std::vector<std::vector<cplx>> key_fields(matched ? scene.keyframes.size() : 0);
  for (size_t k = 0; k < scene.keyframes.size(); ++k) {
    const auto j = static_cast<size_t>(keyframe_frame(scene, scene.keyframes[k].t));
    if (is_key[j])
      throw_input_error(scene.label(), fmt::format("keyframes[{}].t", k),
                        fmt::format("t = {} falls on frame {}, which another key frame already holds; "
                                    "use more frames or move the key frame",
                                    scene.keyframes[k].t, j));
    is_key[j] = 1;
    const std::vector<cplx> key = keyframe_field(space, scene, k, laplacian);
    std::fill_n(fixed.begin() + static_cast<std::ptrdiff_t>(j * n), n, char{1});
    std::copy(key.begin(), key.end(), values.begin() + static_cast<std::ptrdiff_t>(j * n));
    if (matched) key_fields[k] = key;
  }
  // Topology kept between key frames (keyframe_topology.h): moving constraints and
  // templates, added at every other frame below.
  std::optional<KeyframeTopologyPlan> plan;
  if (matched) {
    plan.emplace(space, scene, key_fields);
    if (intervals) *intervals = plan->intervals();
  }

  // Element regions at every other frame (key frames and elements combine in one solve).
  const std::vector<CompiledElement> elements = compile(scene);
  const double d = scene.falloff / (space.diameter() * space.diameter());
  const StreaklineConstraints streaklines(space, scene);
  GenerateOptions quiet = options;
  quiet.progress = nullptr;
  for_each_frame(scene.time.frames, quiet, [&](int j) {
    if (is_key[static_cast<size_t>(j)]) return;
    const std::span<char> f(fixed.data() + static_cast<size_t>(j) * n, n);
    const std::span<cplx> v(values.data() + static_cast<size_t>(j) * n, n);
    constrain_elements(space, scene, elements, scene.time.time(j), d, f, v);
    if (plan) plan->constrain(space, scene, scene.time.time(j), d, f, v);
    streaklines.constrain(scene.time.time(j), f, v);
  });
}

}  // namespace

Field generate_spacetime(const DesignSpace& space, const Scene& scene,
                         const GenerateOptions& options, GenerateReport* report) {
  const auto start = std::chrono::steady_clock::now();
  const int nv = space.mesh().num_vertices();
  check_spacetime_scene(scene, nv);
  std::unique_ptr<ConnectionLaplacian> own_laplacian;
  const ConnectionLaplacian& laplacian = laplacian_for(space, scene.solver.weights, options.cache, own_laplacian);
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
  if (!r.success)
    throw_input_error(scene.label(), "solver.tolerance",
                      fmt::format("the space-time solve stopped at relative residual {:.2e} after {} "
                                  "iterations, short of the tolerance {:.1e}",
                                  r.residual, r.iterations, scene.solver.tolerance));
  if (options.cache) options.cache->state().last.assign(field.data().begin(), field.data().end());
  if (report) {
    report->method = "spatio-temporal optimization, " + r.method + (warm ? " (warm start)" : "");
    report->residual = r.residual;
    report->iterations = r.iterations;
    report->keyframe_intervals = std::move(intervals);
  }
  finish_report(report, scene, nv, start);
  if (report)
    for (const KeyframeIntervalReport& k : report->keyframe_intervals)
      if (!k.collision.empty()) report->warnings.push_back(k.collision);
  return field;
}

Field generate(const DesignSpace& space, const Scene& scene, const GenerateOptions& options,
               GenerateReport* report) {
  // The first frame's values are final only when nothing changes frames afterwards.
  GenerateOptions o = options;
  if (!scene.edits.empty() || scene.incompressible) o.first_frame_done = nullptr;
  Field field = generate_unedited(space, scene, o, report);
  check_cancelled(options);
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

Field generate_unedited(const DesignSpace& space, const Scene& scene, const GenerateOptions& options,
                        GenerateReport* report) {
  check_cancelled(options);
  switch (scene.generator) {
    case Generator::basis: return generate_basis_sum(space, scene, options, report);
    case Generator::constrained: return generate_constrained(space, scene, options, report);
    case Generator::spacetime: return generate_spacetime(space, scene, options, report);
    case Generator::deform: return generate_deform(space, scene, options, report);
  }
  TVF_CHECK(false, "unknown generator");
}

}  // namespace tvf
