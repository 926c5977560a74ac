#include "tvf/design/design_check.h"

#include "tvf/core/error.h"
#include "tvf/design/element_field.h"
#include "tvf/design/generate.h"
#include "tvf/design/keyframe_topology.h"
#include "tvf/design/keyframes.h"
#include "tvf/scene/edits.h"
#include "tvf/field/field_sampler.h"
#include "tvf/integrate/periodic_orbits.h"

#include <fmt/format.h>

#include <algorithm>
#include <map>
#include <numeric>
#include <optional>
#include <set>
#include <tuple>

namespace tvf {

namespace {

// Topological class of a type: stability for index +1 (center apart), saddle for −1.
enum class Stability { repelling, attracting, center, saddle };
Stability stability(SingularityType t) {
  switch (t) {
    case SingularityType::source:
    case SingularityType::repelling_focus: return Stability::repelling;
    case SingularityType::sink:
    case SingularityType::attracting_focus: return Stability::attracting;
    case SingularityType::center: return Stability::center;
    case SingularityType::saddle: return Stability::saddle;
  }
  return Stability::saddle;
}
// Designed stabilities, as bits: a path designed repelling at some frame and attracting at
// another changes stability by design (a Hopf event on it is implied, not extra).
constexpr unsigned kRepelling = 1, kAttracting = 2;
unsigned stability_bit(SingularityType t) {
  switch (stability(t)) {
    case Stability::repelling: return kRepelling;
    case Stability::attracting: return kAttracting;
    default: return 0;
  }
}
bool complex_eigenvalues(SingularityType t) {
  return t == SingularityType::center || t == SingularityType::repelling_focus ||
         t == SingularityType::attracting_focus;
}
// Compatible types (see the header): equal topological class; a center with any focus.
bool compatible(SingularityType designed, SingularityType found) {
  if (designed == SingularityType::center) return complex_eigenvalues(found);
  if (found == SingularityType::center) return complex_eigenvalues(designed);
  return stability(designed) == stability(found);
}

// One singularity to look for at one frame.
struct Expected {
  int frame;
  Vec3 position;   // the designed point, on the domain
  int index;
  SingularityType type;
  Vec3 predicted;  // where the field's value at `position` moves the zero (first order)
};

std::string position_text(const Vec3& x, bool planar) {
  return planar ? fmt::format("({:.2f}, {:.2f})", x.x(), x.y())
                : fmt::format("({:.2f}, {:.2f}, {:.2f})", x.x(), x.y(), x.z());
}

// Matches the expectations of one singularity feature, frame by frame.
void match_singularity(DesignedFeature& f, const std::vector<Expected>& expected, const Topology& topo,
                       double tol, std::set<int>& claimed) {
  f.frames = static_cast<int>(expected.size());
  std::set<int> paths;
  int first_missing = -1, first_differs = -1;
  double missing_shift = 0;  // the first-order shift of the zero at first_missing
  SingularityType differs_found = SingularityType::source, differs_designed = SingularityType::source;
  for (const Expected& e : expected) {
    const auto& sings = topo.singularities[static_cast<size_t>(e.frame)];
    int best = -1, best_any = -1;
    double d_best = tol, d_any = tol;
    for (size_t k = 0; k < sings.size(); ++k) {
      const Singularity& s = sings[k];
      if (s.index != e.index) continue;
      const double d = (s.position - e.predicted).norm();
      if (d <= d_any) d_any = d, best_any = static_cast<int>(k);
      if (d <= d_best && compatible(e.type, s.type)) d_best = d, best = static_cast<int>(k);
    }
    f.max_shift = std::max(f.max_shift, (e.predicted - e.position).norm());
    const int hit = best >= 0 ? best : best_any;
    if (hit >= 0) {
      const int id = topo.singularity_path[static_cast<size_t>(e.frame)][static_cast<size_t>(hit)];
      if (id >= 0) paths.insert(id);
    }
    if (best >= 0) {
      ++f.frames_matched;
      f.max_distance = std::max(f.max_distance, d_best);
    } else if (best_any >= 0) {
      ++f.frames_type_differs;
      if (first_differs < 0) {
        first_differs = e.frame;
        differs_found = sings[static_cast<size_t>(best_any)].type;
        differs_designed = e.type;
      }
    } else if (first_missing < 0) {
      first_missing = e.frame;
      missing_shift = (e.predicted - e.position).norm();
    }
  }
  f.paths.assign(paths.begin(), paths.end());
  claimed.insert(paths.begin(), paths.end());
  f.found = f.frames > 0 && f.frames_matched == f.frames;
  std::vector<std::string> notes;
  if (f.frames == 0) notes.push_back("no frame falls in its life span");
  const int missing = f.frames - f.frames_matched - f.frames_type_differs;
  if (missing > 0) {
    notes.push_back(fmt::format("no singularity of index {:+d} within {:.3g} of where the field puts it at {} of {} "
                                "frames (first at t = {:.3f})",
                                f.index, tol, missing, f.frames, topo.times[static_cast<size_t>(first_missing)]));
    // Why, where the rest of the design outweighs the element at its own place (two Hopf
    // templates on a sphere with falloff 5: each one's cubic far field, at the other's pole,
    // moved its zero 5.8 away, and the analysis found a sink there and no focus).
    if (missing_shift > tol)
      notes.back() += fmt::format(": the rest of the design outweighs it there (its field at the designed point "
                                  "would move the zero {:.3g} away, |J⁻¹·V|); a larger falloff or the elements "
                                  "further apart keep their fields apart",
                                  missing_shift);
  }
  if (f.frames_type_differs > 0)
    notes.push_back(fmt::format("of another type at {} of {} frames (first at t = {:.3f}: {} where {} is designed)",
                                f.frames_type_differs, f.frames, topo.times[static_cast<size_t>(first_differs)],
                                to_string(differs_found), to_string(differs_designed)));
  for (size_t k = 0; k < notes.size(); ++k) f.note += (k ? "; " : "") + notes[k];
}

}  // namespace

bool DesignCheck::all_found() const {
  return std::all_of(designed.begin(), designed.end(), [](const DesignedFeature& f) { return f.found; });
}

DesignCheck check_design(const Scene& scene, const DesignSpace& space, const Field& field, const Topology& topo,
                         const DesignCheckOptions& options) {
  const int N = static_cast<int>(topo.times.size());
  if (N != scene.time.frames)
    throw_input_error(scene.label(), "time.frames",
                      fmt::format("the field has {} frames but the scene designs {}: check the field against "
                                  "the scene that made it",
                                  N, scene.time.frames));
  const Mesh& mesh = space.mesh();
  DesignCheck out;
  out.position_tolerance = options.position_tolerance * mesh.mean_edge_length();
  const double dt = N > 1 ? (topo.times.back() - topo.times.front()) / (N - 1) : 0.0;
  out.time_tolerance = options.time_tolerance * dt;
  const double tol = out.position_tolerance;
  auto on_domain = [&](const Vec3& x) { return surface_position(mesh, space.locate(x)); };
  // Where the field puts the zero of a singularity designed at x with Jacobian J (in the
  // element's frame, the frame of the face holding x) at frame j: one Newton step from x,
  // x − J⁻¹·V(x), since the rest of the design adds V(x) to the element's own field.
  const FieldSampler sampler(space.bundle(), field);
  auto expect = [&](int j, const Vec3& x, const Mat2& J) -> Expected {
    const SurfacePoint p = space.locate(x);
    Expected e{j, surface_position(mesh, p), J.determinant() > 0 ? 1 : -1, classify_jacobian(J), Vec3::Zero()};
    e.predicted = e.position;
    const double scale = J.cwiseAbs().maxCoeff();
    if (std::abs(J.determinant()) > 1e-12 * scale * scale) {
      const Vec2 step = J.inverse() * to_vec2(sampler.in_face(p, topo.times[static_cast<size_t>(j)]));
      e.predicted = e.position - step.x() * space.bundle().face_e1(p.face) - step.y() * space.bundle().face_e2(p.face);
    }
    return e;
  };
  std::set<int> claimed;
  // The stabilities the design gives each feature's singularity over its life (kRepelling,
  // kAttracting), and each path the key-frame plan carries: where a path's design holds
  // both, its focus changes stability by design and a Hopf event on it is implied.
  std::map<size_t, unsigned> feature_stabilities;  // index into out.designed
  std::map<int, unsigned> path_stabilities;        // path id

  // The scene's edits (validated with the scene). Cancelled pairs: the frame, the window
  // (frames each way) and the two positions on the domain.
  const std::vector<Edit>& edits = scene.edits;
  struct Cut {
    size_t edit;
    int frame, window;
    std::array<Vec3, 2> pair;
  };
  std::vector<Cut> cuts;
  for (size_t i = 0; i < edits.size(); ++i)
    if (const auto* c = std::get_if<CancelEdit>(&edits[i]))
      cuts.push_back({i, c->frame, static_cast<int>(std::lround(c->window * (N - 1))),
                      {on_domain(c->pair[0]), on_domain(c->pair[1])}});
  auto edit_name = [](size_t i) { return fmt::format("edits[{}]", i); };

  // `stability_designed`: false for a Hopf element's focus, whose designed stability change
  // is its own Hopf event (matched below), not a licence for others.
  auto add_singularity = [&](const std::string& source, const std::string& type, const std::vector<Expected>& all,
                             int index, const Vec3& first_position, bool stability_designed = true) {
    DesignedFeature f;
    f.kind = FeatureKind::singularity;
    f.source = source;
    f.type = type;
    f.index = index;
    f.position = first_position;
    if (!all.empty()) {
      f.t_begin = topo.times[static_cast<size_t>(all.front().frame)];
      f.t_end = topo.times[static_cast<size_t>(all.back().frame)];
      f.position = all.front().position;
    }
    // Frames in the window of a cancel edit that takes this singularity away are not checked.
    std::vector<Expected> expected;
    for (const Expected& e : all) {
      const Cut* by = nullptr;
      for (const Cut& c : cuts)
        if (std::abs(e.frame - c.frame) <= c.window)
          for (const Vec3& x : c.pair)
            if (std::min((e.position - x).norm(), (e.predicted - x).norm()) <= tol) by = &c;
      if (by) {
        ++f.frames_edited;
        f.edit = edit_name(by->edit);
      } else {
        expected.push_back(e);
      }
    }
    match_singularity(f, expected, topo, tol, claimed);
    if (stability_designed)
      for (const Expected& e : all) feature_stabilities[out.designed.size()] |= stability_bit(e.type);
    if (f.frames == 0 && f.frames_edited > 0) {
      f.found = true;  // every frame of its life is in the edit's window
      f.note.clear();
    }
    out.designed.push_back(std::move(f));
  };

  // Elements: singular ones along their paths, bifurcations at their points (matched
  // below, once the edits have said where they are expected).
  std::set<int> designed_bifs;  // found bifurcations matched to bifurcation elements
  struct BifurcationFeature {
    size_t feature;  // index into out.designed
    BifurcationKind kind;
    bool sink;       // joins a sink (else a source)
    bool typed;      // false: an edit's own feature, either kind and any pair
  };
  std::vector<BifurcationFeature> bifurcation_features;
  struct HopfFeature {
    size_t feature;      // index into out.designed
    bool supercritical;
  };
  std::vector<HopfFeature> hopf_features;
  // Template elements' features (index into out.designed) with the template's scale: one
  // not found gets a hint when the scale spans too few edges for the mesh to resolve it.
  struct TemplateScale {
    size_t feature = 0;
    double scale = 0, resolved_edges = 0;  // template_resolved_edges (generate.h)
  };
  std::vector<TemplateScale> template_scales;
  for (size_t k = 0; k < scene.elements.size(); ++k) {
    const Element& e = scene.elements[k];
    const std::string source = fmt::format("elements[{}]", k);
    if (const auto* s = std::get_if<SingularElement>(&e)) {
      const CompiledElement el(e);
      std::vector<Expected> expected;
      for (int j = 0; j < N; ++j) {
        const double t = topo.times[static_cast<size_t>(j)];
        if (!el.active(t)) continue;
        const ElementState st = el.at(t);
        expected.push_back(expect(j, st.position, st.field.matrix));
      }
      add_singularity(source, s->type ? to_string(*s->type) : "jacobian", expected, el.index(),
                      on_domain(s->path.front().position));
    } else if (const auto* h = std::get_if<BifurcationElement>(&e); h && is_hopf(h->type)) {
      // The focus, at every frame, with the normal form's Jacobian (scale-free at p).
      const CompiledElement el(e);
      std::vector<Expected> expected;
      for (int j = 0; j < N; ++j) {
        const double mu = el.at(topo.times[static_cast<size_t>(j)]).field.local_time;
        Mat2 J;
        J << mu, -1, 1, mu;
        expected.push_back(expect(j, h->at.position, J));
      }
      template_scales.push_back({out.designed.size(), h->scale, template_resolved_edges(h->type)});
      add_singularity(source, to_string(h->type), expected, 1, on_domain(h->at.position), false);
      if (N < 2 || h->at.t <= topo.times.front() || h->at.t >= topo.times.back()) continue;
      template_scales.push_back({out.designed.size(), h->scale, template_resolved_edges(h->type)});
      hopf_features.push_back({out.designed.size(), h->type == BifurcationType::hopf_supercritical});
      DesignedFeature f;
      f.kind = FeatureKind::bifurcation;
      f.source = source;
      f.type = to_string(h->type);
      f.t_begin = f.t_end = h->at.t;
      f.position = on_domain(h->at.position);
      out.designed.push_back(std::move(f));
    } else if (const auto* b = std::get_if<BifurcationElement>(&e)) {
      // Only a bifurcation strictly inside the time range is an event of the field.
      if (N < 2 || b->at.t <= topo.times.front() || b->at.t >= topo.times.back()) continue;
      DesignedFeature f;
      f.kind = FeatureKind::bifurcation;
      f.source = source;
      f.type = to_string(b->type);
      f.t_begin = f.t_end = b->at.t;
      f.position = on_domain(b->at.position);
      const bool creation = b->type == BifurcationType::saddle_sink_creation ||
                            b->type == BifurcationType::saddle_source_creation;
      const bool sink = b->type == BifurcationType::saddle_sink_creation ||
                        b->type == BifurcationType::saddle_sink_cancellation;
      template_scales.push_back({out.designed.size(), b->scale, template_resolved_edges(b->type)});
      bifurcation_features.push_back(
          {out.designed.size(), creation ? BifurcationKind::creation : BifurcationKind::cancellation, sink, true});
      out.designed.push_back(std::move(f));
    }
  }

  // Key frames: their singular elements at their frames.
  for (size_t k = 0; k < scene.keyframes.size(); ++k) {
    const Keyframe& kf = scene.keyframes[k];
    const int j = keyframe_frame(scene, kf.t);
    for (size_t i = 0; i < kf.elements.size(); ++i) {
      const KeyframeElement& e = kf.elements[i];
      if (e.kind != "singular") continue;
      const Mat2 J = e.type ? jacobian_of(*e.type) : e.jacobian;
      const Expected ex = expect(j, e.at, J);
      add_singularity(fmt::format("keyframes[{}].elements[{}]", k, i), e.type ? to_string(*e.type) : "jacobian",
                      {ex}, ex.index, ex.position);
    }
  }

  // Key-frame topology "matched": the pairs it creates or cancels between key frames are
  // designed bifurcations (keyframe_topology.h; the generation's plan, or planned again
  // from the key frames, which the spacetime generator holds exactly).
  if (scene.generator == Generator::spacetime && scene.solver.keyframe_topology == KeyframeTopology::matched &&
      scene.keyframes.size() >= 2 && N == scene.time.frames) {
    // The generation's own plan when the caller has it, else the same plan made again.
    std::optional<KeyframeTopologyPlan> replanned;
    const std::vector<KeyframeIntervalReport>* given = options.keyframe_intervals;
    // (Only when it is this scene's: an interval for each pair of its key frames, at their times.)
    const auto n = static_cast<int>(scene.keyframes.size());
    auto at = [&](int k, double t) { return k >= 0 && k < n && scene.keyframes[static_cast<size_t>(k)].t == t; };
    if (given && (given->size() + 1 != scene.keyframes.size() ||
                  !std::all_of(given->begin(), given->end(), [&](const KeyframeIntervalReport& r) {
                    return at(r.from_keyframe, r.t0) && at(r.to_keyframe, r.t1);
                  })))
      given = nullptr;
    if (!given) {
      std::vector<std::vector<cplx>> key_fields;
      for (const Keyframe& kf : scene.keyframes) {
        const auto frame = field.frame(keyframe_frame(scene, kf.t));
        key_fields.emplace_back(frame.begin(), frame.end());
      }
      replanned.emplace(space, scene, key_fields);
    }
    const std::vector<KeyframeIntervalReport>& intervals = given ? *given : replanned->intervals();
    // The plan carries every matched singularity, also those no element names (a key
    // frame's own saddle, which the static solve adds): the path through one at its first
    // key frame is the plan's, not an extra (its continuations across type changes, a node
    // changing stability, are claimed with it below).
    for (const KeyframeIntervalReport& r : intervals) {
      if (r.fallback) continue;  // left free: nothing carried
      const double t0 = topo.times[static_cast<size_t>(keyframe_frame(scene, r.t0))];
      for (const KeyframeIntervalReport::Match& m : r.matched)
        for (const SingularityPath& p : topo.paths)
          for (const PathSample& s : p.points)
            if (s.t == t0 && (s.position - m.from).norm() <= tol) {
              claimed.insert(p.id);
              path_stabilities[p.id] |= stability_bit(m.type) | stability_bit(m.to_type);
              break;
            }
    }
    for (const KeyframeIntervalReport& r : intervals)
      out.keyframe_intervals.push_back({r.from_keyframe, r.to_keyframe, r.t0, r.t1,
                                        r.fallback ? 0 : static_cast<int>(r.created.size() + r.cancelled.size()),
                                        {}, r.fallback, r.unguided_reason});
    for (const KeyframeIntervalReport& r : intervals)
      for (int creation = 0; creation < 2 && !r.fallback; ++creation)
        for (const KeyframeIntervalReport::Pair& p : creation ? r.created : r.cancelled) {
          if (N < 2 || p.t <= topo.times.front() || p.t >= topo.times.back()) continue;
          const bool sink = p.node_type == SingularityType::sink || p.node_type == SingularityType::attracting_focus;
          DesignedFeature f;
          f.kind = FeatureKind::bifurcation;
          f.source = fmt::format("solver.keyframe_topology (keyframes[{}] to [{}])", r.from_keyframe, r.to_keyframe);
          f.type = creation ? (sink ? "saddle_sink_creation" : "saddle_source_creation")
                            : (sink ? "saddle_sink_cancellation" : "saddle_source_cancellation");
          f.t_begin = f.t_end = p.t;
          f.position = on_domain(p.at);
          bifurcation_features.push_back(
              {out.designed.size(), creation ? BifurcationKind::creation : BifurcationKind::cancellation, sink, true});
          out.designed.push_back(std::move(f));
        }
  }

  // Deformation: the base's singular elements stay in place, with Jacobian M(t)·J.
  if (scene.generator == Generator::deform && scene.deform) {
    const Scene base = deform_base_scene(scene);
    for (size_t k = 0; k < base.elements.size(); ++k) {
      const auto* s = std::get_if<SingularElement>(&base.elements[k]);
      if (!s) continue;
      const CompiledElement el(base.elements[k]);
      const ElementState st = el.at(scene.time.t0);
      const Vec3 x = on_domain(st.position);
      std::vector<Expected> expected;
      for (int j = 0; j < N; ++j)
        expected.push_back(expect(j, st.position, deform_matrix(scene, topo.times[static_cast<size_t>(j)]) * st.field.matrix));
      add_singularity(fmt::format("deform.base.elements[{}]", k), s->type ? to_string(*s->type) : "jacobian", expected,
                      el.index(), x);
    }
  }

  // Edits that remove or move bifurcations, in order: each refers to the bifurcation
  // feature nearest to its `at` (space in tolerances, time in time tolerances) within twice
  // the tolerances, or else is a feature of its own.
  const double span = N > 1 ? topo.times.back() - topo.times.front() : 1.0;
  const double time_tol = out.time_tolerance > 0 ? out.time_tolerance : span;
  for (size_t i = 0; i < edits.size(); ++i) {
    const auto* remove = std::get_if<RemoveBifurcationEdit>(&edits[i]);
    const auto* move = std::get_if<MoveBifurcationEdit>(&edits[i]);
    if (!remove && !move) continue;
    const PathPoint& at = remove ? remove->at : move->at;
    const Vec3 x = on_domain(at.position);
    DesignedFeature* target = nullptr;
    double best = 2.0;
    for (const BifurcationFeature& bf : bifurcation_features) {
      DesignedFeature& f = out.designed[bf.feature];
      if (f.expected_absent) continue;
      const double score = std::max((f.position - x).norm() / tol, std::abs(f.t_begin - at.t) / time_tol);
      if (score <= best) best = score, target = &f;
    }
    if (!target) {
      DesignedFeature f;
      f.kind = FeatureKind::bifurcation;
      f.source = edit_name(i);
      f.type = op_name(edits[i]);
      f.t_begin = f.t_end = at.t;
      f.position = x;
      bifurcation_features.push_back({out.designed.size(), BifurcationKind::creation, false, false});
      out.designed.push_back(std::move(f));
      target = &out.designed.back();
    }
    target->edit = edit_name(i);
    if (remove) {
      target->expected_absent = true;
    } else {
      target->moved = true;
      target->position = on_domain(move->to.position);
      target->t_begin = target->t_end = move->to.t;
    }
  }
  for (const BifurcationFeature& bf : bifurcation_features) {
    DesignedFeature& f = out.designed[bf.feature];
    const bool any_kind = !bf.typed || f.expected_absent;
    double best_score = 1e300;
    for (size_t i = 0; i < topo.bifurcations.size(); ++i) {
      const Bifurcation& fb = topo.bifurcations[i];
      if (!any_kind && fb.kind != bf.kind) continue;
      const double d = (fb.position - f.position).norm();
      const double dtime = std::abs(fb.t - f.t_begin);
      if (d > tol || dtime > out.time_tolerance) continue;
      const double score = d / tol + (out.time_tolerance > 0 ? dtime / out.time_tolerance : 0.0);
      if (score < best_score) best_score = score, f.bifurcation = static_cast<int>(i);
    }
    const std::string kind_text = any_kind ? "bifurcation" : to_string(bf.kind);
    if (f.expected_absent) {
      f.found = f.bifurcation < 0;
      if (!f.found) {
        const Bifurcation& fb = topo.bifurcations[static_cast<size_t>(f.bifurcation)];
        f.distance = (fb.position - f.position).norm();
        f.time_offset = fb.t - f.t_begin;
        f.note = fmt::format("the {} at ({}, t = {:.3f}) is still there, although {} removes it", to_string(fb.kind),
                             position_text(fb.position, space.planar()), fb.t, f.edit);
        f.bifurcation = -1;
      }
      continue;
    }
    if (f.bifurcation < 0) {
      f.note = fmt::format("no {} within {:.3g} and {:.3g} in time of ({}, t = {:.3f}){}", kind_text, tol,
                           out.time_tolerance, position_text(f.position, space.planar()), f.t_begin,
                           f.moved ? fmt::format(", where {} moves it", f.edit) : "");
      continue;
    }
    const Bifurcation& fb = topo.bifurcations[static_cast<size_t>(f.bifurcation)];
    f.distance = (fb.position - f.position).norm();
    f.time_offset = fb.t - f.t_begin;
    f.paths = {fb.paths[0], fb.paths[1]};
    claimed.insert(f.paths.begin(), f.paths.end());
    designed_bifs.insert(f.bifurcation);
    if (!bf.typed) {
      f.found = true;
      continue;
    }
    const SingularityPath& p = topo.paths[static_cast<size_t>(fb.paths[0])];
    const SingularityPath& q = topo.paths[static_cast<size_t>(fb.paths[1])];
    const SingularityPath& node = p.index > 0 ? p : q;
    const SingularityPath& saddle = p.index > 0 ? q : p;
    const Stability want = bf.sink ? Stability::attracting : Stability::repelling;
    f.found = saddle.type == SingularityType::saddle && stability(node.type) == want;
    if (!f.found)
      f.note = fmt::format("the {} at t = {:.3f} joins a {} and a {}, not a saddle and a {}", to_string(bf.kind), fb.t,
                           to_string(p.type), to_string(q.type), bf.sink ? "sink" : "source");
  }

  // Hopf events: the nearest of the field's within the tolerances, of the designed
  // criticality. (The field's others are implied or extra, below: found for every scene.)
  PeriodicOrbits own_orbits;
  const PeriodicOrbits* orbits = options.orbits;
  if (!orbits) {
    own_orbits = find_periodic_orbits(space.bundle(), field, topo);
    orbits = &own_orbits;
  }
  const int B = static_cast<int>(topo.bifurcations.size());  // Hopf event i is bifurcation B + i
  std::set<int> designed_hopf;  // indices into orbits->hopf
  for (const HopfFeature& hf : hopf_features) {
    DesignedFeature& f = out.designed[hf.feature];
    double best_score = 1e300;
    int best = -1;
    for (size_t i = 0; i < orbits->hopf.size(); ++i) {
      const HopfEvent& ev = orbits->hopf[i];
      const double d = (ev.position - f.position).norm();
      const double dtime = std::abs(ev.t - f.t_begin);
      if (d > tol || dtime > out.time_tolerance) continue;
      const double score = d / tol + (out.time_tolerance > 0 ? dtime / out.time_tolerance : 0.0);
      if (score < best_score) best_score = score, best = static_cast<int>(i);
    }
    if (best < 0) {
      f.note = fmt::format("no Hopf event within {:.3g} and {:.3g} in time of ({}, t = {:.3f})", tol,
                           out.time_tolerance, position_text(f.position, space.planar()), f.t_begin);
      continue;
    }
    const HopfEvent& ev = orbits->hopf[static_cast<size_t>(best)];
    designed_hopf.insert(best);
    f.bifurcation = B + best;
    f.distance = (ev.position - f.position).norm();
    f.time_offset = ev.t - f.t_begin;
    f.paths = ev.paths;
    claimed.insert(f.paths.begin(), f.paths.end());
    f.found = ev.supercritical == hf.supercritical;
    if (!f.found)
      f.note = fmt::format("the Hopf event at t = {:.3f} is {} (its cycle is {}), not {}", ev.t,
                           ev.supercritical ? "supercritical" : "subcritical",
                           ev.supercritical ? "attracting" : "repelling",
                           hf.supercritical ? "supercritical" : "subcritical");
  }

  // Cancelled pairs: absent at their frames.
  for (const Cut& c : cuts) {
    DesignedFeature f;
    f.kind = FeatureKind::singularity;
    f.source = edit_name(c.edit);
    f.type = "cancel";
    f.edit = f.source;
    f.expected_absent = true;
    f.t_begin = f.t_end = topo.times[static_cast<size_t>(c.frame)];
    f.position = c.pair[0];
    f.frames = 1;
    f.found = true;
    for (const Singularity& sg : topo.singularities[static_cast<size_t>(c.frame)])
      for (const Vec3& x : c.pair)
        if (f.found && (sg.position - x).norm() <= tol) {
          f.found = false;
          f.note = fmt::format("the {} at {} is still there at frame {}, although {} cancels it", to_string(sg.type),
                               position_text(sg.position, space.planar()), c.frame, f.edit);
        }
    f.frames_matched = f.found ? 1 : 0;
    out.designed.push_back(std::move(f));
  }

  // Continuations across type changes: a path whose last point is another's first.
  const int P = static_cast<int>(topo.paths.size());
  using Key = std::tuple<double, double, double, double>;
  auto key = [](const PathSample& s) { return Key{s.t, s.position.x(), s.position.y(), s.position.z()}; };
  std::map<Key, std::vector<int>> starts;
  for (const SingularityPath& p : topo.paths) starts[key(p.points.front())].push_back(p.id);
  std::vector<std::vector<int>> continuation(static_cast<size_t>(P));  // both directions
  std::vector<std::vector<int>> type_change_at(static_cast<size_t>(P));  // p → q, at p's end
  std::vector<std::vector<int>> continues_from(static_cast<size_t>(P));  // q ← p, at q's start
  for (const SingularityPath& p : topo.paths) {
    const auto it = starts.find(key(p.points.back()));
    if (it == starts.end()) continue;
    for (const int q : it->second) {
      if (q == p.id) continue;
      continuation[static_cast<size_t>(p.id)].push_back(q);
      continuation[static_cast<size_t>(q)].push_back(p.id);
      type_change_at[static_cast<size_t>(p.id)].push_back(q);
      continues_from[static_cast<size_t>(q)].push_back(p.id);
    }
  }
  std::vector<int> stack(claimed.begin(), claimed.end());
  while (!stack.empty()) {
    const int p = stack.back();
    stack.pop_back();
    for (const int q : continuation[static_cast<size_t>(p)])
      if (claimed.insert(q).second) stack.push_back(q);
  }
  // The continuations belong to the features whose paths they continue.
  for (DesignedFeature& f : out.designed) {
    std::set<int> ps(f.paths.begin(), f.paths.end());
    std::vector<int> todo(f.paths.begin(), f.paths.end());
    while (!todo.empty()) {
      const int p = todo.back();
      todo.pop_back();
      for (const int q : continuation[static_cast<size_t>(p)])
        if (ps.insert(q).second) todo.push_back(q);
    }
    f.paths.assign(ps.begin(), ps.end());
  }
  // The designed stabilities of each chain of paths joined by type changes.
  std::vector<unsigned> chain_stabilities(static_cast<size_t>(P), 0);
  {
    std::vector<unsigned> own(static_cast<size_t>(P), 0);
    for (const auto& [p, bits] : path_stabilities) own[static_cast<size_t>(p)] |= bits;
    for (const auto& [k, bits] : feature_stabilities)
      for (const int p : out.designed[k].paths) own[static_cast<size_t>(p)] |= bits;
    std::vector<int> chain(static_cast<size_t>(P), -1);
    for (int p0 = 0; p0 < P; ++p0) {
      if (chain[static_cast<size_t>(p0)] >= 0) continue;
      std::vector<int> members{p0}, todo{p0};
      chain[static_cast<size_t>(p0)] = p0;
      unsigned bits = own[static_cast<size_t>(p0)];
      while (!todo.empty()) {
        const int p = todo.back();
        todo.pop_back();
        for (const int q : continuation[static_cast<size_t>(p)])
          if (chain[static_cast<size_t>(q)] < 0) {
            chain[static_cast<size_t>(q)] = p0;
            bits |= own[static_cast<size_t>(q)];
            members.push_back(q);
            todo.push_back(q);
          }
      }
      for (const int p : members) chain_stabilities[static_cast<size_t>(p)] = bits;
    }
  }

  // A template a few edges wide (template_resolved_edges, generate.h).
  for (const auto& [feature, scale, resolved_edges] : template_scales) {
    DesignedFeature& f = out.designed[feature];
    const double edges = scale / mesh.mean_edge_length();
    // Not where an event was matched but of the other kind (the note says which).
    const bool unmatched = f.kind == FeatureKind::singularity || f.bifurcation < 0;
    if (!f.found && !f.expected_absent && unmatched && edges < resolved_edges)
      f.note += fmt::format("{}its scale {:.3g} spans {:.1f} mean edge lengths: the mesh resolves a template "
                            "from about {:g}",
                            f.note.empty() ? "" : "; ", scale, edges, resolved_edges);
    // Or the surface closes round within it (placed on the end of a tail or a leg): the
    // template's normal form lives in a plane, and its cycles and ramps do not fit there.
    if (!f.found && !f.expected_absent && unmatched && !space.planar()) {
      const double curvature = space.curvature_within(f.position, 0.5 * scale);
      if (curvature > kTemplateMostCurvature)
        f.note += fmt::format("{}the surface within half its scale ({:.3g}) of its point holds a total curvature "
                              "of {:.2f} (over π: it closes round, as at the end of a tail or a finger); a template "
                              "needs a patch about flat at its scale (place it where the surface is flatter, or "
                              "make it smaller)",
                              f.note.empty() ? "" : "; ", 0.5 * scale, curvature);
    }
  }

  // Bifurcations: designed, implied, extra.
  const auto is_claimed = [&](int p) { return claimed.count(p) > 0; };
  for (size_t i = 0; i < topo.bifurcations.size(); ++i) {
    if (designed_bifs.count(static_cast<int>(i))) continue;
    const Bifurcation& b = topo.bifurcations[i];
    if (is_claimed(b.paths[0]) && is_claimed(b.paths[1]))
      out.implied_bifurcations.push_back(static_cast<int>(i));
    else
      out.extra_bifurcations.push_back(static_cast<int>(i));
  }
  // A Hopf event not designed is implied where its focus's design changes stability (every
  // path of the focus designed, and the design repelling and attracting along them: a node
  // matched across key frames to one of the other stability, an element turned from source
  // to sink); else extra. (Without this a designed center that drifts into a focus with a
  // limit cycle, as on CGAL's mushroom knot, passed as "no extras".)
  std::vector<int> hopf_on_designed;  // extra Hopf events all of whose paths are designed
  for (int i = 0; i < static_cast<int>(orbits->hopf.size()); ++i) {
    if (designed_hopf.count(i)) continue;
    const HopfEvent& ev = orbits->hopf[static_cast<size_t>(i)];
    const bool designed_paths = !ev.paths.empty() && std::all_of(ev.paths.begin(), ev.paths.end(), is_claimed);
    unsigned bits = 0;
    for (const int p : ev.paths) bits |= chain_stabilities[static_cast<size_t>(p)];
    if (designed_paths && bits == (kRepelling | kAttracting)) {
      out.implied_bifurcations.push_back(B + i);
    } else {
      out.extra_bifurcations.push_back(B + i);
      if (designed_paths) hopf_on_designed.push_back(i);
    }
  }
  // The time of bifurcation i of the analysis JSON (saddle–node, then Hopf).
  auto event_time = [&](int i) {
    return i < B ? topo.bifurcations[static_cast<size_t>(i)].t : orbits->hopf[static_cast<size_t>(i - B)].t;
  };
  auto hopf_text = [](const HopfEvent& ev) {
    return fmt::format("a {} Hopf event ({} cycle) at t={:.3f}", ev.supercritical ? "supercritical" : "subcritical",
                       ev.supercritical ? "an attracting" : "a repelling", ev.t);
  };
  for (int p = 0; p < P; ++p)
    if (!is_claimed(p)) out.extra_paths.push_back(p);
  for (const int i : out.extra_bifurcations) {
    const double t = event_time(i);
    for (size_t k = 0; k < out.keyframe_intervals.size(); ++k) {
      DesignCheck::KeyframeInterval& ki = out.keyframe_intervals[k];
      if ((t > ki.t0 || (k == 0 && t >= ki.t0)) && t <= ki.t1) {
        ki.extra_bifurcations.push_back(i);
        break;
      }
    }
  }

  // Extra groups: union–find over extra paths joined by bifurcations and type changes.
  std::vector<int> parent(static_cast<size_t>(P));
  std::iota(parent.begin(), parent.end(), 0);
  auto root = [&](int x) {
    while (parent[static_cast<size_t>(x)] != x) {
      auto& up = parent[static_cast<size_t>(x)];
      up = parent[static_cast<size_t>(up)];  // path halving
      x = up;
    }
    return x;
  };
  auto unite = [&](int a, int b) {
    if (!is_claimed(a) && !is_claimed(b)) parent[static_cast<size_t>(root(a))] = root(b);
  };
  for (const Bifurcation& b : topo.bifurcations) unite(b.paths[0], b.paths[1]);
  for (const HopfEvent& ev : orbits->hopf)
    for (size_t k = 1; k < ev.paths.size(); ++k) unite(ev.paths[0], ev.paths[k]);
  for (int p = 0; p < P; ++p)
    for (const int q : continuation[static_cast<size_t>(p)]) unite(p, q);
  std::map<int, ExtraGroup> groups;
  for (const int p : out.extra_paths) groups[root(p)].paths.push_back(p);
  const bool planar = space.planar();
  const double t_first = N ? topo.times.front() : 0.0, t_last = N ? topo.times.back() : 0.0;
  for (auto& [r, g] : groups) {
    std::set<int> members(g.paths.begin(), g.paths.end());
    g.t_begin = 1e300;
    g.t_end = -1e300;
    size_t count = 0;
    for (const int p : g.paths) {
      const SingularityPath& path = topo.paths[static_cast<size_t>(p)];
      g.t_begin = std::min(g.t_begin, path.birth);
      g.t_end = std::max(g.t_end, path.death);
      for (const PathSample& s : path.points) g.center += s.position, ++count;
    }
    if (count) g.center /= static_cast<double>(count);
    // Events, in time order.
    std::vector<std::pair<double, std::string>> events;
    std::set<std::pair<int, bool>> explained;  // (path, at its end) explained by a bifurcation or type change
    for (size_t i = 0; i < topo.bifurcations.size(); ++i) {
      const Bifurcation& b = topo.bifurcations[i];
      const bool in0 = members.count(b.paths[0]) > 0, in1 = members.count(b.paths[1]) > 0;
      if (!in0 && !in1) continue;
      g.bifurcations.push_back(static_cast<int>(i));
      const bool creation = b.kind == BifurcationKind::creation;
      for (const int p : b.paths) explained.insert({p, !creation});
      std::string what = creation ? "created" : "cancelled";
      if (!in0 || !in1) {
        const SingularityPath& other = topo.paths[static_cast<size_t>(in0 ? b.paths[1] : b.paths[0])];
        what += fmt::format(" with a designed {}", to_string(other.type));
      }
      events.emplace_back(b.t, fmt::format("{} at t={:.3f}", what, b.t));
    }
    for (size_t i = 0; i < orbits->hopf.size(); ++i) {
      const HopfEvent& ev = orbits->hopf[i];
      const auto in = [&](int p) { return members.count(p) > 0; };
      if (designed_hopf.count(static_cast<int>(i)) || std::none_of(ev.paths.begin(), ev.paths.end(), in)) continue;
      g.bifurcations.push_back(B + static_cast<int>(i));
      events.emplace_back(ev.t, hopf_text(ev) + (std::all_of(ev.paths.begin(), ev.paths.end(), in)
                                                     ? ""
                                                     : " of a focus that turns into a designed one"));
    }
    for (const int p : g.paths)
      for (const int q : type_change_at[static_cast<size_t>(p)]) {
        const SingularityPath& a = topo.paths[static_cast<size_t>(p)];
        const SingularityPath& b = topo.paths[static_cast<size_t>(q)];
        events.emplace_back(a.death, fmt::format("turns from {} to {}{} at t={:.3f}", to_string(a.type),
                                                 members.count(q) ? "" : "the designed ", to_string(b.type), a.death));
      }
    for (const int p : g.paths) {
      const SingularityPath& path = topo.paths[static_cast<size_t>(p)];
      if (!continues_from[static_cast<size_t>(p)].empty() && !members.count(continues_from[static_cast<size_t>(p)].front()))
        events.emplace_back(path.birth, fmt::format("turns from the designed {} at t={:.3f}",
                                                    to_string(topo.paths[static_cast<size_t>(continues_from[static_cast<size_t>(p)].front())].type),
                                                    path.birth));
      if (!type_change_at[static_cast<size_t>(p)].empty()) explained.insert({p, true});
      if (!continues_from[static_cast<size_t>(p)].empty()) explained.insert({p, false});
      if (path.birth > t_first && !explained.count({p, false}))
        events.emplace_back(path.birth, fmt::format("enters through the boundary at t={:.3f}", path.birth));
      if (path.death < t_last && !explained.count({p, true}))
        events.emplace_back(path.death, fmt::format("leaves through the boundary at t={:.3f}", path.death));
    }
    std::stable_sort(events.begin(), events.end(),
                     [](const auto& a, const auto& b) { return a.first < b.first; });
    events.erase(std::unique(events.begin(), events.end()), events.end());
    std::string types;
    for (size_t k = 0; k < g.paths.size() && k < 6; ++k)
      types += (k ? "+" : "") + std::string(to_string(topo.paths[static_cast<size_t>(g.paths[k])].type));
    if (g.paths.size() > 6) types += "+…";
    const std::string what = g.paths.size() == 1   ? fmt::format("1 path ({})", types)
                             : g.paths.size() == 2 ? fmt::format("2 paths ({} pair)", types)
                                                   : fmt::format("{} paths ({})", g.paths.size(), types);
    g.description = fmt::format("{} living t∈[{:.3f}, {:.3f}] near {}", what, g.t_begin, g.t_end,
                                position_text(g.center, planar));
    for (size_t k = 0; k < events.size(); ++k) g.description += (k ? ", " : ": ") + events[k].second;
    out.extras.push_back(std::move(g));
  }
  // A Hopf event not asked for on a designed focus: a group of its own, without paths.
  for (const int i : hopf_on_designed) {
    const HopfEvent& ev = orbits->hopf[static_cast<size_t>(i)];
    ExtraGroup g;
    g.bifurcations = {B + i};
    g.t_begin = g.t_end = ev.t;
    g.center = ev.position;
    std::string owner = "a singularity the key-frame plan carries";
    for (const DesignedFeature& f : out.designed)
      if (f.kind == FeatureKind::singularity &&
          std::any_of(ev.paths.begin(), ev.paths.end(),
                      [&](int p) { return std::find(f.paths.begin(), f.paths.end(), p) != f.paths.end(); })) {
        owner = fmt::format("{} ({})", f.source, f.type);
        break;
      }
    g.description = fmt::format("{} near {}, on the designed path of {}", hopf_text(ev), position_text(ev.position, planar),
                                owner);
    out.extras.push_back(std::move(g));
  }
  std::stable_sort(out.extras.begin(), out.extras.end(),
                   [](const ExtraGroup& a, const ExtraGroup& b) { return a.t_begin < b.t_begin; });
  return out;
}

std::string DesignCheck::summary(int max_lines) const {
  int sings = 0, bifs = 0, found_count = 0;
  for (const DesignedFeature& f : designed) {
    (f.kind == FeatureKind::singularity ? sings : bifs) += 1;
    found_count += f.found;
  }
  auto plural = [](size_t n, const char* one, const char* many) {
    return fmt::format("{} {}", n, n == 1 ? one : many);
  };
  std::string s = fmt::format("designed {}, {}: ", plural(static_cast<size_t>(sings), "singularity", "singularities"),
                              plural(static_cast<size_t>(bifs), "bifurcation", "bifurcations"));
  s += designed.empty()          ? "nothing to find"
       : all_found()             ? "all found"
                                 : fmt::format("{} of {} found", found_count, designed.size());
  if (!implied_bifurcations.empty())
    s += fmt::format(" ({} implied by the design)", plural(implied_bifurcations.size(), "bifurcation", "bifurcations"));
  if (extra_paths.empty() && extra_bifurcations.empty())
    s += "; no extras";
  else
    s += fmt::format("; extra: {}, {}", plural(extra_paths.size(), "path", "paths"),
                     plural(extra_bifurcations.size(), "bifurcation", "bifurcations"));
  int removed = 0, moved = 0;
  for (const DesignedFeature& f : designed) {
    removed += f.expected_absent && f.found;
    moved += f.moved && f.found;
  }
  if (removed || moved) {
    std::string parts = removed ? fmt::format("{} removed", removed) : "";
    if (moved) parts += fmt::format("{}{} moved", removed ? ", " : "", moved);
    s += fmt::format(" ({} as edited)", parts);
  }
  std::vector<std::string> lines;
  for (const DesignedFeature& f : designed) {
    if (!f.found) {
      lines.push_back(fmt::format("not found: {} ({}): {}", f.source, f.type, f.note));
    } else if (f.expected_absent) {
      lines.push_back(fmt::format("removed as edited: {} ({}) by {}", f.source, f.type, f.edit));
    } else if (f.moved) {
      lines.push_back(fmt::format("moved as edited: {} ({}) by {}: found {:.3g} from its new place, {:+.3f} in time",
                                  f.source, f.type, f.edit, f.distance, f.time_offset));
    }
  }
  for (const ExtraGroup& g : extras) lines.push_back("extra: " + g.description);
  const size_t shown = std::min(lines.size(), static_cast<size_t>(std::max(max_lines, 0)));
  for (size_t k = 0; k < shown; ++k) s += "\n  " + lines[k];
  if (shown < lines.size()) s += fmt::format("\n  … and {} more (see the design JSON)", lines.size() - shown);
  return s;
}

nlohmann::json design_check_to_json(const DesignCheck& check) {
  using nlohmann::json;
  auto vec3 = [](const Vec3& x) { return json::array({x.x(), x.y(), x.z()}); };
  json designed = json::array();
  for (const DesignedFeature& f : check.designed) {
    json j = {{"source", f.source},
              {"kind", f.kind == FeatureKind::singularity ? "singularity" : "bifurcation"},
              {"type", f.type}};
    if (f.kind == FeatureKind::singularity) {
      j["index"] = f.index;
      j["life"] = json::array({f.t_begin, f.t_end});
      j["position"] = vec3(f.position);
      j["found"] = f.found;
      j["frames"] = {{"checked", f.frames}, {"matched", f.frames_matched}, {"type_differs", f.frames_type_differs}};
      j["max_distance"] = f.max_distance;
      j["max_shift"] = f.max_shift;
    } else {
      j["t"] = f.t_begin;
      j["position"] = vec3(f.position);
      j["found"] = f.found;
      if (f.bifurcation >= 0) {
        j["bifurcation"] = f.bifurcation;
        j["distance"] = f.distance;
        j["time_offset"] = f.time_offset;
      } else {
        j["bifurcation"] = nullptr;
      }
    }
    j["paths"] = f.paths;
    if (!f.edit.empty()) {
      j["edit"] = f.edit;
      j["expected"] = f.expected_absent ? "absent" : f.moved ? "moved" : "present";
      if (f.kind == FeatureKind::singularity) j["frames"]["edited"] = f.frames_edited;
    }
    if (!f.note.empty()) j["note"] = f.note;
    designed.push_back(std::move(j));
  }
  json groups = json::array();
  for (const ExtraGroup& g : check.extras)
    groups.push_back({{"paths", g.paths},
                      {"bifurcations", g.bifurcations},
                      {"life", json::array({g.t_begin, g.t_end})},
                      {"center", vec3(g.center)},
                      {"description", g.description}});
  json out = json{{"all_found", check.all_found()},
              {"summary", check.summary(1 << 30)},
              {"tolerance", {{"position", check.position_tolerance}, {"time", check.time_tolerance}}},
              {"designed", std::move(designed)},
              {"implied_bifurcations", check.implied_bifurcations},
              {"extra", {{"paths", check.extra_paths}, {"bifurcations", check.extra_bifurcations}, {"groups", std::move(groups)}}}};
  if (!check.keyframe_intervals.empty()) {
    json intervals = json::array();
    for (const DesignCheck::KeyframeInterval& k : check.keyframe_intervals)
      intervals.push_back({{"keyframes", json::array({k.from_keyframe, k.to_keyframe})},
                           {"interval", json::array({k.t0, k.t1})},
                           {"planned_bifurcations", k.planned},
                           {"extra_bifurcations", k.extra_bifurcations},
                           {"fallback", k.fallback}});
    for (size_t k = 0; k < check.keyframe_intervals.size(); ++k)
      if (!check.keyframe_intervals[k].unguided_reason.empty())
        intervals[k]["unguided_reason"] = check.keyframe_intervals[k].unguided_reason;
    out["keyframe_intervals"] = std::move(intervals);
  }
  return out;
}

}  // namespace tvf
