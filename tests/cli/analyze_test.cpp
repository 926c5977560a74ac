// `tvf analyze DIR_OR_SCENE -o FILE.json` as a user meets it (DESIGN §9, §11): the
// analysis JSON of a generated folder and of a scene, the designed bifurcations found, and
// bad input rejected with one sentence, a non-zero exit and no output left behind.
#include "support/test_paths.h"

#include <gtest/gtest.h>
#include <nlohmann/json.hpp>

#include <algorithm>
#include <cmath>
#include <filesystem>
#include <set>
#include <string>

namespace tvf {
namespace {

namespace fs = std::filesystem;
using test::count_lines;
using test::run_tvf;
using test::quoted;
using test::TempDir;

nlohmann::json read_json(const fs::path& p) { return nlohmann::json::parse(test::read_text(p)); }

std::set<std::string> keys(const nlohmann::json& j) {
  std::set<std::string> out;
  for (auto it = j.begin(); it != j.end(); ++it) out.insert(it.key());
  return out;
}

// One saddle–source cancellation (eq. 1) at (0.1, −0.05) and t = 0.5 on a small grid.
constexpr const char* kSmallScene = R"({"tvf": 1,
  "domain": {"grid": {"size": [33, 33], "min": [-1, -1], "max": [1, 1]}},
  "time": {"frames": 21, "range": [0, 1]},
  "falloff": 0.5,
  "elements": [{"kind": "bifurcation", "type": "saddle_source_cancellation", "at": [0.1, -0.05, 0.5],
                "scale": 0.4, "time_scale": 0.3, "angle": 0.5}]})";

TEST(CliAnalyze, GeneratedFolderHasTheDesignedBifurcations) {
  TempDir dir;
  const std::string scene = test::source_dir() + "/examples/01_bifurcation_templates/scene.json";
  const auto g = run_tvf("generate '" + scene + "' -o " + quoted(dir / "out") + " -q --no-vtk");
  ASSERT_EQ(g.exit_code, 0) << g.output;
  const auto r = run_tvf("analyze " + quoted(dir / "out") + " -o " + quoted(dir / "analysis.json"));
  ASSERT_EQ(r.exit_code, 0) << r.output;
  // The summary, the four pictures, the design check and its file.
  EXPECT_EQ(count_lines(r.output), 7) << r.output;
  EXPECT_NE(r.output.find("designed 0 singularities, 4 bifurcations: all found; no extras"), std::string::npos)
      << r.output;
  EXPECT_NE(r.output.find("4 bifurcations"), std::string::npos) << r.output;
  EXPECT_NE(r.output.find((dir / "analysis.json").string()), std::string::npos) << r.output;
  for (const char* picture : {"analysis_coherence.svg", "analysis_coherence.png", "analysis_paths.svg",
                              "analysis_paths.png"})
    EXPECT_TRUE(std::filesystem::exists(dir / picture)) << picture;

  const nlohmann::json j = read_json(dir / "analysis.json");
  // DESIGN §9's keys and §12's "periodic_orbits" (none here: the example has no focus).
  EXPECT_EQ(keys(j), (std::set<std::string>{"frames", "times", "singularities", "paths", "bifurcations", "coherence",
                                            "periodic_orbits"}));
  EXPECT_TRUE(j["periodic_orbits"].empty());
  EXPECT_EQ(j["frames"], 100);
  EXPECT_EQ(j["times"].size(), 100u);
  EXPECT_EQ(j["coherence"].size(), 99u);
  // The scene's four templates (place, time, kind), and nothing else.
  struct Designed {
    double x, y, t;
    const char* kind;
  };
  const Designed designed[] = {{-0.5, 0.5, 0.3, "creation"},
                               {0.5, -0.5, 0.6, "creation"},
                               {0.5, 0.5, 0.5, "cancellation"},
                               {-0.5, -0.5, 0.7, "cancellation"}};
  ASSERT_EQ(j["bifurcations"].size(), 4u);
  const double cell = 2.0 / 64 * std::sqrt(2.0);
  const double dt = 1.0 / 99;
  for (const auto& d : designed) {
    int found = 0;
    for (const auto& b : j["bifurcations"]) {
      const double dx = b["position"][0].get<double>() - d.x;
      const double dy = b["position"][1].get<double>() - d.y;
      if (b["kind"] == d.kind && std::hypot(dx, dy) <= cell && std::abs(b["t"].get<double>() - d.t) <= dt) ++found;
    }
    EXPECT_EQ(found, 1) << d.kind << " at (" << d.x << ", " << d.y << ", " << d.t << ")";
  }
  // The design check beside it (the folder's scene.json) found the four, and nothing else.
  const nlohmann::json d = read_json(dir / "analysis_design.json");
  EXPECT_EQ(keys(d), (std::set<std::string>{"all_found", "summary", "tolerance", "designed", "implied_bifurcations",
                                            "extra"}));
  EXPECT_TRUE(d["all_found"].get<bool>());
  ASSERT_EQ(d["designed"].size(), 4u);
  for (const auto& f : d["designed"]) {
    EXPECT_EQ(f["kind"], "bifurcation");
    EXPECT_TRUE(f["found"].get<bool>());
    EXPECT_EQ(j["bifurcations"][f["bifurcation"].get<size_t>()]["kind"],
              f["type"].get<std::string>().find("creation") != std::string::npos ? "creation" : "cancellation");
  }
  EXPECT_TRUE(d["extra"]["paths"].empty());
  // Each bifurcation joins a saddle and a node.
  for (const auto& b : j["bifurcations"]) {
    std::set<std::string> types;
    for (const auto& id : b["paths"]) types.insert(j["paths"][id.get<size_t>()]["type"].get<std::string>());
    EXPECT_EQ(types.count("saddle"), 1u) << b.dump();
  }
}

TEST(CliAnalyze, SceneFileIsGeneratedThenAnalysedLikeItsFolder) {
  TempDir dir;
  test::write_text(dir / "scene.json", kSmallScene);
  const auto r = run_tvf("analyze " + quoted(dir / "scene.json") + " -o " + quoted(dir / "from_scene.json") + " --quiet");
  ASSERT_EQ(r.exit_code, 0) << r.output;
  EXPECT_EQ(r.output, "");
  const nlohmann::json a = read_json(dir / "from_scene.json");
  ASSERT_EQ(a["bifurcations"].size(), 1u);
  EXPECT_EQ(a["bifurcations"][0]["kind"], "cancellation");
  EXPECT_NEAR(a["bifurcations"][0]["t"].get<double>(), 0.5, 0.05);
  ASSERT_EQ(a["paths"].size(), 2u);
  for (const auto& p : a["paths"]) {
    EXPECT_EQ(p["birth"], 0.0);
    for (const auto& pt : p["points"]) EXPECT_EQ(pt.size(), 4u);
  }

  // The generated folder (and its field.tvff) reload the same field: the same analysis.
  const auto g = run_tvf("generate " + quoted(dir / "scene.json") + " -o " + quoted(dir / "out") + " -q --no-vtk");
  ASSERT_EQ(g.exit_code, 0) << g.output;
  const auto f = run_tvf("analyze " + quoted(dir / "out") + " -o " + quoted(dir / "from_folder.json") + " -q");
  ASSERT_EQ(f.exit_code, 0) << f.output;
  EXPECT_EQ(read_json(dir / "from_folder.json"), a);
  const auto t = run_tvf("analyze " + quoted(dir / "out" / "field.tvff") + " -o " + quoted(dir / "from_file.json") + " -q");
  ASSERT_EQ(t.exit_code, 0) << t.output;
  EXPECT_EQ(read_json(dir / "from_file.json"), a);
  // The design checks agree too: the scene itself, the folder's scene.json, the one beside
  // the field file, and (with no scene.json) the copy inside field.tvff.
  const nlohmann::json design = read_json(dir / "from_scene_design.json");
  EXPECT_TRUE(design["all_found"].get<bool>()) << design.dump();
  EXPECT_EQ(read_json(dir / "from_folder_design.json"), design);
  EXPECT_EQ(read_json(dir / "from_file_design.json"), design);
  fs::remove(dir / "out" / "scene.json");
  const auto e = run_tvf("analyze " + quoted(dir / "out") + " -o " + quoted(dir / "embedded.json") + " -q");
  ASSERT_EQ(e.exit_code, 0) << e.output;
  EXPECT_EQ(read_json(dir / "embedded_design.json"), design);
  // A broken scene.json beside the field is bad input: one sentence naming it, no output.
  test::write_text(dir / "out" / "scene.json", R"({"tvf": 1, "falloff": "wide"})");
  const auto b = run_tvf("analyze " + quoted(dir / "out") + " -o " + quoted(dir / "broken.json"));
  EXPECT_NE(b.exit_code, 0);
  EXPECT_EQ(count_lines(b.output), 1) << b.output;
  EXPECT_NE(b.output.find("scene.json"), std::string::npos) << b.output;
  EXPECT_FALSE(fs::exists(dir / "broken.json"));
  EXPECT_FALSE(fs::exists(dir / "broken_design.json"));
}

TEST(CliAnalyze, HopfScenesCyclesAndEventsAreInTheJsonAndTheDesignCheck) {
  // Example 23's two templates on a coarser grid and fewer frames: the cycles of every frame
  // in "periodic_orbits", both Hopf events appended to "bifurcations", both found by the
  // design check.
  TempDir dir;
  auto scene = nlohmann::json::parse(test::read_text(test::source_dir() + "/examples/23_hopf_bifurcation/scene.json"));
  scene["domain"]["grid"]["size"] = {33, 33};
  scene["time"]["frames"] = 41;
  test::write_text(dir / "scene.json", scene.dump());
  const auto r = run_tvf("analyze " + quoted(dir / "scene.json") + " -o " + quoted(dir / "analysis.json"));
  ASSERT_EQ(r.exit_code, 0) << r.output;
  EXPECT_NE(r.output.find("2 Hopf events"), std::string::npos) << r.output;
  const nlohmann::json j = read_json(dir / "analysis.json");
  ASSERT_FALSE(j["periodic_orbits"].empty());
  std::set<std::string> stabilities;
  for (const auto& o : j["periodic_orbits"]) {
    stabilities.insert(o["stability"].get<std::string>());
    EXPECT_EQ(o["center"].size(), 3u);
    EXPECT_GE(o["points"].size(), 8u);
    EXPECT_GT(o["radius"].get<double>(), 0.0);
  }
  EXPECT_EQ(stabilities, (std::set<std::string>{"attracting", "repelling"}));
  std::vector<nlohmann::json> hopf;
  for (const auto& b : j["bifurcations"])
    if (b["kind"] == "hopf") hopf.push_back(b);
  ASSERT_EQ(hopf.size(), 2u) << j["bifurcations"].dump();
  EXPECT_NEAR(hopf[0]["t"].get<double>(), 0.35, 0.05);
  EXPECT_EQ(hopf[0]["criticality"], "supercritical");
  EXPECT_NEAR(hopf[0]["position"][0].get<double>(), -0.5, 0.07);
  EXPECT_NEAR(hopf[1]["t"].get<double>(), 0.65, 0.05);
  EXPECT_EQ(hopf[1]["criticality"], "subcritical");
  EXPECT_NEAR(hopf[1]["position"][0].get<double>(), 0.5, 0.07);
  const nlohmann::json d = read_json(dir / "analysis_design.json");
  EXPECT_TRUE(d["all_found"].get<bool>()) << d["summary"];
  EXPECT_TRUE(fs::exists(dir / "analysis_paths.png"));
}

TEST(CliAnalyze, BadInputIsOneSentenceNonZeroExitAndNoOutput) {
  TempDir dir;
  fs::create_directories(dir / "corrupt");
  test::write_text(dir / "corrupt" / "field.tvff", "TVFFIELD but not really a field file");
  fs::create_directories(dir / "empty");
  test::write_text(dir / "bad_scene.json", R"({"tvf": 1, "domain": {"grid": {"size": [5, 5]}}, "bogus": 3})");
  struct Case {
    const char* name;
    fs::path input;
    const char* expected;  // substring of the one-line error
  };
  const Case cases[] = {
      {"missing folder", dir / "nowhere", "nowhere"},
      {"corrupt field file", dir / "corrupt", "field.tvff"},
      {"folder without a field", dir / "empty", "field.tvff"},
      {"bad scene", dir / "bad_scene.json", "bogus"},
  };
  for (const auto& c : cases) {
    SCOPED_TRACE(c.name);
    const fs::path out = dir / "analysis.json";
    const auto r = run_tvf("analyze " + quoted(c.input) + " -o " + quoted(out));
    EXPECT_NE(r.exit_code, 0);
    EXPECT_EQ(count_lines(r.output), 1) << r.output;
    EXPECT_NE(r.output.find(c.expected), std::string::npos) << r.output;
    EXPECT_FALSE(fs::exists(out)) << "output left behind";
  }
  // An output that cannot be written names itself, and is refused before the work: a file
  // where its folder would be, a folder given as the file.
  test::write_text(dir / "scene.json", kSmallScene);
  for (const auto& [out, expected] :
       {std::pair{dir / "scene.json" / "a.json", std::string("scene.json is not a folder")},
        std::pair{dir / "empty", (dir / "empty").string() + ": is a folder; give the name of the file"}}) {
    const auto r = run_tvf("analyze " + quoted(dir / "scene.json") + " -o " + quoted(out));
    EXPECT_NE(r.exit_code, 0);
    EXPECT_EQ(count_lines(r.output), 1) << r.output;
    EXPECT_NE(r.output.find(expected), std::string::npos) << r.output;
  }
  // A folder that does not exist yet is made, as `tvf generate` makes its output folder.
  const auto made = run_tvf("analyze " + quoted(dir / "scene.json") + " -q -o " + quoted(dir / "new" / "a.json"));
  ASSERT_EQ(made.exit_code, 0) << made.output;
  EXPECT_TRUE(fs::exists(dir / "new" / "a.json"));
  EXPECT_TRUE(fs::exists(dir / "new" / "a_paths.png"));
  fs::remove_all(dir / "new");
  // Nothing but the inputs in the folder: no temporary files.
  for (const auto& e : fs::directory_iterator(dir.path()))
    EXPECT_NE(e.path().filename().string()[0], '.') << e.path();
}

}  // namespace
}  // namespace tvf
