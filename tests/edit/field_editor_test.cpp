// Topological edits (DESIGN §7): pair cancellation, bifurcation removal and movement,
// smoothing, replay from the scene and refusals, measured with the analysis.
#include "tvf/analysis/coherence.h"
#include "tvf/analysis/singularities.h"
#include "tvf/analysis/topology.h"
#include "tvf/scene/design_space.h"
#include "tvf/design/generate.h"
#include "tvf/scene/scene_json.h"
#include "tvf/edit/field_editor.h"

#include "support/test_paths.h"

#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <cstring>

namespace tvf {
namespace {

using json = nlohmann::json;

// 33×33 grid on [-1, 1]² (cell 1/16), 21 frames, constrained design: a flow to the right
// with a saddle drifting right and a source downstream of it (the pair to cancel), and a
// centre far from them.
json pair_scene() {
  return json::parse(R"({"tvf": 1,
    "domain": {"grid": {"size": [33, 33], "min": [-1, -1], "max": [1, 1]}},
    "time": {"frames": 21, "range": [0, 1]},
    "generator": "constrained", "solver": {"region_radius": 0.15},
    "falloff": 20,
    "elements": [
      {"kind": "regular", "pathline": [[-0.9, -0.3, 0], [-0.8, -0.3, 1]]},
      {"kind": "singular", "jacobian": [[-1, 0], [0, 1]], "path": [[-0.3, -0.3, 0], [-0.25, -0.3, 1]]},
      {"kind": "singular", "type": "source", "path": [[0.2, -0.3, 0]]},
      {"kind": "singular", "type": "ccw_center", "path": [[0.1, 0.6, 0]]}]})");
}

// One saddle–sink creation at (0, 0.1, 0.4) whose pair lives to t = 1, and a centre.
json bifurcation_scene() {
  return json::parse(R"({"tvf": 1,
    "domain": {"grid": {"size": [33, 33], "min": [-1, -1], "max": [1, 1]}},
    "time": {"frames": 21, "range": [0, 1]},
    "falloff": 30,
    "elements": [
      {"kind": "bifurcation", "type": "saddle_sink_creation", "at": [0, 0.1, 0.4],
       "scale": 0.3, "time_scale": 0.3, "angle": 0},
      {"kind": "singular", "type": "ccw_center", "path": [[-0.5, -0.6, 0]]}]})");
}

struct Design {
  Scene scene;
  std::unique_ptr<DesignSpace> space;
  Field field;
  explicit Design(const json& j) : scene(scene_from_json(j, "test.json", "test.json")) {
    space = make_design_space(scene);
    GenerateOptions o;
    o.parallel = false;
    field = generate_unedited(*space, scene, o);
  }
};

const Singularity* nearest_to(const std::vector<Singularity>& s, const Vec3& p) {
  const Singularity* best = nullptr;
  for (const auto& x : s)
    if (!best || (x.position - p).norm() < (best->position - p).norm()) best = &x;
  return best;
}

bool bitwise_equal(const Field& a, const Field& b) {
  return a.data().size() == b.data().size() &&
         std::memcmp(a.data().data(), b.data().data(), a.data().size() * sizeof(cplx)) == 0;
}

TEST(FieldEditor, CancelRemovesThePairAndNothingElse) {
  Design d(pair_scene());
  const TangentBundle& bundle = d.space->bundle();
  const int j = 10;
  const auto before = find_singularities(bundle, d.field, j);
  const Vec3 source(0.2, -0.3, 0), saddle(-0.275, -0.3, 0);
  const Singularity* a = nearest_to(before, source);
  const Singularity* b = nearest_to(before, saddle);
  ASSERT_TRUE(a && b);
  ASSERT_EQ(a->index, 1);
  ASSERT_EQ(b->index, -1);
  ASSERT_LT((a->position - source).norm(), 0.1);
  ASSERT_LT((b->position - saddle).norm(), 0.1);

  Field edited = d.field;
  FieldEditor editor(*d.space, edit_settings(d.scene));
  CancelEdit c;
  c.frame = j;
  c.pair = {source, saddle};
  const EditReport report = editor.cancel(edited, c);
  EXPECT_EQ(report.key_frames, std::vector<int>{j});
  EXPECT_EQ(report.window_first, 8);  // ±10 % of 20 frame steps
  EXPECT_EQ(report.window_last, 12);

  // The pair is gone at frame j: two singularities fewer, none left near either.
  const auto after = find_singularities(bundle, edited, j);
  EXPECT_EQ(after.size() + 2, before.size());
  for (const auto& s : after) {
    EXPECT_GT((s.position - a->position).norm(), 0.15) << to_string(s.type);
    EXPECT_GT((s.position - b->position).norm(), 0.15) << to_string(s.type);
  }
  // No other singularity moves by more than one cell, at any frame.
  const double cell = 2.0 / 32 * std::sqrt(2.0);
  for (int k = 0; k < d.field.frames(); ++k) {
    const auto old_k = find_singularities(bundle, d.field, k);
    const auto new_k = find_singularities(bundle, edited, k);
    for (const auto& s : old_k) {
      if ((s.position - a->position).norm() < 0.3 || (s.position - b->position).norm() < 0.3) continue;
      const Singularity* n = nearest_to(new_k, s.position);
      ASSERT_TRUE(n) << "frame " << k;
      EXPECT_LE((n->position - s.position).norm(), cell) << "frame " << k << " " << to_string(s.type);
      EXPECT_EQ(n->index, s.index);
    }
  }
  // Frames outside the window are untouched, bit for bit.
  for (int k : {0, 7, 13, 20})
    for (int v = 0; v < edited.num_vertices(); ++v) ASSERT_EQ(edited.at(k, v), d.field.at(k, v)) << k;

  // The window keeps the neighbouring frames smooth: the largest frame-to-frame change is
  // well below that of the same cancellation without the space-time re-solve.
  Field abrupt = d.field;
  c.window = 0;
  editor.cancel(abrupt, c);
  const auto y_smooth = coherence(edited);
  const auto y_abrupt = coherence(abrupt);
  const double max_smooth = *std::max_element(y_smooth.begin(), y_smooth.end());
  const double max_abrupt = *std::max_element(y_abrupt.begin(), y_abrupt.end());
  EXPECT_LT(max_smooth, 0.6 * max_abrupt) << max_smooth << " vs " << max_abrupt;
}

TEST(FieldEditor, RefusalsLeaveTheFieldUnchanged) {
  Design d(pair_scene());
  FieldEditor editor(*d.space, edit_settings(d.scene));
  Field field = d.field;
  auto refused = [&](const Edit& e) {
    std::string message;
    try {
      editor.apply(field, e);
    } catch (const EditRefused& x) {
      message = x.what();
    }
    EXPECT_TRUE(bitwise_equal(field, d.field)) << describe(e);
    return message;
  };
  CancelEdit same;  // the source and the centre: both +1
  same.frame = 5;
  same.pair = {Vec3(0.2, -0.3, 0), Vec3(0.1, 0.6, 0)};
  EXPECT_NE(refused(same).find("both have index +1"), std::string::npos) << refused(same);
  CancelEdit twice;  // two positions next to the same singularity
  twice.frame = 5;
  twice.pair = {Vec3(0.19, -0.3, 0), Vec3(0.21, -0.31, 0)};
  EXPECT_NE(refused(twice).find("the same singularity"), std::string::npos);
  CancelEdit late;
  late.frame = 21;
  late.pair = {Vec3(0.2, -0.3, 0), Vec3(-0.275, -0.3, 0)};
  EXPECT_NE(refused(late).find("outside the field's frames 0–20"), std::string::npos);
  RemoveBifurcationEdit none;  // this design has no bifurcation
  none.at = {Vec3::Zero(), 0.5};
  EXPECT_NE(refused(none).find("no bifurcation"), std::string::npos);
}

class IsolatedBifurcation : public testing::TestWithParam<const char*> {};

TEST_P(IsolatedBifurcation, RemovingItRemovesBothPaths) {
  json scene = bifurcation_scene();
  scene["elements"][0]["type"] = GetParam();
  const bool creation = std::string(GetParam()).ends_with("creation");
  // The mirror in time for the cancellation: at t = 0.6, its pair living from t = 0 (a
  // sharper falloff, or the sink's field and the centre's make a second pair).
  if (!creation) {
    scene["elements"][0]["at"][2] = 0.6;
    scene["falloff"] = 60;
  }
  const double t_bif = creation ? 0.4 : 0.6;
  Design d(scene);
  const TangentBundle& bundle = d.space->bundle();
  const Topology before = analyze_topology(bundle, d.field);
  ASSERT_EQ(before.bifurcations.size(), 1u);
  const Bifurcation bif = before.bifurcations[0];
  ASSERT_EQ(bif.kind, creation ? BifurcationKind::creation : BifurcationKind::cancellation);
  EXPECT_NEAR(bif.t, t_bif, 0.06);

  Field edited = d.field;
  FieldEditor editor(*d.space, edit_settings(d.scene));
  RemoveBifurcationEdit r;
  r.at = {Vec3(0, 0.1, 0), t_bif};
  const EditReport report = editor.remove_bifurcation(edited, r);
  EXPECT_FALSE(report.key_frames.empty());

  const Topology after = analyze_topology(bundle, edited);
  EXPECT_TRUE(after.bifurcations.empty()) << after.bifurcations.size();
  EXPECT_EQ(after.paths.size() + 2, before.paths.size());
  // The centre's path is still there, where it was.
  for (size_t j = 0; j < after.singularities.size(); ++j) {
    ASSERT_EQ(after.singularities[j].size(), 1u) << "frame " << j;
    EXPECT_LT((after.singularities[j][0].position - Vec3(-0.5, -0.6, 0)).norm(), 0.1);
  }
}

// Both kinds: a creation whose pair lives to t = 1, a cancellation whose pair lives from 0.
// (A saddle–source cancellation here is refused: the centre's rotation dominates the
// boundary of every region around the source, and the harmonic fill keeps the pair; see
// docs/architecture.md.)
INSTANTIATE_TEST_SUITE_P(FieldEditor, IsolatedBifurcation,
                         testing::Values("saddle_sink_creation", "saddle_sink_cancellation"));

TEST(FieldEditor, MovingABifurcationMovesItsPoint) {
  Design d(bifurcation_scene());
  const TangentBundle& bundle = d.space->bundle();
  Field edited = d.field;
  FieldEditor editor(*d.space, edit_settings(d.scene));
  MoveBifurcationEdit m;
  m.at = {Vec3(0, 0.1, 0), 0.4};
  // Just before frame 10 (t = 0.5), so the moved pair is young there, as the original is
  // at frame 9 (the original creation is at t ≈ 0.44).
  m.to = {Vec3(0.3, 0.5, 0), 0.49};
  m.window = 0.25;
  editor.move_bifurcation(edited, m);
  const Topology after = analyze_topology(bundle, edited);
  ASSERT_FALSE(after.bifurcations.empty());
  // The creation nearest to the target is there (within two cells and two frames).
  const Bifurcation* best = nullptr;
  for (const auto& b : after.bifurcations)
    if (b.kind == BifurcationKind::creation &&
        (!best || (b.position - m.to.position).norm() < (best->position - m.to.position).norm()))
      best = &b;
  ASSERT_TRUE(best);
  EXPECT_LT((best->position - m.to.position).norm(), 2 * 2.0 / 32 * std::sqrt(2.0));
  EXPECT_NEAR(best->t, 0.49, 0.05);
  // None is left at the old place.
  for (const auto& b : after.bifurcations) EXPECT_GT((b.position - m.at.position).norm(), 0.15);
}

TEST(FieldEditor, SmoothingLowersTheEnergyAndKeepsTheDesign) {
  Design d(pair_scene());
  Field edited = d.field;
  FieldEditor editor(*d.space, edit_settings(d.scene));
  SmoothEdit s;
  s.strength = 0.5;
  editor.smooth(edited, s);
  const ConnectionLaplacian L = connection_laplacian(d.space->bundle());
  // The space-time energy of DESIGN §5.3: Σ_j z_jᴴ L z_j + b Σ_j Σ_i d_i |z_{j+1,i} − z_{j,i}|².
  const double b = d.scene.solver.temporal_weight;
  auto energy = [&](const Field& f) {
    double e = 0;
    for (int j = 0; j < f.frames(); ++j) {
      Eigen::Map<const Eigen::VectorXcd> z(f.frame(j).data(), f.num_vertices());
      e += (z.adjoint() * (L.matrix * z)).real()(0, 0);
      if (j + 1 < f.frames())
        for (int i = 0; i < f.num_vertices(); ++i) e += b * L.weight_sum[i] * std::norm(f.at(j + 1, i) - f.at(j, i));
    }
    return e;
  };
  EXPECT_LT(energy(edited), 0.9 * energy(d.field));
  // Still the same singularities (smoothing with strength 0.5 moves none out of its cell
  // neighbourhood).
  for (int j : {0, 10, 20})
    EXPECT_EQ(find_singularities(d.space->bundle(), edited, j).size(),
              find_singularities(d.space->bundle(), d.field, j).size());
  // A stronger smoothing changes the field more.
  Field stronger = d.field;
  s.strength = 1.0;
  editor.smooth(stronger, s);
  EXPECT_LT(energy(stronger), energy(edited));
}

TEST(FieldEditor, ReplayFromTheSceneIsBitForBit) {
  json j = pair_scene();
  j["edits"] = json::parse(R"([{"op": "cancel", "frame": 10, "pair": [[0.2, -0.3], [-0.275, -0.3]]},
                               {"op": "smooth", "strength": 0.3}])");
  const Scene scene = scene_from_json(j, "test.json", "test.json");
  const auto space = make_design_space(scene);
  const Field a = generate(*space, scene);
  GenerateReport report;
  const Field b = generate(*space, scene, {}, &report);
  EXPECT_TRUE(bitwise_equal(a, b));
  EXPECT_EQ(report.edits.size(), 2u);
  // The same as applying the edits by hand, and not the unedited field.
  GenerateOptions o;
  Field c = generate_unedited(*space, scene, o);
  EXPECT_FALSE(bitwise_equal(a, c));
  apply_scene_edits(*space, scene, c);
  EXPECT_TRUE(bitwise_equal(a, c));
  // And a round trip through the scene text keeps the edits.
  const Scene again = parse_scene(scene_to_text(scene), "again.json");
  EXPECT_TRUE(bitwise_equal(a, generate(*space, again)));
}

TEST(FieldEditor, ARefusedSceneEditNamesItsEntry) {
  json j = pair_scene();
  j["edits"] = json::parse(R"([{"op": "smooth", "strength": 0.3},
                               {"op": "cancel", "frame": 3, "pair": [[0.2, -0.3], [0.1, 0.6]]}])");
  const Scene scene = scene_from_json(j, "test.json", "test.json");
  const auto space = make_design_space(scene);
  const std::string message = test::error_of([&] { generate(*space, scene); });
  EXPECT_NE(message.find("test.json: edits[1]: "), std::string::npos) << message;
  EXPECT_NE(message.find("index +1"), std::string::npos) << message;
}


}  // namespace
}  // namespace tvf

namespace tvf {
namespace {

// The S-shaped fold of paper §8.2's three-path case: V = (x³ − a·x − k·(t − ½), −y) has
// one saddle for |k(t − ½)| > 2(a/3)^{3/2} and, in between, two saddles and a node on the
// x axis: a saddle path (0, β), a node path (α, β) and a saddle path (α, 1).
Field fold_field(const Mesh& mesh, int frames) {
  Field f(TimeSampling{0.0, 1.0, frames}, mesh.num_vertices());
  const double a = 0.25, k = 0.2;
  for (int j = 0; j < frames; ++j)
    for (int v = 0; v < mesh.num_vertices(); ++v) {
      const Vec3& p = mesh.position(v);
      f.at(j, v) = cplx(p.x() * p.x() * p.x() - a * p.x() - k * (f.time().time(j) - 0.5), -p.y());
    }
  return f;
}

// At every resolution (issue 16: it worked at 33² and failed at 49² and 65², leaving five
// paths and four new bifurcations while reporting success).
class ThreePathCase : public testing::TestWithParam<int> {};

TEST_P(ThreePathCase, CollapsesToOneSingularity) {
  GridSpec g;
  g.nx = g.ny = GetParam();
  const DesignSpace space(make_grid(g));
  Field field = fold_field(space.mesh(), 21);
  const Topology before = analyze_topology(space.bundle(), field);
  ASSERT_EQ(before.bifurcations.size(), 2u);
  size_t most = 0;
  for (const auto& s : before.singularities) most = std::max(most, s.size());
  ASSERT_EQ(most, 3u);

  FieldEditor editor(space);
  RemoveBifurcationEdit r;
  r.at = {before.bifurcations[1].position, before.bifurcations[1].t};
  const EditReport report = editor.remove_bifurcation(field, r);
  EXPECT_NE(report.summary.find("three-path"), std::string::npos) << report.summary;

  const Topology after = analyze_topology(space.bundle(), field);
  EXPECT_TRUE(after.bifurcations.empty()) << after.bifurcations.size();
  // The survivor travels from the first outer track to the other without a jump: no step
  // between frames is more than a quarter of the whole way (a jump would be all of it).
  const double way =
      (after.singularities.back()[0].position - after.singularities.front()[0].position).norm();
  ASSERT_GT(way, 1.0);
  for (size_t j = 1; j < after.singularities.size(); ++j)
    EXPECT_LT((after.singularities[j][0].position - after.singularities[j - 1][0].position).norm(), 0.25 * way)
        << "frame " << j;
  // One saddle path over the whole time range.
  ASSERT_EQ(after.paths.size(), 1u);
  EXPECT_EQ(after.paths[0].type, SingularityType::saddle);
  EXPECT_EQ(after.paths[0].birth, 0.0);
  EXPECT_EQ(after.paths[0].death, 1.0);
  for (size_t j = 0; j < after.singularities.size(); ++j) {
    ASSERT_EQ(after.singularities[j].size(), 1u) << "frame " << j;
    EXPECT_EQ(after.singularities[j][0].index, -1) << "frame " << j;
  }
}

INSTANTIATE_TEST_SUITE_P(FieldEditor, ThreePathCase, testing::Values(33, 49, 65, 129));

}  // namespace
}  // namespace tvf

namespace tvf {
namespace {

TEST(FieldEditor, ARegionThatWouldSwallowAnotherSingularityIsRefused) {
  // A strip one cell high: V = (f(x), y − 0.3h), f with zeros at ±0.2 and ±0.6 (indices −1,
  // +1, −1, +1 from left to right). The outer pair is ±1, but every chain of faces between
  // them passes through the two inner singularities.
  GridSpec g;
  g.nx = 33;
  g.ny = 2;
  g.min = Vec2(-1, 0);
  g.max = Vec2(1, 0.0625);
  const DesignSpace space(make_grid(g));
  Field field(TimeSampling{0.0, 1.0, 3}, space.mesh().num_vertices());
  for (int j = 0; j < 3; ++j)
    for (int v = 0; v < space.mesh().num_vertices(); ++v) {
      const Vec3& p = space.mesh().position(v);
      const double x = p.x();
      field.at(j, v) = cplx((x + 0.6) * (x + 0.2) * (x - 0.2) * (x - 0.6), p.y() - 0.3 * 0.0625);
    }
  const auto sings = find_singularities(space.bundle(), field, 1);
  ASSERT_EQ(sings.size(), 4u);
  const Field original = field;
  FieldEditor editor(space);
  CancelEdit c;
  c.frame = 1;
  c.pair = {Vec3(-0.6, 0.02, 0), Vec3(0.6, 0.02, 0)};
  std::string message;
  try {
    editor.cancel(field, c);
  } catch (const EditRefused& e) {
    message = e.what();
  }
  EXPECT_NE(message.find("the region would swallow the"), std::string::npos) << message;
  EXPECT_TRUE(bitwise_equal(field, original));
  // The inner pair, with nothing between them, cancels.
  c.pair = {Vec3(-0.2, 0.02, 0), Vec3(0.2, 0.02, 0)};
  editor.cancel(field, c);
  EXPECT_EQ(find_singularities(space.bundle(), field, 1).size(), 2u);
}

}  // namespace
}  // namespace tvf

namespace tvf {
namespace {

// A saddle–sink creation on the unit sphere (icosphere, 2,562 vertices) at t = 0.4 and a
// storm (a centre) away from it, moved through the log map at the creation.
json sphere_move_scene() {
  return json::parse(R"({"tvf": 1,
    "domain": {"sphere": {"subdivisions": 4, "radius": 1}},
    "time": {"frames": 21, "range": [0, 1]},
    "falloff": 120,
    "elements": [
      {"kind": "bifurcation", "type": "saddle_sink_creation", "at": [0.6, 0, 0.8, 0.4],
       "scale": 0.3, "time_scale": 0.3, "angle": 0},
      {"kind": "singular", "type": "ccw_center", "path": [[-0.6, -0.6, 0.5292, 0]]}],
    "edits": [{"op": "move_bifurcation", "at": [0.6, 0, 0.8, 0.4], "to": [0, 0.6, 0.8, 0.49],
               "window": 0.25}]})");
}

TEST(FieldEditor, MovingABifurcationOnTheSphere) {
  const json j = sphere_move_scene();
  Design d(j);  // generate_unedited: the design before its edit
  const TangentBundle& bundle = d.space->bundle();
  const double cell = d.space->mesh().mean_edge_length();
  const Topology before = analyze_topology(bundle, d.field);
  const Vec3 from = Vec3(0.6, 0, 0.8), to = Vec3(0, 0.6, 0.8);
  auto nearest_creation = [&](const Topology& topo, const Vec3& x) {
    const Bifurcation* best = nullptr;
    for (const auto& b : topo.bifurcations)
      if (b.kind == BifurcationKind::creation &&
          (!best || (b.position - x).norm() < (best->position - x).norm()))
        best = &b;
    return best;
  };
  const Bifurcation* original = nearest_creation(before, from);
  ASSERT_TRUE(original);
  ASSERT_LT((original->position - from).norm(), 2 * cell);

  // Replay from the scene: twice the same bits, and the same as the editor by hand.
  const Field edited = generate(*d.space, d.scene);
  EXPECT_TRUE(bitwise_equal(edited, generate(*d.space, d.scene)));
  Field by_hand = d.field;
  apply_scene_edits(*d.space, d.scene, by_hand);
  EXPECT_TRUE(bitwise_equal(edited, by_hand));

  const Topology after = analyze_topology(bundle, edited);
  // The creation is at the new place and time (within two edge lengths and two frames),
  // and none is left at the old place.
  const Bifurcation* moved = nearest_creation(after, to);
  ASSERT_TRUE(moved);
  EXPECT_LT((moved->position - to).norm(), 2 * cell) << moved->position.transpose();
  EXPECT_NEAR(moved->t, 0.49, 2 * 0.05);
  for (const auto& b : after.bifurcations)
    EXPECT_GT((b.position - original->position).norm(), 3 * cell) << b.position.transpose() << " t = " << b.t;
  // Every other singularity (away from the old and the new place of the pair) stays within
  // one edge length of where it was, at every frame.
  for (int k = 0; k < d.field.frames(); ++k) {
    const auto& old_k = before.singularities[static_cast<size_t>(k)];
    const auto& new_k = after.singularities[static_cast<size_t>(k)];
    for (const auto& s : old_k) {
      if ((s.position - from).norm() < 0.6 || (s.position - to).norm() < 0.6) continue;
      const Singularity* n = nearest_to(new_k, s.position);
      ASSERT_TRUE(n) << "frame " << k;
      EXPECT_LE((n->position - s.position).norm(), cell) << "frame " << k << " " << to_string(s.type);
      EXPECT_EQ(n->index, s.index);
    }
  }
}

TEST(FieldEditor, MovingABifurcationOnTheSphereBeyondItsChartIsRefused) {
  json j = sphere_move_scene();
  j.erase("edits");
  Design d(j);
  FieldEditor editor(*d.space, edit_settings(d.scene));
  MoveBifurcationEdit m;
  m.at = {Vec3(0.6, 0, 0.8), 0.4};
  m.to = {Vec3(-0.6, 0, -0.8), 0.49};  // the antipode: beyond the chart's disc
  m.window = 0.25;
  Field field = d.field;
  std::string message;
  try {
    editor.move_bifurcation(field, m);
  } catch (const EditRefused& e) {
    message = e.what();
  }
  EXPECT_NE(message.find("beyond the disc"), std::string::npos) << message;
  EXPECT_TRUE(bitwise_equal(field, d.field));
}

}  // namespace
}  // namespace tvf

namespace tvf {
namespace {

// Issue 16: a creation at (0.5, 0, t ≈ 0.5) moved to (0.3, 0.3) at t = 0.6 with a window of
// 0.3 appeared 0.17 away from the target at 65² and 129² (and the edit was accepted); at
// 33² it was refused. At every resolution the moved creation is where it was asked, within
// the design check's tolerances (2.5 mean edge lengths, 2 frame steps), and none is left at
// the old place.
class LateMove : public testing::TestWithParam<int> {};

TEST_P(LateMove, LandsOnTheTarget) {
  json j = json::parse(R"({"tvf": 1,
    "domain": {"grid": {"size": [33, 33], "min": [-1, -1], "max": [1, 1]}},
    "time": {"frames": 41, "range": [0, 1]},
    "falloff": 30,
    "elements": [
      {"kind": "bifurcation", "type": "saddle_sink_creation", "at": [0.5, 0, 0.5],
       "scale": 0.3, "time_scale": 0.3, "angle": 0},
      {"kind": "singular", "type": "ccw_center", "path": [[-0.5, -0.6, 0]]}]})");
  j["domain"]["grid"]["size"] = {GetParam(), GetParam()};
  Design d(j);
  FieldEditor editor(*d.space, edit_settings(d.scene));
  MoveBifurcationEdit m;
  m.at = {Vec3(0.5, 0, 0), 0.5};
  m.to = {Vec3(0.3, 0.3, 0), 0.6};
  m.window = 0.3;
  Field edited = d.field;
  ASSERT_NO_THROW(editor.move_bifurcation(edited, m));
  const Topology after = analyze_topology(d.space->bundle(), edited);
  const double h = d.space->mesh().mean_edge_length(), dt = 1.0 / 40;
  const Bifurcation* best = nullptr;
  for (const auto& b : after.bifurcations)
    if (b.kind == BifurcationKind::creation &&
        (!best || (b.position - m.to.position).norm() < (best->position - m.to.position).norm()))
      best = &b;
  ASSERT_TRUE(best);
  EXPECT_LE((best->position - m.to.position).norm(), 2.5 * h) << best->position.transpose();
  EXPECT_LE(std::abs(best->t - m.to.t), 2 * dt) << best->t;
  for (const auto& b : after.bifurcations) EXPECT_GT((b.position - Vec3(0.5, 0, 0)).norm(), 2.5 * h);
}

INSTANTIATE_TEST_SUITE_P(FieldEditor, LateMove, testing::Values(33, 65, 129));

}  // namespace
}  // namespace tvf
