#include "tvf/edit/field_editor.h"

#include "tvf/analysis/singularities.h"
#include "tvf/analysis/topology.h"
#include "tvf/scene/design_tolerance.h"
#include "tvf/field/field_sampler.h"
#include "tvf/mesh/chart_inverse.h"
#include "tvf/solve/spacetime.h"

#include <fmt/format.h>
#include <tbb/task_arena.h>

#include <algorithm>
#include <cmath>
#include <functional>
#include <limits>
#include <map>
#include <optional>

namespace tvf {

// Frames [first, last] re-solved by the space-time solve: free[k] (|V| entries, 1 = free)
// for frame first + k, empty for a frame held fixed.
struct FieldEditor::Window {
  int first = 0;
  int last = -1;
  std::vector<std::vector<char>> free;
};

namespace {

std::string where(const Vec3& p) {
  return p.z() == 0 ? fmt::format("({:.3g}, {:.3g})", p.x(), p.y())
                    : fmt::format("({:.3g}, {:.3g}, {:.3g})", p.x(), p.y(), p.z());
}
std::string name(const Singularity& s) {
  return fmt::format("{} at {}", to_string(s.type), where(s.position));
}

size_t nearest(const std::vector<Singularity>& sings, const Vec3& p) {
  size_t best = 0;
  for (size_t k = 1; k < sings.size(); ++k)
    if ((sings[k].position - p).squaredNorm() < (sings[best].position - p).squaredNorm()) best = k;
  return best;
}

// Runs a solve on one thread: parallel reductions may add in any order, and replaying the
// edits of a scene must give the same field bit for bit.
template <class Fn>
SolveReport deterministic(Fn&& fn) {
  tbb::task_arena one(1);
  return one.execute(fn);
}

LaplacianWeights hermitian(LaplacianWeights w) {
  return w == LaplacianWeights::mean_value ? LaplacianWeights::cotan : w;
}

// Singularity tracks through the paths of a topology: paths continue each other across
// type changes (the old path's last sample is the new path's first), and begin or end at
// bifurcations.
struct Tracks {
  std::vector<int> next, prev, created_by, cancelled_by;

  explicit Tracks(const Topology& topo) {
    const size_t n = topo.paths.size();
    next.assign(n, -1);
    prev.assign(n, -1);
    created_by.assign(n, -1);
    cancelled_by.assign(n, -1);
    for (size_t b = 0; b < topo.bifurcations.size(); ++b)
      for (int p : topo.bifurcations[b].paths) {
        if (p < 0) continue;
        (topo.bifurcations[b].kind == BifurcationKind::creation ? created_by : cancelled_by)[static_cast<size_t>(p)] =
            static_cast<int>(b);
      }
    for (size_t p = 0; p < n; ++p) {
      const auto& a = topo.paths[p];
      if (cancelled_by[p] >= 0 || a.points.empty()) continue;
      for (size_t q = 0; q < n; ++q) {
        const auto& c = topo.paths[q];
        if (q == p || created_by[q] >= 0 || prev[q] >= 0 || c.points.empty() || c.index != a.index) continue;
        if (c.points.front().t == a.points.back().t && c.points.front().position == a.points.back().position) {
          next[p] = static_cast<int>(q);
          prev[q] = static_cast<int>(p);
          break;
        }
      }
    }
  }
  // The paths of the track from p onwards in time direction sigma (+1 forward).
  std::vector<int> follow(int p, int sigma) const {
    std::vector<int> out{p};
    for (int q = sigma > 0 ? next[static_cast<size_t>(p)] : prev[static_cast<size_t>(p)]; q >= 0;
         q = sigma > 0 ? next[static_cast<size_t>(q)] : prev[static_cast<size_t>(q)])
      out.push_back(q);
    return out;
  }
  // The bifurcation ending the track at its last path in direction sigma (-1: none).
  int end_bifurcation(int last, int sigma) const {
    return sigma > 0 ? cancelled_by[static_cast<size_t>(last)] : created_by[static_cast<size_t>(last)];
  }
};

std::vector<char> membership(size_t paths, const std::vector<int>& track) {
  std::vector<char> in(paths, 0);
  for (int p : track) in[static_cast<size_t>(p)] = 1;
  return in;
}

// The singularities of frame j on tracks a and b (indices into topo.singularities[j]).
std::optional<std::array<size_t, 2>> pair_at(const Topology& topo, int j, const std::vector<char>& a,
                                             const std::vector<char>& b) {
  const auto& ids = topo.singularity_path[static_cast<size_t>(j)];
  std::optional<size_t> ia, ib;
  for (size_t k = 0; k < ids.size(); ++k) {
    if (ids[k] < 0) continue;
    if (a[static_cast<size_t>(ids[k])] && !ia) ia = k;
    else if (b[static_cast<size_t>(ids[k])] && !ib) ib = k;
  }
  if (!ia || !ib) return std::nullopt;
  return std::array<size_t, 2>{*ia, *ib};
}

// How far the position (and time) an edit names may lie from the feature it names: a few
// cells and a few frames. Beyond that the edit names nothing, and picking the nearest
// feature anyway would edit something the user did not point at (issue 16).
constexpr double kReachEdges = 4.0;   // mean edge lengths
constexpr double kReachFrames = 4.0;  // frame steps

double reach_in_space(const Mesh& mesh) { return kReachEdges * mesh.mean_edge_length(); }
double reach_in_time(const TimeSampling& time) {
  return kReachFrames * (time.frames > 1 ? std::abs(time.t1 - time.t0) / (time.frames - 1) : 0.0);
}

// The nearest bifurcation (space in domain diameters and time in time ranges) among those
// within reach of `at`; nullopt when none is.
std::optional<size_t> nearest_bifurcation(const Topology& topo, const PathPoint& at, double diameter, double span,
                                          double reach_x, double reach_t) {
  std::optional<size_t> best;
  double best_d = std::numeric_limits<double>::infinity();
  for (size_t b = 0; b < topo.bifurcations.size(); ++b) {
    const auto& bf = topo.bifurcations[b];
    if ((bf.position - at.position).norm() > reach_x || std::abs(bf.t - at.t) > reach_t + 1e-12) continue;
    const double dx = (bf.position - at.position).norm() / diameter;
    const double dt = (bf.t - at.t) / span;
    const double d = dx * dx + dt * dt;
    if (d < best_d) {
      best_d = d;
      best = b;
    }
  }
  return best;
}

// The topology an edit works on (one thread: replay must be bit for bit).
Topology analyze_for_edit(const TangentBundle& bundle, const Field& field) {
  TopologyOptions options;
  options.parallel = false;
  return analyze_topology(bundle, field, options);
}

std::string bifurcation_name(const Bifurcation& b);

// The bifurcation an edit names by its space-time point `at` (the nearest within a few
// cells and frames, space in domain diameters and time in time ranges); refused when the
// field has none there.
size_t named_bifurcation(const Topology& topo, const Field& field, const Mesh& mesh, const PathPoint& at,
                         double diameter, const char* what) {
  if (topo.bifurcations.empty()) throw EditRefused(fmt::format("the field has no bifurcation to {}", what));
  const TimeSampling& time = field.time();
  const double span = time.t1 > time.t0 ? time.t1 - time.t0 : 1.0;
  const double rx = reach_in_space(mesh), rt = reach_in_time(time);
  if (const auto b = nearest_bifurcation(topo, at, diameter, span, rx, rt)) return *b;
  const size_t any = *nearest_bifurcation(topo, at, diameter, span, std::numeric_limits<double>::infinity(),
                                          std::numeric_limits<double>::infinity());
  const Bifurcation& n = topo.bifurcations[any];
  throw EditRefused(fmt::format("there is no bifurcation within {:.3g} ({} edge lengths) and {:.3g} in time ({} "
                                "frames) of {} at t = {:.3g}; the nearest is {}, {:.3g} away at a time {:.3g} apart",
                                rx, kReachEdges, rt, kReachFrames, where(at.position), at.t, bifurcation_name(n),
                                (n.position - at.position).norm(), std::abs(n.t - at.t)));
}

// Point location on a planar mesh: faces bucketed on a uniform grid of about one face per
// bucket, so a query tests a handful of faces (closest_point tests them all). Points
// outside every face fall back to closest_point.
class PlanarLocator {
public:
  explicit PlanarLocator(const Mesh& mesh) : mesh_(mesh) {
    lo_ = mesh.bbox_min().head<2>();
    const Vec2 hi = mesh.bbox_max().head<2>();
    const double side = std::max(mesh.mean_edge_length(), 1e-12);
    nx_ = std::max(1, static_cast<int>(std::ceil((hi.x() - lo_.x()) / side)));
    ny_ = std::max(1, static_cast<int>(std::ceil((hi.y() - lo_.y()) / side)));
    cell_ = Vec2((hi.x() - lo_.x()) / nx_, (hi.y() - lo_.y()) / ny_);
    buckets_.resize(static_cast<size_t>(nx_) * static_cast<size_t>(ny_));
    for (int f = 0; f < mesh.num_faces(); ++f) {
      Vec2 a = Vec2::Constant(std::numeric_limits<double>::infinity()), b = -a;
      for (int v : mesh.face(f)) {
        a = a.cwiseMin(mesh.position(v).head<2>());
        b = b.cwiseMax(mesh.position(v).head<2>());
      }
      const auto [ix0, iy0] = bucket(a);
      const auto [ix1, iy1] = bucket(b);
      for (int iy = iy0; iy <= iy1; ++iy)
        for (int ix = ix0; ix <= ix1; ++ix)
          buckets_[static_cast<size_t>(iy) * static_cast<size_t>(nx_) + static_cast<size_t>(ix)].push_back(f);
    }
  }
  SurfacePoint locate(const Vec3& x) const {
    const auto [ix, iy] = bucket(x.head<2>());
    for (int f : buckets_[static_cast<size_t>(iy) * static_cast<size_t>(nx_) + static_cast<size_t>(ix)]) {
      const Face& c = mesh_.face(f);
      const Vec2 p0 = mesh_.position(c[0]).head<2>(), p1 = mesh_.position(c[1]).head<2>(),
                 p2 = mesh_.position(c[2]).head<2>();
      const Vec2 q = x.head<2>();
      const double area = (p1 - p0).x() * (p2 - p0).y() - (p1 - p0).y() * (p2 - p0).x();
      if (area == 0) continue;
      const double b1 = ((q - p0).x() * (p2 - p0).y() - (q - p0).y() * (p2 - p0).x()) / area;
      const double b2 = ((p1 - p0).x() * (q - p0).y() - (p1 - p0).y() * (q - p0).x()) / area;
      const double b0 = 1 - b1 - b2;
      constexpr double eps = -1e-12;
      if (b0 >= eps && b1 >= eps && b2 >= eps) return {f, Vec3(b0, b1, b2)};
    }
    return closest_point(mesh_, x);
  }

private:
  std::pair<int, int> bucket(const Vec2& p) const {
    const int ix = std::clamp(static_cast<int>(std::floor((p.x() - lo_.x()) / cell_.x())), 0, nx_ - 1);
    const int iy = std::clamp(static_cast<int>(std::floor((p.y() - lo_.y()) / cell_.y())), 0, ny_ - 1);
    return {ix, iy};
  }
  const Mesh& mesh_;
  Vec2 lo_, cell_;
  int nx_ = 1, ny_ = 1;
  std::vector<std::vector<int>> buckets_;
};

std::string bifurcation_name(const Bifurcation& b) {
  return fmt::format("the {} bifurcation at {} at t = {:.3g}", to_string(b.kind), where(b.position), b.t);
}

// How close an edited field must put a bifurcation to count as the one asked for: the
// design check's tolerances (scene/design_tolerance.h), so an edit accepted here is one
// the design check finds as edited.
struct Faithful {
  double x = 0, t = 0;  // world units, time units
  Faithful(const Mesh& mesh, const TimeSampling& time) {
    x = kDesignPositionTolerance * mesh.mean_edge_length();
    t = kDesignTimeTolerance * (time.frames > 1 ? std::abs(time.t1 - time.t0) / (time.frames - 1) : 0.0);
  }
  bool near(const Vec3& p, double tp, const Vec3& q, double tq) const {
    return (p - q).norm() <= x && std::abs(tp - tq) <= t + 1e-12;
  }
};

// Refuses a removal whose result is not what was asked: a removed bifurcation still there,
// or a bifurcation the field did not have before (the fill made new pairs).
void verify_removal(const Topology& before, const Topology& after, const std::vector<const Bifurcation*>& removed,
                    const Faithful& tol, const Bifurcation& named) {
  for (const Bifurcation* r : removed)
    for (const Bifurcation& b : after.bifurcations)
      if (tol.near(b.position, b.t, r->position, r->t))
        throw EditRefused(fmt::format("cannot remove {} faithfully: after the edit {} is still there",
                                      bifurcation_name(named), bifurcation_name(b)));
  for (const Bifurcation& b : after.bifurcations) {
    const bool old = std::any_of(before.bifurcations.begin(), before.bifurcations.end(), [&](const Bifurcation& a) {
      return a.kind == b.kind && tol.near(a.position, a.t, b.position, b.t);
    });
    if (!old)
      throw EditRefused(fmt::format("cannot remove {} faithfully: the edit would make a new bifurcation, {} "
                                    "({} bifurcations after it, {} before)",
                                    bifurcation_name(named), bifurcation_name(b), after.bifurcations.size(),
                                    before.bifurcations.size()));
  }
}

}  // namespace

FieldEditor::FieldEditor(const DesignSpace& space, EditSettings settings)
    : space_(space), settings_(settings),
      laplacian_(connection_laplacian(space.bundle(), settings.weights)),
      st_laplacian_(settings.weights == hermitian(settings.weights)
                        ? laplacian_
                        : connection_laplacian(space.bundle(), hermitian(settings.weights))),
      region_(space.bundle(), laplacian_, settings.region) {}

void FieldEditor::resolve_window(Field& field, const Window& window, EditReport& report) const {
  const int n_frames = field.frames();
  const auto nv = static_cast<size_t>(field.num_vertices());
  bool any = false;
  for (const auto& f : window.free)
    any = any || std::any_of(f.begin(), f.end(), [](char c) { return c != 0; });
  if (!any) return;
  // The sub-problem: the window plus one fixed frame on each side (the time couplings
  // reach only the next frame, so this is the whole problem's solution on the window).
  const int lo = std::max(0, window.first - 1);
  const int hi = std::min(n_frames - 1, window.last + 1);
  const auto frames = static_cast<size_t>(hi - lo + 1);
  std::vector<char> fixed(frames * nv, 1);
  std::vector<cplx> values(frames * nv);
  for (int j = lo; j <= hi; ++j) {
    const auto k = static_cast<size_t>(j - lo);
    const auto src = field.frame(j);
    std::copy(src.begin(), src.end(), values.begin() + static_cast<std::ptrdiff_t>(k * nv));
    const int w = j - window.first;
    if (w < 0 || j > window.last || window.free[static_cast<size_t>(w)].empty()) continue;
    const auto& free = window.free[static_cast<size_t>(w)];
    for (size_t v = 0; v < nv; ++v)
      if (free[v]) fixed[k * nv + v] = 0;
  }
  std::vector<cplx> z = values;
  const SpaceTimeSolver solver(st_laplacian_, static_cast<int>(frames), settings_.temporal_weight);
  SpaceTimeOptions options;
  options.tolerance = settings_.tolerance;
  options.parallel = false;  // deterministic reductions: replaying edits is bit for bit
  const SolveReport r = deterministic([&] { return solver.solve(fixed, values, z, options); });
  if (!r.success)
    throw EditRefused(fmt::format("the space-time re-solve of frames {}–{} stopped at relative residual {:.2e} "
                                  "after {} iterations, short of the tolerance {:.1e}",
                                  window.first, window.last, r.residual, r.iterations, settings_.tolerance));
  for (int j = lo; j <= hi; ++j) {
    auto dst = field.frame(j);
    std::copy_n(z.begin() + static_cast<std::ptrdiff_t>(static_cast<size_t>(j - lo) * nv), nv, dst.begin());
  }
  report.iterations += r.iterations;
  report.residual = std::max(report.residual, r.residual);
  if (report.window_first < 0 || window.first < report.window_first) report.window_first = window.first;
  report.window_last = std::max(report.window_last, window.last);
}

EditReport FieldEditor::apply(Field& field, const Edit& edit) {
  struct Visit {
    FieldEditor& e;
    Field& f;
    EditReport operator()(const CancelEdit& x) const { return e.cancel(f, x); }
    EditReport operator()(const RemoveBifurcationEdit& x) const { return e.remove_bifurcation(f, x); }
    EditReport operator()(const MoveBifurcationEdit& x) const { return e.move_bifurcation(f, x); }
    EditReport operator()(const SmoothEdit& x) const { return e.smooth(f, x); }
  };
  return std::visit(Visit{*this, field}, edit);
}

namespace {

int window_frames(const Field& field, double window) {
  return static_cast<int>(std::lround(window * (field.frames() - 1)));
}

// Window around key frames: every non-key frame within `w` of a key frame is freed on the
// interior of the nearest key frame's region.
void add_flanks(int frames, const std::map<int, std::vector<char>>& key_interior, int w, int& first, int& last,
                std::vector<std::vector<char>>& free) {
  if (key_interior.empty()) return;
  const int kf = key_interior.begin()->first, kl = key_interior.rbegin()->first;
  first = std::max(0, kf - w);
  last = std::min(frames - 1, kl + w);
  free.assign(static_cast<size_t>(last - first + 1), {});
  for (int j = first; j <= last; ++j) {
    if (key_interior.count(j)) continue;
    // Nearest key frame.
    auto it = key_interior.lower_bound(j);
    const std::vector<char>* best = nullptr;
    int best_d = std::numeric_limits<int>::max();
    if (it != key_interior.end()) {
      best = &it->second;
      best_d = it->first - j;
    }
    if (it != key_interior.begin()) {
      auto p = std::prev(it);
      if (j - p->first < best_d) {
        best = &p->second;
        best_d = j - p->first;
      }
    }
    // Frames within the window (the frames next to it stay fixed); not the first or last
    // frame of the time range: nothing beyond them would hold the change back (the re-solved
    // frames would all copy the key frame).
    if (best && best_d <= w && j > 0 && j < frames - 1) free[static_cast<size_t>(j - first)] = *best;
  }
}

}  // namespace

// The time window around edited key frames. First try: the key frames' re-solved vertices
// (key_free; pasted vertices stay fixed) free together with the flanks, so the fills of
// consecutive key frames are smoothed in time too; kept when every key frame still has the
// singularities the frame-by-frame edit gave it (same count, same indices, each within
// 1.5 mean edge lengths). Otherwise only the flanks (frames beyond the key frames, free on
// flank_free of the nearest key frame) are re-solved.
void FieldEditor::smooth_around(Field& field, const std::map<int, std::vector<char>>& key_free,
                                const std::map<int, std::vector<char>>& flank_free, int w,
                                EditReport& report) const {
  Window window;
  add_flanks(field.frames(), flank_free, w, window.first, window.last, window.free);
  if (key_free.size() > 1) {
    Window both = window;
    for (const auto& [j, free] : key_free) both.free[static_cast<size_t>(j - both.first)] = free;
    Field trial = field;
    EditReport trial_report = report;
    bool ok = true;
    try {
      resolve_window(trial, both, trial_report);
    } catch (const EditRefused&) {
      ok = false;
    }
    const double tolerance = 1.5 * space_.mesh().mean_edge_length();
    for (auto it = key_free.begin(); ok && it != key_free.end(); ++it) {
      const auto a = find_singularities(space_.bundle(), field, it->first);
      const auto b = find_singularities(space_.bundle(), trial, it->first);
      ok = a.size() == b.size();
      for (const Singularity& x : b) {
        if (!ok) break;
        const Singularity& y = a[nearest(a, x.position)];
        ok = y.index == x.index && (y.position - x.position).norm() <= tolerance;
      }
    }
    if (ok) {
      field = std::move(trial);
      report = std::move(trial_report);
      return;
    }
  }
  resolve_window(field, window, report);
}

EditReport FieldEditor::cancel(Field& field, const CancelEdit& edit) {
  const int j = edit.frame;
  if (j < 0 || j >= field.frames())
    throw EditRefused(fmt::format("frame {} is outside the field's frames 0–{}", j, field.frames() - 1));
  const auto sings = find_singularities(space_.bundle(), field, j);
  if (sings.size() < 2)
    throw EditRefused(fmt::format("frame {} has {} singularit{}, and cancelling needs a pair", j, sings.size(),
                                  sings.size() == 1 ? "y" : "ies"));
  const size_t ia = nearest(sings, edit.pair[0]);
  const size_t ib = nearest(sings, edit.pair[1]);
  const double reach = reach_in_space(space_.mesh());
  for (const auto& [k, given] : {std::pair{ia, edit.pair[0]}, std::pair{ib, edit.pair[1]}}) {
    const double d = (sings[k].position - given).norm();
    if (d > reach)
      throw EditRefused(fmt::format("there is no singularity within {:.3g} ({} edge lengths) of {} at frame {}; the "
                                    "nearest is the {}, {:.3g} away",
                                    reach, kReachEdges, where(given), j, name(sings[k]), d));
  }
  if (ia == ib)
    throw EditRefused(fmt::format("both positions name the same singularity, the {} at frame {}", name(sings[ia]), j));
  if (sings[ia].index + sings[ib].index != 0)
    throw EditRefused(fmt::format("the {} and the {} at frame {} both have index {:+d}; only a pair of index +1 "
                                  "and −1 cancels",
                                  name(sings[ia]), name(sings[ib]), j, sings[ia].index));
  const RegionResult r = region_.cancel(field.frame(j), sings[ia].where.face, sings[ib].where.face);
  if (!r.success) {
    std::string why;
    if (r.blocked_by >= 0) {
      const auto it = std::find_if(sings.begin(), sings.end(),
                                   [&](const Singularity& s) { return s.where.face == r.blocked_by; });
      why = it != sings.end() ? fmt::format("the region would swallow the {}", name(*it))
                              : "the region would swallow another singularity";
    } else {
      why = fmt::format("a region grown by {} rings still holds {} singular faces", r.growths, r.remaining);
    }
    throw EditRefused(fmt::format("cannot cancel the {} and the {} at frame {}: {}", name(sings[ia]),
                                  name(sings[ib]), j, why));
  }
  Field out = field;
  std::copy(r.values.begin(), r.values.end(), out.frame(j).begin());
  EditReport report;
  report.key_frames = {j};
  report.region_faces = static_cast<int>(r.faces.size());
  report.growths = r.growths;
  Window window;
  add_flanks(field.frames(), {{j, r.interior}}, window_frames(field, edit.window), window.first, window.last,
             window.free);
  resolve_window(out, window, report);
  report.summary = fmt::format("cancelled the {} and the {} at frame {} ({} faces re-solved; frames {}–{} "
                               "smoothed)",
                               name(sings[ia]), name(sings[ib]), j, r.faces.size(), window.first, window.last);
  field = std::move(out);
  return report;
}

EditReport FieldEditor::remove_bifurcation(Field& field, const RemoveBifurcationEdit& edit) {
  const TangentBundle& bundle = space_.bundle();
  const Topology topo = analyze_for_edit(bundle, field);
  const Bifurcation& bif = topo.bifurcations[named_bifurcation(topo, field, space_.mesh(), edit.at, space_.diameter(), "remove")];
  const TimeSampling& time = field.time();
  const Tracks tracks(topo);
  const int sigma = bif.kind == BifurcationKind::creation ? 1 : -1;
  const std::vector<int> ta = tracks.follow(bif.paths[0], sigma);
  const std::vector<int> tb = tracks.follow(bif.paths[1], sigma);
  const int ea = tracks.end_bifurcation(ta.back(), sigma);
  const int eb = tracks.end_bifurcation(tb.back(), sigma);
  const bool loop = ea >= 0 && ea == eb;
  const size_t np = topo.paths.size();
  std::vector<char> in_a = membership(np, ta), in_b = membership(np, tb);

  // Pairs to cancel, frame by frame: (frame, face of a, face of b).
  struct Cut {
    int frame;
    int face_a, face_b;
  };
  std::vector<Cut> cuts;
  std::string what;
  // Three-path case: per cut frame, the tracks of the singularity that survives there.
  std::map<int, const std::vector<char>*> survivor;
  std::vector<char> in_1, in_2;
  std::vector<const Bifurcation*> removed{&bif};  // what must be gone afterwards
  if (loop || (ea < 0 && eb < 0)) {
    for (int j = 0; j < field.frames(); ++j) {
      if (sigma * (time.time(j) - bif.t) <= 0) continue;
      if (const auto p = pair_at(topo, j, in_a, in_b))
        cuts.push_back({j, topo.singularities[static_cast<size_t>(j)][(*p)[0]].where.face,
                        topo.singularities[static_cast<size_t>(j)][(*p)[1]].where.face});
    }
    what = loop ? "an isolated loop" : "an isolated pair";
    if (loop) removed.push_back(&topo.bifurcations[static_cast<size_t>(ea)]);
  } else {
    // The three-path case (paper §8.2): exactly one of the two tracks (the middle one) ends
    // in a second bifurcation, with a third singularity whose track runs on to the other
    // time boundary (or the domain boundary). Over the overlap the middle singularity is
    // cancelled with one of the two outer ones, leaving one singularity.
    if (ea >= 0 && eb >= 0)
      throw EditRefused(fmt::format("{} is not isolated: both of its singularities end in other bifurcations "
                                    "(only isolated bifurcations and the three-path case of paper §8.2 can be "
                                    "removed)",
                                    bifurcation_name(bif)));
    const bool a_middle = ea >= 0;
    const std::vector<int>& middle = a_middle ? ta : tb;
    const std::vector<int>& outer1 = a_middle ? tb : ta;
    const Bifurcation& other = topo.bifurcations[static_cast<size_t>(a_middle ? ea : eb)];
    const int m_last = middle.back();
    const int third_start = other.paths[0] == m_last ? other.paths[1] : other.paths[0];
    // The third singularity lives on the other side of `other` in time.
    const std::vector<int> outer2 = tracks.follow(third_start, -sigma);
    if (tracks.end_bifurcation(outer2.back(), -sigma) >= 0)
      throw EditRefused(fmt::format("{} is not isolated: its singularities are connected through {} to further "
                                    "bifurcations (only isolated bifurcations and the three-path case of paper "
                                    "§8.2 can be removed)",
                                    bifurcation_name(bif), bifurcation_name(other)));
    const std::vector<char> in_m = membership(np, middle);
    in_1 = membership(np, outer1);
    in_2 = membership(np, outer2);
    const double lo = std::min(bif.t, other.t), hi = std::max(bif.t, other.t);
    std::vector<int> frames;
    for (int j = 0; j < field.frames(); ++j)
      if (time.time(j) > lo && time.time(j) < hi) frames.push_back(j);
    // At each frame of the overlap the middle singularity is cancelled with the nearer outer
    // one (the pair that is about to meet, or has just been born), so the survivor is the
    // outer singularity that lives on past the nearer bifurcation; it passes from one outer
    // track to the other where they are equally near.
    for (int j : frames) {
      const auto& s = topo.singularities[static_cast<size_t>(j)];
      const auto pm1 = pair_at(topo, j, in_m, in_1);
      const auto pm2 = pair_at(topo, j, in_m, in_2);
      std::optional<std::array<size_t, 2>> p;
      if (pm1 && pm2)
        p = (s[(*pm1)[0]].position - s[(*pm1)[1]].position).norm() <=
                    (s[(*pm2)[0]].position - s[(*pm2)[1]].position).norm()
                ? pm1
                : pm2;
      else
        p = pm1 ? pm1 : pm2;
      if (p) {
        cuts.push_back({j, s[(*p)[0]].where.face, s[(*p)[1]].where.face});
        survivor[j] = p == pm1 ? &in_2 : &in_1;
      }
    }
    what = fmt::format("the three-path configuration with {}", bifurcation_name(other));
    removed.push_back(&other);
  }
  if (cuts.empty())
    throw EditRefused(fmt::format("the pair of {} exists at no frame (it lives between two frames), so there is "
                                  "nothing to remove at the frames",
                                  bifurcation_name(bif)));

  Field out = field;
  EditReport report;
  std::map<int, std::vector<char>> interiors;
  std::map<int, std::vector<int>> regions;
  int rings = 0;  // the previous frame's growth: the pair changes little from frame to frame
  for (const Cut& c : cuts) {
    const RegionResult r = region_.cancel(field.frame(c.frame), c.face_a, c.face_b, std::max(0, rings - 1));
    rings = r.growths;
    if (!r.success) {
      const auto& sings = topo.singularities[static_cast<size_t>(c.frame)];
      std::string why = fmt::format("a region grown by {} rings still holds {} singular faces", r.growths,
                                    r.remaining);
      for (const auto& s : sings)
        if (s.where.face == r.blocked_by) why = fmt::format("the region would swallow the {}", name(s));
      throw EditRefused(fmt::format("cannot remove {}: at frame {} {}", bifurcation_name(bif), c.frame, why));
    }
    std::copy(r.values.begin(), r.values.end(), out.frame(c.frame).begin());
    interiors.emplace(c.frame, r.interior);
    regions.emplace(c.frame, r.faces);
    report.key_frames.push_back(c.frame);
    report.region_faces = std::max(report.region_faces, static_cast<int>(r.faces.size()));
    report.growths = std::max(report.growths, r.growths);
  }
  // Second pass: every frame over the union of the regions, so that consecutive frames get
  // consecutive fills (the regions grown frame by frame differ, and the fills jump with
  // them). Kept only if it cancels the pair at every frame.
  if (cuts.size() > 1) {
    std::vector<char> in_union(static_cast<size_t>(space_.mesh().num_faces()), 0);
    for (const auto& [j, faces] : regions)
      for (int f : faces) in_union[static_cast<size_t>(f)] = 1;
    std::vector<int> common;
    for (size_t f = 0; f < in_union.size(); ++f)
      if (in_union[f]) common.push_back(static_cast<int>(f));
    Field second = out;
    std::map<int, std::vector<char>> second_interiors;
    bool ok = true;
    for (const Cut& c : cuts) {
      const RegionResult r = region_.cancel_in(field.frame(c.frame), c.face_a, c.face_b, common);
      if (!r.success) {
        ok = false;
        break;
      }
      std::copy(r.values.begin(), r.values.end(), second.frame(c.frame).begin());
      second_interiors.emplace(c.frame, r.interior);
      report.region_faces = std::max(report.region_faces, static_cast<int>(r.faces.size()));
    }
    if (ok) {
      out = std::move(second);
      interiors = std::move(second_interiors);
    }
  }
  if (!survivor.empty() && space_.planar()) move_survivor(out, topo, survivor, interiors, report);
  smooth_around(out, interiors, interiors, window_frames(field, edit.window), report);
  verify_removal(topo, analyze_for_edit(bundle, out), removed, Faithful(space_.mesh(), time), bif);
  report.summary = fmt::format("removed {} ({}) by cancelling the pair at frames {}–{}", bifurcation_name(bif), what,
                               cuts.front().frame, cuts.back().frame);
  field = std::move(out);
  return report;
}

// The three-path collapse leaves the survivor on one outer track, then on the other: a
// jump where the cancelled partner changes. Over the cut frames the survivor is moved to
// the straight line between its first and last positions: its neighbourhood (a disc of 3
// edge lengths) is pasted at the new place and the region between re-solved, so the old
// place is left without it. Planar domains (the neighbourhood is translated in the plane).
void FieldEditor::move_survivor(Field& out, const Topology& topo, const std::map<int, const std::vector<char>*>& survivor,
                                std::map<int, std::vector<char>>& interiors, EditReport& report) {
  const Mesh& mesh = space_.mesh();
  auto position_of = [&](int j) -> std::optional<std::pair<Vec3, int>> {
    const auto& ids = topo.singularity_path[static_cast<size_t>(j)];
    const std::vector<char>& keep = *survivor.at(j);
    for (size_t k = 0; k < ids.size(); ++k)
      if (ids[k] >= 0 && keep[static_cast<size_t>(ids[k])])
        return std::make_pair(topo.singularities[static_cast<size_t>(j)][k].position,
                              topo.singularities[static_cast<size_t>(j)][k].where.face);
    return std::nullopt;
  };
  const int f0 = survivor.begin()->first, f1 = survivor.rbegin()->first;
  const auto s0 = position_of(f0), s1 = position_of(f1);
  if (!s0 || !s1 || f1 <= f0) return;
  const PlanarLocator locator(mesh);
  const double h = mesh.mean_edge_length();
  for (const auto& [j, keep] : survivor) {
    const auto sj = position_of(j);
    if (!sj) continue;
    const double w = static_cast<double>(j - f0) / static_cast<double>(f1 - f0);
    const Vec3 target = s0->first + w * (s1->first - s0->first);
    const Vec3 offset = target - sj->first;
    if (offset.norm() < h) continue;
    Field frame(TimeSampling{0.0, 1.0, 1}, out.num_vertices());
    std::copy(out.frame(j).begin(), out.frame(j).end(), frame.frame(0).begin());
    const FieldSampler sampler(space_.bundle(), frame);
    std::vector<int> pinned;
    std::vector<cplx> values;
    for (int v = 0; v < mesh.num_vertices(); ++v) {
      if ((mesh.position(v) - target).norm() > 3 * h) continue;
      const Vec3 from = mesh.position(v) - offset;
      const SurfacePoint sp = locator.locate(from);
      if ((surface_position(mesh, sp) - from).norm() > 1e-9 * space_.diameter()) return;  // keep the jump
      pinned.push_back(v);
      values.push_back(sampler.in_face(sp, 0.0));
    }
    if (pinned.empty()) continue;
    const RegionResult r = region_.paste(out.frame(j), pinned, values, {sj->second});
    if (!r.success) continue;  // this frame keeps the survivor where it is
    std::copy(r.values.begin(), r.values.end(), out.frame(j).begin());
    std::vector<char>& in = interiors[j];
    for (size_t v = 0; v < in.size(); ++v) in[v] = in[v] || r.interior[v];
    report.growths = std::max(report.growths, r.growths);
  }
}

namespace {

// Where the moved pair's neighbourhood comes from (move_bifurcation): local coordinates
// around the bifurcation, in which the neighbourhood is translated, and their inverse.
// Planar domains: the plane's own coordinates (the neighbourhood is translated in the
// plane). Surfaces: the log map at the bifurcation (log_map.h), inverted by point location
// in the log-coordinate triangulation (chart_inverse.h); vectors are carried in the chart's
// frame (the frame at the bifurcation, parallel-transported), as element fields are.
class MoveChart {
public:
  MoveChart(const DesignSpace& space, const Vec3& at) : space_(space) {
    if (space.planar()) {
      planar_.emplace(space.mesh());
      return;
    }
    space.log_map().compute(space.locate(at), chart_);
    // The disc in which the chart is inverted: half the domain's diameter (on a unit sphere
    // about 100°, short of the cut locus at the antipode).
    inverse_.emplace(space.bundle(), chart_, 0.5 * space.diameter());
  }
  MoveChart(const MoveChart&) = delete;  // inverse_ refers to chart_
  MoveChart& operator=(const MoveChart&) = delete;
  bool planar() const { return planar_.has_value(); }
  // Local coordinates of a vertex, or of a surface point.
  cplx vertex(int v) const {
    const Vec3& x = space_.mesh().position(v);
    return planar() ? cplx(x.x(), x.y()) : chart_.coords[static_cast<size_t>(v)];
  }
  cplx point(const SurfacePoint& q, const Vec3& world) const {
    return planar() ? cplx(world.x(), world.y()) : inverse_->coords(q);
  }
  // Whether vertex v has trustworthy coordinates (inside the inverted disc).
  bool charted(int v) const { return planar() || std::abs(chart_.coords[static_cast<size_t>(v)]) <= inverse_->radius(); }
  // The surface point with local coordinates w (nullopt outside the domain or the disc).
  std::optional<SurfacePoint> locate(cplx w) const {
    if (planar()) {
      const Vec3 from(w.real(), w.imag(), 0.0);
      const SurfacePoint sp = planar_->locate(from);
      if ((surface_position(space_.mesh(), sp) - from).norm() > 1e-9 * space_.diameter()) return std::nullopt;
      return sp;
    }
    return inverse_->locate(w);
  }
  // A vector in the frame of face q.face (at the source point q) as the value at vertex v
  // after the move: on planar domains the frames are all the global frame.
  cplx carry(cplx in_face, const SurfacePoint& q, int v) const {
    if (planar()) return in_face;
    return in_face / inverse_->frame_in_face(q) * chart_.frame[static_cast<size_t>(v)];
  }
  double radius() const { return planar() ? std::numeric_limits<double>::infinity() : inverse_->radius(); }

private:
  const DesignSpace& space_;
  std::optional<PlanarLocator> planar_;
  LocalChart chart_;
  std::optional<ChartInverse> inverse_;
};

// Refuses a move whose result is not what was asked: no bifurcation of the kind moved
// within the design check's tolerances of the target (issue 16: a creation moved to
// (0.301, 0.299, 0.60) appeared 4.4 cells away), or one left at the old place.
void verify_move(const Topology& after, const Bifurcation& bif, const PathPoint& to, const Faithful& tol) {
  const Bifurcation* best = nullptr;
  double best_d = std::numeric_limits<double>::infinity();
  for (const Bifurcation& b : after.bifurcations) {
    if (b.kind != bif.kind) continue;
    const double d = (b.position - to.position).norm() / std::max(tol.x, 1e-300) +
                     std::abs(b.t - to.t) / std::max(tol.t, 1e-300);
    if (d < best_d) {
      best_d = d;
      best = &b;
    }
  }
  if (!best)
    throw EditRefused(fmt::format("cannot move {} faithfully to {} at t = {:.3g}: after the edit the field has no {} "
                                  "bifurcation",
                                  bifurcation_name(bif), where(to.position), to.t, to_string(bif.kind)));
  if (!tol.near(best->position, best->t, to.position, to.t))
    throw EditRefused(fmt::format("cannot move {} faithfully to {} at t = {:.3g}: the edit would put it at {} at t = "
                                  "{:.3g}, {:.3g} away and {:+.3g} in time (at most {:.3g} and {:.3g} are accepted); "
                                  "try a longer window, or a target nearer in time",
                                  bifurcation_name(bif), where(to.position), to.t, where(best->position), best->t,
                                  (best->position - to.position).norm(), best->t - to.t, tol.x, tol.t));
  if (!tol.near(bif.position, bif.t, to.position, to.t))
    for (const Bifurcation& b : after.bifurcations)
      if (b.kind == bif.kind && tol.near(b.position, b.t, bif.position, bif.t))
        throw EditRefused(fmt::format("cannot move {} faithfully: after the edit a {} bifurcation is still at its old "
                                      "place",
                                      bifurcation_name(bif), to_string(bif.kind)));
}

}  // namespace

EditReport FieldEditor::move_bifurcation(Field& field, const MoveBifurcationEdit& edit) {
  const TangentBundle& bundle = space_.bundle();
  const Mesh& mesh = space_.mesh();
  const Topology topo = analyze_for_edit(bundle, field);
  const Bifurcation& bif = topo.bifurcations[named_bifurcation(topo, field, space_.mesh(), edit.at, space_.diameter(), "move")];
  const TimeSampling& time = field.time();
  const double span = time.t1 > time.t0 ? time.t1 - time.t0 : 1.0;
  const Tracks tracks(topo);
  const int sigma = bif.kind == BifurcationKind::creation ? 1 : -1;
  const size_t np = topo.paths.size();
  const std::vector<char> in_a = membership(np, tracks.follow(bif.paths[0], sigma));
  const std::vector<char> in_b = membership(np, tracks.follow(bif.paths[1], sigma));

  const double tb = bif.t, tn = edit.to.t;
  const MoveChart chart(space_, bif.position);
  // The move in local coordinates: on a surface the log map of the new place.
  const SurfacePoint to_point = space_.locate(edit.to.position);
  if (chart.planar() ? !chart.locate(cplx(edit.to.position.x(), edit.to.position.y()))
                     : (surface_position(mesh, to_point) - edit.to.position).norm() > reach_in_space(mesh))
    throw EditRefused(fmt::format("cannot move {} to {}: that is outside the domain", bifurcation_name(bif),
                                  where(edit.to.position)));
  const cplx shift = chart.point(to_point, edit.to.position) - chart.point(space_.locate(bif.position), bif.position);
  if (!chart.planar() && !chart.locate(shift + chart.point(space_.locate(bif.position), bif.position)))
    throw EditRefused(fmt::format("cannot move {} to {}: it lies beyond the disc of radius {:.3g} around the "
                                  "bifurcation in which its local chart is used",
                                  bifurcation_name(bif), where(edit.to.position), chart.radius()));
  const double wt = edit.window * span;
  const double te = tn + sigma * wt;  // the moved pair rejoins its track here
  if (te < time.t0 || te > time.t1)
    throw EditRefused(fmt::format("moving {} to t = {:.3g} with a window of {:.3g} reaches t = {:.3g}, outside "
                                  "the time range [{}, {}]; use a smaller window or an earlier time",
                                  bifurcation_name(bif), tn, wt, te, time.t0, time.t1));
  if (wt <= 0) throw EditRefused("moving a bifurcation needs a window > 0 over which the pair rejoins its track");
  // The pair must still live where the moved one rejoins it.
  auto frame_of = [&](double t) {
    return std::clamp(static_cast<int>(std::lround((t - time.t0) / span * (field.frames() - 1))), 0,
                      field.frames() - 1);
  };
  if (!pair_at(topo, frame_of(te), in_a, in_b))
    throw EditRefused(fmt::format("the pair of {} no longer exists at t = {:.3g}, where the moved pair would "
                                  "rejoin it; use a smaller window",
                                  bifurcation_name(bif), te));
  // The frames just before the new time (after it, for a cancellation) get the pair's
  // approach: the original's neighbourhood as it was just before the bifurcation (no pair
  // yet, a nearly vanishing field), moved to the new place. Without it the last frame
  // without the pair kept the old place's field there, and the fold that the analysis
  // finds between it and the first frame with the pair (linear in time) lay wherever that
  // interpolation put it: 0.17 away from the target at 65² (issue 16).
  const double step = span / std::max(1, field.frames() - 1);
  const double lead = 2 * step;
  const double begin = sigma > 0 ? std::min({tb, tn, tn - lead}) : std::max({tb, tn, tn + lead});
  const double h = mesh.mean_edge_length();
  const FieldSampler original(bundle, field);

  Field out = field;
  EditReport report;
  std::map<int, std::vector<char>> interiors;  // re-solved and pasted vertices per key frame
  std::map<int, std::vector<char>> solved;     // re-solved vertices only
  for (int j = 0; j < field.frames(); ++j) {
    const double t = time.time(j);
    if (sigma * (t - begin) <= 0 || sigma * (t - te) > 0) continue;
    std::vector<cplx> values(field.frame(j).begin(), field.frame(j).end());
    std::vector<char> interior(values.size(), 0);
    std::vector<int> pinned;
    auto refuse = [&](const RegionResult& r, const char* what) {
      std::string why = fmt::format("a region grown by {} rings still holds {} unwanted singular faces", r.growths,
                                    r.remaining);
      for (const auto& s : topo.singularities[static_cast<size_t>(j)])
        if (s.where.face == r.blocked_by) why = fmt::format("the region would swallow the {}", name(s));
      throw EditRefused(fmt::format("cannot move {}: {} at frame {}: {}", bifurcation_name(bif), what, j, why));
    };
    // Cancel the original pair where it exists.
    if (sigma * (t - tb) > 0) {
      if (const auto p = pair_at(topo, j, in_a, in_b)) {
        const auto& s = topo.singularities[static_cast<size_t>(j)];
        const RegionResult r = region_.cancel(values, s[(*p)[0]].where.face, s[(*p)[1]].where.face);
        if (!r.success) refuse(r, "cancelling the pair");
        values = r.values;
        for (size_t v = 0; v < values.size(); ++v) interior[v] |= r.interior[v];
        report.growths = std::max(report.growths, r.growths);
      }
    }
    // Paste the moved pair (or its approach, up to `lead` before the new time).
    if (sigma * (t - tn) > -lead) {
      const bool approach = sigma * (t - tn) <= 0;
      const double lambda = approach ? 0.0 : (t - tn) / (te - tn);
      const double source_t = std::clamp(approach ? tb + (t - tn) : tb + lambda * (te - tb),
                                         std::min(time.t0, time.t1), std::max(time.t0, time.t1));
      const cplx offset = (1 - lambda) * shift;
      const int js = frame_of(source_t);
      const SurfacePoint bp = space_.locate(bif.position);
      cplx pa = chart.point(bp, bif.position), pb = pa;
      if (const auto p = pair_at(topo, js, in_a, in_b)) {
        const Singularity& sa = topo.singularities[static_cast<size_t>(js)][(*p)[0]];
        const Singularity& sb = topo.singularities[static_cast<size_t>(js)][(*p)[1]];
        pa = chart.point(sa.where, sa.position);
        pb = chart.point(sb.where, sb.position);
      }
      const cplx centre = (pa + pb) / 2.0 + offset;
      const double radius = std::abs(pa - pb) / 2 + 3 * h;
      const double core = std::abs(pa - pb) / 2 + h;  // the pair itself
      std::vector<cplx> pinned_values;
      for (int v = 0; v < mesh.num_vertices(); ++v) {
        if (!chart.charted(v) || std::abs(chart.vertex(v) - centre) > radius) continue;
        const cplx from = chart.vertex(v) - offset;
        const auto sp = chart.locate(from);
        // A vertex of the disc's rim whose source lies outside the domain is left to the
        // region solve; only the pair's own neighbourhood must come from inside.
        if (!sp && std::abs(chart.vertex(v) - centre) > core) continue;
        if (!sp) {
          const std::string place =
              chart.planar() ? fmt::format("{}, outside the domain", where(Vec3(from.real(), from.imag(), 0.0)))
                             : fmt::format("beyond the disc of radius {:.3g} around the bifurcation in which its "
                                           "local chart is used",
                                           chart.radius());
          throw EditRefused(fmt::format("cannot move {}: at frame {} the moved pair's neighbourhood would come "
                                        "from {}",
                                        bifurcation_name(bif), j, place));
        }
        pinned.push_back(v);
        pinned_values.push_back(chart.carry(original.in_face(*sp, source_t), *sp, v));
      }
      if (pinned.empty())
        throw EditRefused(fmt::format("cannot move {}: at frame {} the moved pair's neighbourhood lies outside the "
                                      "domain",
                                      bifurcation_name(bif), j));
      const RegionResult r = region_.paste(values, pinned, pinned_values);
      if (!r.success) refuse(r, "placing the moved pair");
      values = r.values;
      for (size_t v = 0; v < values.size(); ++v) interior[v] |= r.interior[v];
      report.growths = std::max(report.growths, r.growths);
      report.region_faces = std::max(report.region_faces, static_cast<int>(r.faces.size()));
    }
    std::copy(values.begin(), values.end(), out.frame(j).begin());
    std::vector<char> free = interior;
    for (int v : pinned) free[static_cast<size_t>(v)] = 0;
    solved.emplace(j, std::move(free));
    for (int v : pinned) interior[static_cast<size_t>(v)] = 1;
    interiors.emplace(j, std::move(interior));
    report.key_frames.push_back(j);
  }
  if (report.key_frames.empty())
    throw EditRefused(fmt::format("moving {} to t = {:.3g} changes no frame", bifurcation_name(bif), tn));
  smooth_around(out, solved, interiors, window_frames(field, edit.window), report);
  verify_move(analyze_for_edit(bundle, out), bif, edit.to, Faithful(mesh, time));
  report.summary = fmt::format("moved {} to {} at t = {:.3g} (frames {}–{} edited)", bifurcation_name(bif),
                               where(edit.to.position), tn, report.key_frames.front(), report.key_frames.back());
  field = std::move(out);
  return report;
}

EditReport FieldEditor::smooth(Field& field, const SmoothEdit& edit) {
  if (!(edit.strength > 0 && edit.strength <= 1))
    throw EditRefused(fmt::format("the smoothing strength must be in (0, 1], got {}", edit.strength));
  const auto nv = static_cast<Eigen::Index>(field.num_vertices());
  const double mu = 1.0 / ((4 * edit.strength) * (4 * edit.strength));
  // The Laplacian with a ghost vertex n + i joined to each vertex i by weight μ·d_i.
  ConnectionLaplacian ghost;
  ghost.weights = st_laplacian_.weights;
  ghost.hermitian = true;
  ghost.weight_sum.resize(2 * nv);
  ghost.weight_sum << st_laplacian_.weight_sum, st_laplacian_.weight_sum;
  std::vector<Eigen::Triplet<cplx>> triplets;
  triplets.reserve(static_cast<size_t>(st_laplacian_.matrix.nonZeros() + 4 * nv));
  for (Eigen::Index c = 0; c < st_laplacian_.matrix.outerSize(); ++c)
    for (Eigen::SparseMatrix<cplx>::InnerIterator it(st_laplacian_.matrix, c); it; ++it)
      triplets.emplace_back(it.row(), it.col(), it.value());
  for (Eigen::Index i = 0; i < nv; ++i) {
    const double w = mu * st_laplacian_.weight_sum[i];
    triplets.emplace_back(i, i, w);
    triplets.emplace_back(nv + i, nv + i, w);
    triplets.emplace_back(i, nv + i, -w);
    triplets.emplace_back(nv + i, i, -w);
  }
  ghost.matrix.resize(2 * nv, 2 * nv);
  ghost.matrix.setFromTriplets(triplets.begin(), triplets.end());

  const auto frames = static_cast<size_t>(field.frames());
  const auto n = static_cast<size_t>(nv);
  std::vector<char> fixed(frames * 2 * n, 0);
  std::vector<cplx> z(frames * 2 * n);
  for (size_t j = 0; j < frames; ++j) {
    const auto src = field.frame(static_cast<int>(j));
    std::copy(src.begin(), src.end(), z.begin() + static_cast<std::ptrdiff_t>(j * 2 * n));
    std::copy(src.begin(), src.end(), z.begin() + static_cast<std::ptrdiff_t>(j * 2 * n + n));
    std::fill_n(fixed.begin() + static_cast<std::ptrdiff_t>(j * 2 * n + n), n, char{1});
  }
  const std::vector<cplx> values = z;
  const SpaceTimeSolver solver(ghost, field.frames(), settings_.temporal_weight);
  SpaceTimeOptions options;
  options.tolerance = settings_.tolerance;
  options.parallel = false;
  const SolveReport r = deterministic([&] { return solver.solve(fixed, values, z, options); });
  if (!r.success)
    throw EditRefused(fmt::format("the smoothing solve stopped at relative residual {:.2e} after {} iterations, "
                                  "short of the tolerance {:.1e}",
                                  r.residual, r.iterations, settings_.tolerance));
  Field out = field;
  for (size_t j = 0; j < frames; ++j)
    std::copy_n(z.begin() + static_cast<std::ptrdiff_t>(j * 2 * n), n, out.frame(static_cast<int>(j)).begin());
  EditReport report;
  report.iterations = r.iterations;
  report.residual = r.residual;
  report.window_first = 0;
  report.window_last = field.frames() - 1;
  report.summary = fmt::format("smoothed every frame with strength {} ({} CG iterations)", edit.strength,
                               r.iterations);
  field = std::move(out);
  return report;
}

EditSettings edit_settings(const Scene& scene) {
  EditSettings s;
  switch (scene.solver.weights) {
    case Weights::cotan: s.weights = LaplacianWeights::cotan; break;
    case Weights::uniform: s.weights = LaplacianWeights::uniform; break;
    case Weights::mean_value: s.weights = LaplacianWeights::mean_value; break;
  }
  s.temporal_weight = scene.solver.temporal_weight;
  s.tolerance = scene.solver.tolerance;
  return s;
}

std::vector<EditReport> apply_scene_edits(const DesignSpace& space, const Scene& scene, Field& field) {
  const std::vector<Edit>& edits = scene.edits;
  std::vector<EditReport> reports;
  if (edits.empty()) return reports;
  FieldEditor editor(space, edit_settings(scene));
  for (size_t i = 0; i < edits.size(); ++i) {
    try {
      reports.push_back(editor.apply(field, edits[i]));
    } catch (const EditRefused& e) {
      throw_input_error(scene.label(), fmt::format("edits[{}]", i), e.what());
    }
  }
  return reports;
}

}  // namespace tvf
