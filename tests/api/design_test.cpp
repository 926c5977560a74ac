// The library facade (api/design.h): the same field as the pipeline by hand, kept until the
// scene changes, edits appended as `tvf edit` appends them, undo/redo, refusals and
// cancellation that change nothing, and a generated folder read back.
#include "tvf/api/design.h"

#include "tvf/scene/scene_json.h"

#include "support/test_paths.h"

#include <gtest/gtest.h>

#include <atomic>
#include <cstring>
#include <string>
#include <vector>

namespace tvf {
namespace {

using json = nlohmann::json;

// 17×17 grid, 5 frames: a source drifting right and a centre (basis fields: exact,
// deterministic sums).
json small_scene(const std::string& generator = "basis") {
  return json::parse(R"({"tvf": 1,
    "domain": {"grid": {"size": [17, 17], "min": [-1, -1], "max": [1, 1]}},
    "time": {"frames": 5, "range": [0, 1]},
    "generator": ")" + generator + R"(",
    "elements": [
      {"kind": "singular", "type": "source", "path": [[-0.4, -0.3, 0], [-0.2, -0.3, 1]]},
      {"kind": "singular", "type": "ccw_center", "path": [[0.4, 0.4, 0]]}]})");
}

Scene scene_of(const json& j) { return scene_from_json(j, "test.json", "test.json"); }

bool bitwise_equal(const Field& a, const Field& b) {
  return a.data().size() == b.data().size() &&
         std::memcmp(a.data().data(), b.data().data(), a.data().size() * sizeof(cplx)) == 0;
}

TEST(Design, GeneratesWhatThePipelineGenerates) {
  const Scene scene = scene_of(small_scene());
  const auto space = make_design_space(scene);
  const Field by_hand = generate(*space, scene);
  Design design(scene);
  EXPECT_FALSE(design.has_field());
  EXPECT_TRUE(bitwise_equal(design.generate(), by_hand));
  EXPECT_TRUE(bitwise_equal(generate_scene(scene).field, by_hand));
  EXPECT_EQ(design.report().frames, 5);
  EXPECT_EQ(design.report().vertices, 17 * 17);
  // The analysis is the one of the field, periodic orbits included (DESIGN §12).
  const Topology topology = analyze_topology(space->bundle(), by_hand);
  nlohmann::json expected = topology_to_json(topology);
  add_periodic_orbits_to_json(expected, find_periodic_orbits(space->bundle(), by_hand, topology));
  EXPECT_EQ(design.analysis_json(), expected);
  EXPECT_EQ(analysis_json_of(*space, by_hand), expected);
}

TEST(Design, LivesOnAMeshGivenInCodeWhileTheSceneKeepsItsDomain) {
  const Scene grid_scene = scene_of(small_scene());
  const auto grid = make_design_space(grid_scene);
  // The grid's own vertices and faces, given as a mesh made in code.
  Design design(grid_scene, Mesh(grid->mesh().positions(), grid->mesh().faces(), "arrays"));
  EXPECT_EQ(design.scene().domain.mesh, "arrays");
  EXPECT_FALSE(design.scene().domain.grid.has_value());
  const DesignSpace* given = &design.space();
  EXPECT_TRUE(given->planar());
  // The same vertices and faces: the same field, bit for bit.
  EXPECT_TRUE(bitwise_equal(design.generate(), generate(*grid, grid_scene)));
  // A change that keeps the domain keeps the mesh; so does undo after a change of domain.
  nlohmann::json moved = scene_to_json(design.scene());
  moved["elements"][1]["path"] = json::parse("[[0.2, 0.5, 0, 0]]");
  design.set_scene(moved);
  EXPECT_EQ(&design.space(), given);
  nlohmann::json other = small_scene();
  other["domain"]["grid"]["size"] = json::parse("[9, 9]");
  design.set_scene(other);
  EXPECT_EQ(design.space().mesh().num_vertices(), 81);
  design.undo();
  EXPECT_EQ(&design.space(), given);
  // A mesh that would not fit in memory is refused before anything is built.
  Scene huge = grid_scene;
  huge.time.frames = 100000000;
  EXPECT_THROW(Design(huge, Mesh(grid->mesh().positions(), grid->mesh().faces(), "arrays")), Error);
}

TEST(Design, KeepsTheFieldUntilTheSceneChangesAndUndoBringsItBack) {
  Design design(scene_of(small_scene()));
  const Field* first = &design.generate();
  const Field copy = *first;
  EXPECT_EQ(&design.generate(), first);  // not made again
  const DesignSpace* domain = &design.space();

  json moved = small_scene();
  moved["elements"][1]["path"][0] = {0.2, 0.4, 0};
  design.set_scene(scene_of(moved));
  EXPECT_FALSE(design.has_field());
  EXPECT_EQ(&design.space(), domain);  // same grid: the domain is kept
  EXPECT_FALSE(bitwise_equal(design.generate(), copy));
  EXPECT_TRUE(design.can_undo());

  design.undo();
  EXPECT_TRUE(design.has_field());  // the field of the scene before was kept
  EXPECT_TRUE(bitwise_equal(design.field(), copy));
  EXPECT_EQ(scene_to_json(design.scene()), scene_to_json(scene_of(small_scene())));
  design.redo();
  EXPECT_EQ(scene_to_json(design.scene())["elements"][1]["path"][0], json({0.2, 0.4, 0.0}));

  json finer = small_scene();
  finer["domain"]["grid"]["size"] = {9, 9};
  design.set_scene(scene_of(finer));
  EXPECT_EQ(design.space().mesh().num_vertices(), 81);  // a new domain
  EXPECT_FALSE(design.can_redo());
  EXPECT_EQ(test::error_of([&] { design.redo(); }), "test.json: nothing to redo");
}

TEST(Design, EditIsAppendedToTheSceneAndReplaysFromIt) {
  Design design(scene_of(small_scene("constrained")));
  const Field before = design.generate();
  const EditReport report = design.edit(json{{"op", "smooth"}, {"strength", 0.5}});
  EXPECT_FALSE(report.summary.empty());
  ASSERT_EQ(design.scene().edits.size(), 1u);
  EXPECT_EQ(std::get<SmoothEdit>(design.scene().edits[0]).strength, 0.5);
  EXPECT_TRUE(design.has_field());
  EXPECT_FALSE(bitwise_equal(design.field(), before));
  // The edited field is the one the edited scene makes (edits replay bit for bit).
  const Field replayed = generate_scene(design.scene()).field;
  EXPECT_TRUE(bitwise_equal(design.field(), replayed));
  design.undo();
  EXPECT_TRUE(design.scene().edits.empty());
  EXPECT_TRUE(bitwise_equal(design.field(), before));
}

TEST(Design, RefusedAndInvalidEditsChangeNothing) {
  Design design(scene_of(small_scene("constrained")));
  const Field before = design.generate();
  // No saddle anywhere: there is no pair to cancel.
  const std::string refused = test::error_of([&] {
    design.edit(json::parse(R"({"op": "cancel", "frame": 2, "pair": [[-0.3, -0.3], [0.4, 0.4]]})"));
  });
  EXPECT_NE(refused.find("test.json: refused to cancel"), std::string::npos) << refused;
  EXPECT_NE(refused.find("the scene is unchanged"), std::string::npos) << refused;
  EXPECT_EQ(test::error_of([&] { design.edit(json{{"op", "smooth"}, {"strength", 7}}); }).rfind("test.json: edits[0]", 0),
            0u);
  EXPECT_TRUE(design.scene().edits.empty());
  EXPECT_FALSE(design.can_undo());
  EXPECT_TRUE(bitwise_equal(design.field(), before));
}

TEST(Design, ASceneWhoseSurfaceSketchMeetsItselfIsRefusedOnTheDomainItHas) {
  // set_scene(json) validates as the reader does and, on the domain the Design has built,
  // tests a surface sketch as generate() would: refused there, the Design unchanged.
  Design design(scene_of(json::parse(R"({"tvf": 1, "domain": {"sphere": {"subdivisions": 3}}, "time": {"frames": 5},
    "generator": "constrained", "elements": [{"kind": "singular", "type": "ccw_center", "path": [[0, 0, 1, 0]]}]})")));
  design.generate();
  const long long revision = design.revision();
  json next = scene_to_json(design.scene());
  // (0°, 0°) → (40°, 30°) → (40°, 0°) → (0°, 30°) in longitude and latitude: an X.
  next["elements"].push_back(json::parse(R"({"kind": "streakline", "t": 0.8, "from": 0.2,
    "points": [[1, 0, 0], [0.663414, 0.556670, 0.5], [0.766044, 0.642788, 0], [0.866025, 0, 0.5]]})"));
  const std::string refused = test::error_of([&] { design.set_scene(next, "edited.json"); });
  EXPECT_EQ(refused.rfind("edited.json: elements[1].points: the sketch crosses or folds back onto itself on the surface", 0),
            0u)
      << refused;
  EXPECT_EQ(design.revision(), revision);
  EXPECT_TRUE(design.has_field());
}

TEST(Design, CancelledGenerationLeavesTheDesignAsItWas) {
  Design design(scene_of(small_scene("spacetime")));
  std::atomic<bool> stop{true};
  GenerateOptions options;
  options.cancel = &stop;
  EXPECT_THROW(design.generate(options), GenerationCancelled);
  EXPECT_FALSE(design.has_field());
  EXPECT_EQ(design.generate().frames(), 5);
}

// The steps a caller with threads takes (tvf serve's session): a Solve and an EditJob
// prepared at one revision, run apart from the Design, adopted only while the Design is
// still at that revision; before_change sees every change first and can refuse it.
TEST(Design, SolvesAndEditsRunApartAndAreAdoptedOnlyAtTheirRevision) {
  std::vector<std::string> seen;  // the edits of each scene about to become current
  bool refuse = false;
  DesignOptions options;
  options.before_change = [&](const Scene& next) {
    if (refuse) throw Error("cannot save");
    seen.push_back(std::to_string(next.edits.size()));
  };
  Design design(scene_of(small_scene("constrained")), options);
  EXPECT_EQ(design.revision(), 1);
  EXPECT_EQ(design.result(), nullptr);

  // A Solve: the same field as generate(), with its analysis, adopted at revision 1. Its
  // domain is new: it says so before the frames (GenerateOptions::stage).
  Design::Solve solve = design.prepare_solve();
  EXPECT_EQ(solve.revision(), 1);
  std::vector<std::string> stages;
  GenerateOptions go;
  go.stage = [&](const std::string& what) { stages.push_back(what); };
  solve.run(go, true);
  EXPECT_EQ(stages, std::vector<std::string>{"building the domain"});
  const auto made = solve.result();
  ASSERT_NE(made, nullptr);
  ASSERT_TRUE(made->topology.has_value());
  ASSERT_TRUE(made->orbits.has_value());
  EXPECT_TRUE(bitwise_equal(made->field, generate_scene(design.scene()).field));
  EXPECT_TRUE(design.adopt(std::move(solve)));
  EXPECT_EQ(design.result(), made);
  EXPECT_EQ(&design.field(), &made->field);  // not made again
  EXPECT_EQ(design.revision(), 1);

  // A Solve overtaken by a change is not adopted; the result it made stays readable.
  Design::Solve stale = design.prepare_solve();
  json moved = small_scene("constrained");
  moved["elements"][1]["path"][0] = {0.2, 0.4, 0};
  design.set_scene(scene_of(moved));
  EXPECT_EQ(design.revision(), 2);
  stale.run();
  EXPECT_FALSE(design.adopt(std::move(stale)));
  EXPECT_EQ(design.result(), nullptr);
  EXPECT_EQ(design.last_result(), made);
  design.undo();
  EXPECT_EQ(design.revision(), 3);

  // An EditJob: the edit's scene at once, its field applied to the result it is given,
  // committed (history, one revision more) only at its revision.
  Design::EditJob edit = design.prepare_edit(json{{"op", "smooth"}, {"strength", 0.5}});
  EXPECT_EQ(edit.scene().edits.size(), 1u);
  EXPECT_EQ(edit.revision(), 3);
  const EditReport report = edit.run(made, true);
  EXPECT_FALSE(report.summary.empty());
  ASSERT_TRUE(edit.result()->topology.has_value());
  EXPECT_TRUE(bitwise_equal(edit.result()->field, generate_scene(edit.scene()).field));
  Design::EditJob copy = edit;
  EXPECT_TRUE(design.adopt(std::move(edit)));
  EXPECT_EQ(design.revision(), 4);
  EXPECT_EQ(design.scene().edits.size(), 1u);
  EXPECT_TRUE(design.can_undo());
  EXPECT_FALSE(design.adopt(std::move(copy)));  // made on revision 3
  EXPECT_EQ(design.revision(), 4);

  // A change before_change refuses is not made.
  refuse = true;
  EXPECT_EQ(test::error_of([&] { design.undo(); }), "cannot save");
  EXPECT_EQ(test::error_of([&] { design.set_scene(scene_of(small_scene())); }), "cannot save");
  EXPECT_EQ(design.revision(), 4);
  EXPECT_EQ(design.scene().edits.size(), 1u);
  // Seen: the new scene (no edits), the undo (none), the adopted edit (one).
  EXPECT_EQ(seen, (std::vector<std::string>{"0", "0", "1"}));

  // Invalid edits are refused when prepared, naming the entry.
  EXPECT_EQ(test::error_of([&] { design.prepare_edit(json{{"op", "smooth"}, {"strength", 7}}, "s.json"); })
                .rfind("s.json: edits[1]", 0),
            0u);
}

TEST(Design, OpensAGeneratedFolderWithoutRegenerating) {
  test::TempDir dir;
  Scene scene = scene_of(small_scene());
  Design design(scene);
  design.write_outputs(dir.path(), {});
  Design read = Design::open(dir.path().string());
  ASSERT_TRUE(read.has_field());
  EXPECT_TRUE(bitwise_equal(read.field(), design.field()));  // field.tvff keeps doubles
  EXPECT_EQ(scene_to_json(read.scene()), scene_to_json(scene));
  EXPECT_EQ(read.analysis_json(), design.analysis_json());
  ASSERT_TRUE(read.check().has_value());
  EXPECT_NE(test::error_of([&] { Design::open((dir / "missing").string()); }).find("no such file or folder"),
            std::string::npos);
}

}  // namespace
}  // namespace tvf
