// `tvf edit SCENE --cancel … | --remove-bifurcation … | --move-bifurcation … | --smooth S |
// --undo` as a user meets it: the edit is checked on the generated field, appended to the
// scene's edits (or the last one dropped), and a refused edit leaves the file unchanged.
#include "support/test_paths.h"

#include <gtest/gtest.h>
#include <nlohmann/json.hpp>

#include <string>

namespace tvf {
namespace {

using test::run_tvf;
using test::TempDir;

// A flow to the right with a saddle and a source downstream of it, and a centre.
constexpr const char* kScene = R"({"tvf": 1,
  "domain": {"grid": {"size": [33, 33], "min": [-1, -1], "max": [1, 1]}},
  "time": {"frames": 21, "range": [0, 1]},
  "generator": "constrained", "solver": {"region_radius": 0.15},
  "falloff": 20,
  "elements": [
    {"kind": "regular", "pathline": [[-0.9, -0.3, 0], [-0.8, -0.3, 1]]},
    {"kind": "singular", "jacobian": [[-1, 0], [0, 1]], "path": [[-0.3, -0.3, 0], [-0.25, -0.3, 1]]},
    {"kind": "singular", "type": "source", "path": [[0.2, -0.3, 0]]},
    {"kind": "singular", "type": "ccw_center", "path": [[0.1, 0.6, 0]]}]})";

// Shell-quoted path (built by insert: GCC 12 warns falsely on "'" + s + "'").
std::string q(const std::filesystem::path& p) { return test::quoted(p); }

TEST(CliEdit, AppendsCheckedEditsAndUndoes) {
  TempDir dir;
  const auto scene = dir / "scene.json";
  test::write_text(scene, kScene);
  auto r = run_tvf("edit " + q(scene) + " --cancel 10 0.2 -0.3 -0.27 -0.3");
  ASSERT_EQ(r.exit_code, 0) << r.output;
  EXPECT_NE(r.output.find("cancelled the source"), std::string::npos) << r.output;
  EXPECT_NE(r.output.find("appended as edits[0]"), std::string::npos) << r.output;
  auto j = nlohmann::json::parse(test::read_text(scene));
  ASSERT_EQ(j["edits"].size(), 1u);
  EXPECT_EQ(j["edits"][0]["op"], "cancel");
  EXPECT_EQ(j["edits"][0]["frame"], 10);

  r = run_tvf("edit " + q(scene) + " --smooth 0.25 -q");
  ASSERT_EQ(r.exit_code, 0) << r.output;
  EXPECT_EQ(r.output, "");
  j = nlohmann::json::parse(test::read_text(scene));
  ASSERT_EQ(j["edits"].size(), 2u);
  EXPECT_EQ(j["edits"][1]["strength"], 0.25);

  // The edited scene generates (its edits replayed) and reports them.
  r = run_tvf("generate " + q(scene) + " -o " + q(dir / "out") + " --no-vtk");
  ASSERT_EQ(r.exit_code, 0) << r.output;
  EXPECT_NE(r.output.find("edit: cancelled"), std::string::npos) << r.output;
  EXPECT_NE(r.output.find("edit: smoothed"), std::string::npos) << r.output;

  r = run_tvf("edit " + q(scene) + " --undo");
  ASSERT_EQ(r.exit_code, 0) << r.output;
  j = nlohmann::json::parse(test::read_text(scene));
  ASSERT_EQ(j["edits"].size(), 1u);
  EXPECT_EQ(j["edits"][0]["op"], "cancel");
}

TEST(CliEdit, RefusalsLeaveTheSceneUnchanged) {
  TempDir dir;
  const auto scene = dir / "scene.json";
  test::write_text(scene, kScene);
  struct Case {
    std::string args;
    std::string says;
  };
  const Case cases[] = {
      {"--cancel 10 0.2 -0.3 0.1 0.6", "both have index +1"},         // source and centre
      {"--cancel 30 0.2 -0.3 -0.27 -0.3", "FRAME must be an integer in [0, 20]"},
      {"--cancel 10 0.2 -0.3", "--cancel"},                            // too few numbers
      {"--remove-bifurcation 0.5 0 0", "no bifurcation"},
      {"--move-bifurcation 0.4 0 0 0.5 0.3 0.3 0.1", "--move-bifurcation needs T X Y T2 X Y (6 numbers)"},
      {"--smooth 2", "edits[0].strength: must be in (0, 1]"},
      {"--undo", "no edits to undo"},
      {"", "say which edit"},
      // Issue 16: a bad window is not replaced by the default, nor dropped with --smooth.
      {"--cancel 10 0.2 -0.3 -0.27 -0.3 --window -0.5", "--window -0.5: must be in [0, 1]"},
      {"--smooth 0.3 --window 0.2", "--window applies to --cancel"},
      // Issue 16: a position far from every singularity names none of them.
      {"--cancel 10 0.9 0.9 -0.9 0.9", "no singularity within"},
      // Issue 16: positions outside the domain are refused before anything is solved.
      {"--cancel 10 0.2 -0.3 -0.27 -1.5", "outside the domain"},
  };
  for (const Case& c : cases) {
    const auto r = run_tvf("edit " + q(scene) + " " + c.args);
    EXPECT_NE(r.exit_code, 0) << c.args;
    EXPECT_NE(r.output.find(c.says), std::string::npos) << c.args << ": " << r.output;
    EXPECT_EQ(test::read_text(scene), kScene) << c.args;
  }
  // A refused edit says so in one sentence that names the file.
  const auto r = run_tvf("edit " + q(scene) + " --cancel 10 0.2 -0.3 0.1 0.6");
  EXPECT_EQ(test::count_lines(r.output), 1) << r.output;
  EXPECT_NE(r.output.find(scene.string() + ": refused to cancel"), std::string::npos) << r.output;
  EXPECT_NE(r.output.find("the scene is unchanged"), std::string::npos) << r.output;
}

// On a surface --move-bifurcation takes T X Y Z T2 X2 Y2 Z2 and moves the creation through
// the log map (tests/edit/field_editor_test.cpp checks where it ends up).
TEST(CliEdit, MovesABifurcationOnASphere) {
  TempDir dir;
  const auto scene = dir / "sphere.json";
  const std::string text = R"({"tvf": 1, "domain": {"sphere": {"subdivisions": 4, "radius": 1}},
    "time": {"frames": 21, "range": [0, 1]}, "falloff": 120,
    "elements": [{"kind": "bifurcation", "type": "saddle_sink_creation", "at": [0.6, 0, 0.8, 0.4],
                  "scale": 0.3, "time_scale": 0.3, "angle": 0},
                 {"kind": "singular", "type": "ccw_center", "path": [[-0.6, -0.6, 0.5292, 0]]}]})";
  test::write_text(scene, text);
  auto r = run_tvf("edit " + q(scene) + " --move-bifurcation 0.4 0.6 0 0.8 0.49 0 0.6");
  EXPECT_NE(r.exit_code, 0);
  EXPECT_NE(r.output.find("T X Y Z T2 X Y Z (8 numbers) on this surface domain"), std::string::npos) << r.output;
  EXPECT_EQ(test::read_text(scene), text);
  r = run_tvf("edit " + q(scene) + " --move-bifurcation 0.4 0.6 0 0.8 0.49 0 0.6 0.8 --window 0.25");
  ASSERT_EQ(r.exit_code, 0) << r.output;
  EXPECT_NE(r.output.find("moved the creation bifurcation"), std::string::npos) << r.output;
  const auto j = nlohmann::json::parse(test::read_text(scene));
  ASSERT_EQ(j["edits"].size(), 1u);
  EXPECT_EQ(j["edits"][0]["op"], "move_bifurcation");
  EXPECT_EQ(j["edits"][0]["to"], nlohmann::json::parse("[0, 0.6, 0.8, 0.49]"));
}

}  // namespace
}  // namespace tvf

namespace tvf {
namespace {

// Issue 16 on example 01 (four bifurcation templates): a move out of the domain ended in an
// internal error (and `tvf validate` called the scene valid), and a removal named by a point
// far from every bifurcation removed one anyway. Both are refused in one sentence.
TEST(CliEdit, EditsThatNameNothingOrLeaveTheDomainAreRefused) {
  TempDir dir;
  const auto scene = dir / "scene.json";
  const std::string text = test::read_text(test::source_dir() + "/examples/01_bifurcation_templates/scene.json");
  test::write_text(scene, text);
  struct Case {
    std::string args, says;
  };
  const Case cases[] = {
      {"--move-bifurcation 0.3 -0.5 0.5 0.35 1.5 0.5", "edits[0].to: (1.5, 0.5) is outside the domain"},
      {"--remove-bifurcation 0.01 0.95 0.95", "no bifurcation within"},
      {"--move-bifurcation 0.9 0.95 0.95 0.35 0.2 0.2", "no bifurcation within"},
  };
  for (const Case& c : cases) {
    const auto r = run_tvf("edit " + q(scene) + " " + c.args);
    EXPECT_NE(r.exit_code, 0) << c.args;
    EXPECT_EQ(r.output.find("internal error"), std::string::npos) << c.args << ": " << r.output;
    EXPECT_EQ(test::count_lines(r.output), 1) << c.args << ": " << r.output;
    EXPECT_NE(r.output.find(c.says), std::string::npos) << c.args << ": " << r.output;
    EXPECT_EQ(test::read_text(scene), text) << c.args;
  }
  // A scene file holding such an edit is not valid.
  auto j = nlohmann::json::parse(text);
  j["edits"] = nlohmann::json::parse(R"([{"op": "move_bifurcation", "at": [-0.5, 0.5, 0.3], "to": [0.35, 1.5, 0.5]}])");
  test::write_text(dir / "bad.json", j.dump());
  for (const char* command : {"validate ", "generate "}) {
    const auto r = run_tvf(std::string(command) + q(dir / "bad.json") + (command[0] == 'g' ? " -o " + q(dir / "out") : ""));
    EXPECT_NE(r.exit_code, 0) << command << r.output;
    EXPECT_NE(r.output.find("edits[0].to: (0.35, 1.5) is outside the domain"), std::string::npos) << r.output;
    EXPECT_EQ(r.output.find("internal error"), std::string::npos) << r.output;
  }
}

}  // namespace
}  // namespace tvf
