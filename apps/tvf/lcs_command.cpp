#include "lcs_command.h"

#include "progress.h"
#include "render_input.h"

#include "tvf/core/atomic_output.h"
#include "tvf/core/error.h"
#include "tvf/design/streakline_design.h"
#include "tvf/field/npy.h"
#include "tvf/field/vtk_io.h"
#include "tvf/integrate/ftle.h"
#include "tvf/integrate/streakline.h"
#include "tvf/render/lcs_pictures.h"

#include <fmt/format.h>
#include <nlohmann/json.hpp>

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <filesystem>
#include <limits>
#include <string>
#include <tuple>

namespace fs = std::filesystem;

namespace tvf::cli {

namespace {

const char* kInputHelp = "Folder written by `tvf generate` (or its field.tvff), or a scene file";

// A time option inside the field's range, or the range's end when not given.
double time_option(const std::vector<double>& given, const char* name, const TimeSampling& time, bool start) {
  const double lo = std::min(time.t0, time.t1), hi = std::max(time.t0, time.t1);
  if (given.empty()) return start ? lo : hi;
  const double t = given.front();
  const double slack = 1e-12 * std::max(1.0, hi - lo);
  if (!std::isfinite(t) || t < lo - slack || t > hi + slack)
    throw Error(fmt::format("{} {} is outside the field's time range [{}, {}]", name, t, lo, hi));
  return std::clamp(t, lo, hi);
}

Vec3 point_option(const std::vector<double>& v, size_t first, size_t dims) {
  return {v[first], v[first + 1], dims == 3 ? v[first + 2] : 0.0};
}

// A point of the user's on the domain: planar domains take X Y (or X Y 0: the domain lies at
// z = 0), surfaces X Y Z.
void check_point_dims(const std::vector<double>& v, size_t per_point, bool planar, const char* option) {
  if (!planar && per_point != 3)
    throw Error(fmt::format("{}: the domain is a surface: give X Y Z for each point", option));
  for (const double x : v)
    if (!std::isfinite(x)) throw Error(fmt::format("{}: {} is not a number", option, x));
  if (planar && per_point == 3)
    for (size_t k = 2; k < v.size(); k += 3)
      if (v[k] != 0)
        throw Error(fmt::format("{}: Z = {} is off the planar domain, which lies at z = 0: give X Y", option, v[k]));
}

nlohmann::json points_json(const Streakline& s) {
  nlohmann::json points = nlohmann::json::array();
  for (const StreakPoint& p : s.points)
    points.push_back({p.position.x(), p.position.y(), p.position.z(), p.release});
  return points;
}

// A time or distance option as given: positive and finite (left out, it is 0: the
// library's default — half a frame, a quarter frame, a mean edge length).
void check_positive(const CLI::App& sub, const char* name, double value, const char* what) {
  if ((sub.count(name) > 0 || value != 0) && !(value > 0 && std::isfinite(value)))
    throw Error(fmt::format("{} {}: must be a positive {}", name, value, what));
}

// Runs what integrates the input's field; the library's refusals (a field too fast for its
// time range, a seed off the domain) name the input.
template <class F>
auto on_input(const std::string& input, F&& f) {
  try {
    return f();
  } catch (const Error& e) {
    throw Error(fmt::format("{}: {}", input, e.what()));
  }
}

std::vector<Vec3> positions(const Streakline& s) {
  std::vector<Vec3> out;
  for (const StreakPoint& p : s.points) out.push_back(p.position);
  return out;
}

// The curve in pieces, broken where particles between neighbours left the domain.
std::vector<std::vector<Vec3>> pieces(const Streakline& s) {
  std::vector<std::vector<Vec3>> out(1);
  for (const StreakPoint& p : s.points) {
    if (p.gap_before && !out.back().empty()) out.emplace_back();
    out.back().push_back(p.position);
  }
  return out;
}

// How well the points resolve the curve (streakline.h), in the JSON.
void add_resolution(nlohmann::json& j, const Streakline& s) {
  j["resolution"] = s.resolution;
  j["largest_gap"] = s.largest_gap;
  j["unresolved"] = s.unresolved;
  const char* by = refinement_name(s.unresolved_by);
  j["unresolved_by"] = by ? nlohmann::json(by) : nlohmann::json();
}

// The warning for a curve left with neighbours further apart than its resolution, saying
// what stopped the refinement (streakline.h): the particles ran out (`limit`; `advice` then
// says what else to give) or the flow tears the curve (`torn`: which particles end apart).
void warn_unresolved(const Streakline& s, const char* what, const std::string& limit, const std::string& torn,
                     const char* advice) {
  if (s.unresolved == 0) return;
  if (s.unresolved_by == Streakline::Refinement::out_of_particles)
    std::fprintf(stderr,
                 "warning: the %s needs more than %s to keep neighbours within %.3g of each other at t = %g: %d "
                 "pairs are further apart (up to %.3g), drawn as straight chords; give %s or a larger --max-gap\n",
                 what, limit.c_str(), s.resolution, s.t, s.unresolved, s.largest_gap, advice);
  else
    std::fprintf(stderr,
                 "warning: the flow tears the %s apart: %d pairs of %s are further apart than %.3g at t = %g (up to "
                 "%.3g), drawn as straight chords\n",
                 what, s.unresolved, torn.c_str(), s.resolution, s.t, s.largest_gap);
}

}  // namespace

LcsCommand::LcsCommand(CLI::App& app) {
  ftle_ = app.add_subcommand(
      "ftle", "Finite-time Lyapunov exponents (forward and backward) of a field: Lagrangian coherent structures as "
              "arrays (.npy), pictures and a VTK series");
  ftle_->add_option("input", input_, kInputHelp)->required();
  ftle_->add_option("--horizon", horizon_, "Integration time T (> 0): each frame's flow map runs over [t, t ± T]")
      ->required();
  ftle_->add_option("-o,--output", out_, "Output folder (created if missing)")->required();
  ftle_->add_option("--direction", direction_, "Which FTLE: both, forward (repelling LCS) or backward (attracting LCS)")
      ->check(CLI::IsMember({"both", "forward", "backward"}))
      ->capture_default_str();
  ftle_->add_option("--beyond-range", beyond_,
                    "Frames whose window [t, t ± T] reaches past the field's time range: clamp (integrate to the "
                    "range's end and divide by the time integrated) or nan")
      ->check(CLI::IsMember({"clamp", "nan"}))
      ->capture_default_str();
  ftle_->add_option("--dt", dt_, "Largest RK4 time step (default: half the frame spacing)");
  ftle_->add_option("--every", every_,
                    "Compute every K-th frame only (frames 0, K, 2K, …; the others are NaN): a faster look")
      ->capture_default_str();
  ftle_->add_flag("--compose", compose_,
                  "Planar grids: compose per-frame flow maps instead of integrating every frame's window (much faster "
                  "for a whole series, less accurate along the ridges; docs/user_guide.md)");
  ftle_->add_option("--pictures", pictures_, "Colour-mapped pictures per direction, frames evenly spaced (0: none)")
      ->capture_default_str();
  ftle_->add_option("-s,--size", size_, "Pixels on the long side of the pictures")->capture_default_str();
  ftle_->add_flag("--no-vtk", no_vtk_, "Skip the VTK series (ftle.pvd)");
  auto camera = [&](CLI::App* sub, const char* view_help) {
    sub->add_option("--view", view_, view_help)->delimiter(',')->expected(3);
    sub->add_option("--up", up_, "Surfaces: the direction that points up in the picture, X,Y,Z (default 0,0,1)")
        ->delimiter(',')
        ->expected(3);
  };
  camera(ftle_, "Surfaces: direction from the mesh's centre to the camera, X,Y,Z (default 1,-0.6,0.5)");
  ftle_->add_flag("-q,--quiet", quiet_, "Print nothing but errors and warnings");

  auto common = [&](CLI::App* sub) {
    sub->add_option("input", input_, kInputHelp)->required();
    sub->add_option("--from", from_, "First time (default: the start of the field's time range)")->expected(1);
    sub->add_option("--to", to_, "The time shown (default: the end of the field's time range)")->expected(1);
    sub->add_option("-o,--output", out_, "The JSON file to write (the picture goes beside it, .png)")->required();
    sub->add_option("--dt", dt_, "Largest RK4 time step (default: half the frame spacing)");
    sub->add_option("-s,--size", size_, "Pixels on the long side of the picture")->capture_default_str();
    sub->add_flag("--no-picture", no_picture_, "Skip the picture");
    sub->add_flag("-q,--quiet", quiet_, "Print nothing but errors and warnings");
    camera(sub, "Surfaces: direction from the mesh's centre to the camera, X,Y,Z (default: from the centre towards "
                "the curve)");
  };
  streak_ = app.add_subcommand(
      "streaklines", "A streakline: where dye released continuously from a seed over [--from, --to] is at --to (JSON "
                     "and a picture over the field)");
  common(streak_);
  streak_->add_option("--seed", seed_, "The seed: X Y on a planar domain, X Y Z on a surface (default: --element's)")
      ->expected(2, 3);
  streak_->add_option("--element", element_,
                      "A streakline element of the input's scene (its index in elements): its seed, release "
                      "interval and time by default, its sketch drawn under the traced streakline, and the "
                      "distance between the two reported");
  streak_->add_option("--release-spacing", spacing_, "Time between releases (default: a quarter of the frame spacing)");
  streak_->add_option("--max-gap", max_gap_,
                      "Distance between neighbours at --to above which a particle released halfway between them is "
                      "added (default: the mean edge length)");

  timeline_ = app.add_subcommand(
      "timelines", "A timeline: the segment --line drawn at --from, carried by the flow to --to (JSON and a picture)");
  common(timeline_);
  timeline_->add_option("--line", line_, "The segment's ends: X0 Y0 X1 Y1 on a planar domain, X0 Y0 Z0 X1 Y1 Z1 on a surface")
      ->required()
      ->expected(4, 6);
  timeline_->add_option("--count", count_, "Particles on the segment at --from")->capture_default_str();
  timeline_->add_option("--max-gap", max_gap_,
                        "Distance between neighbours at --to above which a particle is added between them "
                        "(default: the mean edge length)");
}

int LcsCommand::run() {
  if (ftle_->parsed()) return run_ftle();
  if (streak_->parsed()) return run_streaklines();
  if (timeline_->parsed()) return run_timelines();
  return 1;
}

SurfaceView LcsCommand::surface_view(bool& given) const {
  SurfaceView v;
  auto vector = [](const std::vector<double>& x, const char* name) {
    const Vec3 d(x[0], x[1], x[2]);
    if (!d.allFinite() || !(d.norm() > 0))
      throw Error(fmt::format("{} {},{},{}: must be a direction, three finite numbers not all zero", name, x[0], x[1],
                              x[2]));
    return d;
  };
  given = !view_.empty();
  if (given) v.direction = vector(view_, "--view");
  if (!up_.empty()) v.up = vector(up_, "--up");
  return v;
}

int LcsCommand::run_ftle() {
  if (!(horizon_ > 0) || !std::isfinite(horizon_))
    throw Error(fmt::format("--horizon {}: must be a positive time", horizon_));
  check_positive(*ftle_, "--dt", dt_, "time");
  if (pictures_ < 0) throw Error(fmt::format("--pictures {}: must be 0 or more", pictures_));
  if (every_ < 1) throw Error(fmt::format("--every {}: must be at least 1", every_));
  if (size_ < 16 || size_ > 16384) throw Error(fmt::format("--size {}: must be in [16, 16384] pixels", size_));
  bool view_given = false;
  const SurfaceView view = surface_view(view_given);
  const bool show = !quiet_ && progress_wanted();
  Progress progress("tvf ftle", show);
  RenderInput in = load_render_input(input_, progress, "ftle", true);
  const TangentBundle& bundle = in.space->bundle();
  FtleOptions o;
  o.horizon = horizon_;
  o.forward = direction_ != "backward";
  o.backward = direction_ != "forward";
  o.beyond_range = beyond_ == "nan" ? HorizonPolicy::nan : HorizonPolicy::clamp;
  o.flow.dt = dt_;
  o.compose = compose_;
  for (int j = 0; j < in.field.frames(); j += every_) o.frames.push_back(j);
  o.progress = [&](int done, int total) { progress.update(done, total); };
  progress.note("flow maps");
  const FtleResult r = on_input(input_, [&] { return compute_ftle(bundle, in.field, o); });

  progress.note("writing");
  OutputStage stage(out_);
  const auto n = static_cast<size_t>(r.frames), nv = static_cast<size_t>(r.vertices);
  const std::vector<double> times = in.field.time().times();
  std::vector<VtkScalarArray> arrays;
  nlohmann::json meta = {{"horizon", horizon_},
                         {"beyond_range", to_string(o.beyond_range)},
                         {"frames", r.frames},
                         {"vertices", r.vertices},
                         {"times", times}};
  if (compose_) meta["compose"] = true;  // flow maps composed (--compose)
  for (const int dir : {1, -1}) {
    const std::vector<float>& values = dir > 0 ? r.forward : r.backward;
    if (values.empty()) continue;
    const std::string name = dir > 0 ? "ftle_forward" : "ftle_backward";
    write_npy(stage.file(name + ".npy").string(), {n, nv}, values.data());
    arrays.push_back({name, values});
    const std::vector<double>& spans = dir > 0 ? r.forward_span : r.backward_span;
    // One colour range for the series, from the frames integrated over the whole horizon
    // (a cut window divides by a shorter time and can reach far higher values).
    std::vector<float> full;
    for (size_t j = 0; j < n; ++j)
      if (std::abs(spans[j] - horizon_) <= 1e-9 * horizon_)
        full.insert(full.end(), values.begin() + static_cast<long>(j * nv), values.begin() + static_cast<long>((j + 1) * nv));
    const auto range = colour_range(full.empty() ? values : full);
    meta[dir > 0 ? "forward" : "backward"] = {{"span", spans},
                                              {"cut_frames", dir > 0 ? r.forward_cut : r.backward_cut},
                                              {"left_domain", dir > 0 ? r.forward_left : r.backward_left},
                                              {"colour_range", {range.first, range.second}}};
    if (pictures_ == 0) continue;
    // Frames with values, evenly spaced; one colour range for all of them.
    std::vector<int> have;
    for (int j = 0; j < r.frames; ++j)
      if (spans[static_cast<size_t>(j)] > 0) have.push_back(j);
    ScalarPictureOptions po;
    po.size = size_;
    po.surface = view;
    std::tie(po.lo, po.hi) = range;
    const int k_max = std::min(pictures_, static_cast<int>(have.size()));
    for (int k = 0; k < k_max; ++k) {
      const int j = have[static_cast<size_t>(k_max == 1 ? 0 : k * (static_cast<int>(have.size()) - 1) / (k_max - 1))];
      po.label = fmt::format("{} FTLE, t = {:.4g}, T = {:.4g}", dir > 0 ? "forward" : "backward",
                             times[static_cast<size_t>(j)], spans[static_cast<size_t>(j)]);
      const Image img = scalar_picture(bundle, std::span<const float>(values).subspan(static_cast<size_t>(j) * nv, nv), po);
      write_png(stage.file(fmt::format("{}_{:04}.png", name, j)).string(), img);
    }
  }
  if (!no_vtk_) {
    // The frames computed (all, unless --every).
    std::vector<double> vtk_times;
    std::vector<std::vector<float>> kept(arrays.size());
    for (const int j : o.frames) {
      vtk_times.push_back(times[static_cast<size_t>(j)]);
      for (size_t a = 0; a < arrays.size(); ++a)
        kept[a].insert(kept[a].end(), arrays[a].values.begin() + static_cast<long>(static_cast<size_t>(j) * nv),
                       arrays[a].values.begin() + static_cast<long>(static_cast<size_t>(j + 1) * nv));
    }
    std::vector<VtkScalarArray> vtk;
    for (size_t a = 0; a < arrays.size(); ++a) vtk.push_back({arrays[a].name, kept[a]});
    // Each file numbered by its frame, as the pictures are (ftle_0016.vtu is frame 16).
    write_vtk_scalar_series(stage.stage().string(), "ftle", in.mesh, vtk_times, vtk, o.frames);
  }
  write_file_atomically(stage.file("ftle.json"), meta.dump(2) + "\n");
  // What an earlier run into the same folder wrote and this one does not (other frames with
  // --every, a direction not asked, the VTK series with --no-vtk) goes in the same commit:
  // ParaView's file-series grouping of ftle_*.vtu would mix the two runs.
  const auto files = stage.commit([](const std::string& name) {
    return name == "ftle.json" || name == "ftle.pvd" || name == "ftle_forward.npy" || name == "ftle_backward.npy" ||
           is_numbered_name(name, "ftle_", ".vtu") || is_numbered_name(name, "ftle_forward_", ".png") ||
           is_numbered_name(name, "ftle_backward_", ".png");
  });
  progress.finish();
  for (const auto& w : in.warnings) std::fprintf(stderr, "warning: %s\n", w.c_str());
  if (!quiet_) {
    std::printf("FTLE of %zu of %d frames × %d vertices, T = %g", o.frames.size(), r.frames, r.vertices, horizon_);
    for (const int dir : {1, -1}) {
      const std::vector<float>& values = dir > 0 ? r.forward : r.backward;
      if (values.empty()) continue;
      float hi = -std::numeric_limits<float>::infinity();
      for (const float v : values)
        if (!std::isnan(v)) hi = std::max(hi, v);
      std::printf("; %s: max %.3g, %ld vertex-frames left the domain", dir > 0 ? "forward" : "backward",
                  static_cast<double>(hi), dir > 0 ? r.forward_left : r.backward_left);
    }
    std::printf("\nwrote %zu files to %s\n", files.size(), fs::absolute(out_).lexically_normal().c_str());
    std::fflush(stdout);
  }
  const int cut = r.forward_cut + r.backward_cut;
  if (cut > 0 && !quiet_) {
    // Naming the directions computed only.
    std::string which;
    if (!r.forward.empty()) which = fmt::format("{} forward", r.forward_cut);
    if (!r.backward.empty()) which += fmt::format("{}{} backward", which.empty() ? "" : " and ", r.backward_cut);
    const bool one = cut == 1;
    const std::string what =
        o.beyond_range == HorizonPolicy::clamp
            ? fmt::format("{} cut at its ends (ftle.json has each frame's span; --beyond-range nan gives {} NaN)",
                          one ? "its window was" : "their windows were", one ? "it" : "them")
            : std::string(one ? "it is NaN" : "they are NaN");
    std::fprintf(stderr, "note: %s %s past the time range [%g, %g] with T = %g: %s\n", which.c_str(),
                 one ? "frame reaches" : "frames reach", in.field.time().t0, in.field.time().t1, horizon_,
                 what.c_str());
  }
  return 0;
}

int LcsCommand::run_streaklines() {
  check_output_file(out_);  // before the work, not after it
  check_positive(*streak_, "--release-spacing", spacing_, "time");
  check_positive(*streak_, "--dt", dt_, "time");
  check_positive(*streak_, "--max-gap", max_gap_, "distance");
  bool view_given = false;
  const SurfaceView view = surface_view(view_given);
  const bool show = !quiet_ && progress_wanted();
  Progress progress("tvf streaklines", show);
  RenderInput in = load_render_input(input_, progress, "streaklines", true);
  const TangentBundle& bundle = in.space->bundle();
  // --element: the scene's sketched streakline gives what the options leave out.
  const StreaklineElement* sketch = nullptr;
  if (element_ >= 0 || streak_->count("--element") > 0) {
    if (!in.scene)
      throw Error(fmt::format("--element {}: {} has no scene to take the element from", element_, input_));
    const auto k = static_cast<size_t>(element_);
    if (element_ < 0 || k >= in.scene->elements.size() ||
        !(sketch = std::get_if<StreaklineElement>(&in.scene->elements[k])))
      throw Error(fmt::format("--element {}: the scene has no streakline element at that index", element_));
    if (seed_.empty()) {
      const Vec3& s0 = sketch->points.front();
      seed_ = bundle.is_flat() ? std::vector<double>{s0.x(), s0.y()} : std::vector<double>{s0.x(), s0.y(), s0.z()};
    }
    if (from_.empty()) from_ = {sketch->from};
    if (to_.empty()) to_ = {sketch->t};
  }
  if (seed_.empty()) throw Error("--seed is required (or --element, a streakline element of the scene)");
  check_point_dims(seed_, seed_.size(), bundle.is_flat(), "--seed");
  StreaklineOptions o;
  o.t0 = time_option(from_, "--from", in.field.time(), true);
  o.t1 = time_option(to_, "--to", in.field.time(), false);
  if (o.t0 > o.t1)
    throw Error(fmt::format("--from {} is after --to {}: dye is released over [--from, --to]", o.t0, o.t1));
  o.release_spacing = spacing_;
  o.max_gap = max_gap_;
  o.flow.dt = dt_;
  Vec3 seed = point_option(seed_, 0, seed_.size());
  progress.note("releasing");
  const Streakline s = on_input(input_, [&] { return trace_streakline(bundle, in.field, seed, o); });
  // On a surface the dye starts from the seed's closest point of it (the trace refused a seed
  // too far off; a sketch's seed is where the generator took it): that is the seed written
  // and drawn.
  if (!bundle.is_flat()) seed = surface_position(bundle.mesh(), in.space->locate(seed));
  nlohmann::json j = {{"t", s.t},
                      {"from", o.t0},
                      {"seed", {seed.x(), seed.y(), seed.z()}},
                      {"released", s.released},
                      {"left", s.left},
                      {"points", points_json(s)}};
  add_resolution(j, s);
  StreaklineMatch match;
  const double h = bundle.mesh().mean_edge_length();
  if (sketch) {
    match = compare_streakline(sketch->points, positions(s));
    j["sketch"] = {{"element", element_},
                   {"hausdorff", match.hausdorff},
                   {"mean", match.mean},
                   {"frechet", match.frechet},
                   {"mean_edge_length", h}};
  }
  std::string picture;
  create_output_folder_for(out_);
  if (!no_picture_) {
    progress.note("drawing");
    CurvePictureOptions po;
    po.size = size_;
    po.surface = view;
    po.face_curves = !view_given;
    if (sketch) po.under = {sketch->points};
    const Image img = curve_picture(bundle, in.field, s.t, pieces(s), std::vector<Vec3>{seed}, po);
    const fs::path out(out_);
    picture = (out.parent_path() / out.stem()).string() + ".png";
    write_png(picture, img);
  }
  write_file_atomically(out_, j.dump() + "\n");
  progress.finish();
  for (const auto& w : in.warnings) std::fprintf(stderr, "warning: %s\n", w.c_str());
  warn_unresolved(s, "streakline",
                  fmt::format("{} added releases", StreaklineOptions{}.max_added),
                  "particles released within 1e-12 of each other", "a smaller --release-spacing");
  // The distances compare the dye with the sketch as drawn for the element's release; other
  // times make them the difference between two shapes, not the field's error.
  if (sketch && !quiet_ && (o.t0 != sketch->from || o.t1 != sketch->t))
    std::fprintf(stderr,
                 "note: the dye released over [%g, %g] is compared with elements[%d]'s sketch, drawn for [%g, %g]: "
                 "the distances are not the field's error at the sketch (leave --from and --to out for that)\n",
                 o.t0, o.t1, element_, sketch->from, sketch->t);
  if (!quiet_) {
    std::printf("streakline at t = %g: %d particles released from t = %g", s.t, s.released, o.t0);
    if (s.left > 0) std::printf(", %d of them left the domain", s.left);
    if (sketch)
      std::printf("; from elements[%d]'s sketch: Hausdorff %.4g (%.2f edge lengths), mean %.4g (%.2f), "
                  "Fréchet %.4g (%.2f)",
                  element_, match.hausdorff, match.hausdorff / h, match.mean, match.mean / h, match.frechet,
                  match.frechet / h);
    std::printf("; wrote %s", fs::absolute(out_).lexically_normal().c_str());
    if (!picture.empty()) std::printf(" and %s", fs::absolute(picture).lexically_normal().c_str());
    std::printf("\n");
  }
  return 0;
}

int LcsCommand::run_timelines() {
  check_output_file(out_);  // before the work, not after it
  if (line_.size() == 5) throw Error("--line: give X0 Y0 X1 Y1 (planar) or X0 Y0 Z0 X1 Y1 Z1 (surfaces)");
  if (const int most = TimelineOptions{}.max_points; count_ < 2 || count_ > most)
    throw Error(fmt::format("--count {}: a timeline has 2 to {} particles", count_, most));
  check_positive(*timeline_, "--max-gap", max_gap_, "distance");
  check_positive(*timeline_, "--dt", dt_, "time");
  bool view_given = false;
  const SurfaceView view = surface_view(view_given);
  const bool show = !quiet_ && progress_wanted();
  Progress progress("tvf timelines", show);
  RenderInput in = load_render_input(input_, progress, "timelines", true);
  const TangentBundle& bundle = in.space->bundle();
  const size_t dims = line_.size() / 2;
  check_point_dims(line_, dims, bundle.is_flat(), "--line");
  TimelineOptions o;
  o.t0 = time_option(from_, "--from", in.field.time(), true);
  o.t1 = time_option(to_, "--to", in.field.time(), false);
  o.count = count_;
  o.max_gap = max_gap_;
  o.flow.dt = dt_;
  const Vec3 a = point_option(line_, 0, dims), b = point_option(line_, dims, dims);
  progress.note("carrying");
  const Streakline s = on_input(input_, [&] { return trace_timeline(bundle, in.field, a, b, o); });
  nlohmann::json j = {{"t", s.t},
                      {"from", o.t0},
                      {"line", {{a.x(), a.y(), a.z()}, {b.x(), b.y(), b.z()}}},
                      {"released", s.released},
                      {"left", s.left},
                      {"points", points_json(s)}};
  add_resolution(j, s);
  std::string picture;
  create_output_folder_for(out_);
  if (!no_picture_) {
    progress.note("drawing");
    CurvePictureOptions po;
    po.size = size_;
    po.surface = view;
    po.face_curves = !view_given;
    po.dots = false;
    const Image img = curve_picture(bundle, in.field, s.t, pieces(s), std::vector<Vec3>{}, po);
    const fs::path out(out_);
    picture = (out.parent_path() / out.stem()).string() + ".png";
    write_png(picture, img);
  }
  write_file_atomically(out_, j.dump() + "\n");
  progress.finish();
  for (const auto& w : in.warnings) std::fprintf(stderr, "warning: %s\n", w.c_str());
  warn_unresolved(s, "timeline", fmt::format("{} particles", TimelineOptions{}.max_points),
                  fmt::format("neighbours within 1e-12 of each other along the line at t = {}", o.t0),
                  "a shorter interval");
  if (!quiet_) {
    std::printf("timeline at t = %g: %zu particles from the line at t = %g", s.t, s.points.size(), o.t0);
    if (s.left > 0) std::printf(" (%d more left the domain)", s.left);
    std::printf("; wrote %s", fs::absolute(out_).lexically_normal().c_str());
    if (!picture.empty()) std::printf(" and %s", fs::absolute(picture).lexically_normal().c_str());
    std::printf("\n");
  }
  return 0;
}

}  // namespace tvf::cli
