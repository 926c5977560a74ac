// The typed edits of a scene (edits.h): read from the canonical JSON the scene parser keeps,
// written back identically, and checked for scenes built in code.
#include "tvf/scene/scene_json.h"
#include "tvf/scene/edits.h"

#include "support/test_paths.h"

#include <gtest/gtest.h>

namespace tvf {
namespace {

using json = nlohmann::json;

json bifurcation_scene() {
  return json::parse(R"({"tvf": 1,
    "domain": {"grid": {"size": [33, 33], "min": [-1, -1], "max": [1, 1]}},
    "time": {"frames": 21, "range": [0, 1]},
    "elements": [{"kind": "bifurcation", "type": "saddle_sink_creation", "at": [0, 0.1, 0.4]}]})");
}

TEST(Edits, TypedEntriesFromTheScene) {
  json j = bifurcation_scene();
  j["edits"] = json::parse(R"([{"op": "cancel", "frame": 3, "pair": [[0, 0], [0.1, 0]], "window": 0.2},
                               {"op": "remove_bifurcation", "at": [0, 0.1, 0.4]},
                               {"op": "move_bifurcation", "at": [0, 0.1, 0.4], "to": [0.5, 0.5, 0.6]},
                               {"op": "smooth", "strength": 0.25}])");
  const Scene scene = scene_from_json(j, "test.json", "test.json");
  const std::vector<Edit>& edits = scene.edits;
  ASSERT_EQ(edits.size(), 4u);
  const auto& c = std::get<CancelEdit>(edits[0]);
  EXPECT_EQ(c.frame, 3);
  EXPECT_EQ(c.pair[1], Vec3(0.1, 0, 0));
  EXPECT_EQ(c.window, 0.2);
  EXPECT_EQ(std::get<RemoveBifurcationEdit>(edits[1]).window, kDefaultEditWindow);
  EXPECT_EQ(std::get<MoveBifurcationEdit>(edits[2]).to.t, 0.6);
  EXPECT_EQ(std::get<SmoothEdit>(edits[3]).strength, 0.25);
  // Written back as the canonical entries (every default written, 2-D positions).
  const json canonical = json::parse(R"([{"op": "cancel", "frame": 3, "pair": [[0.0, 0.0], [0.1, 0.0]], "window": 0.2},
                                         {"op": "remove_bifurcation", "at": [0.0, 0.1, 0.4], "window": 0.1},
                                         {"op": "move_bifurcation", "at": [0.0, 0.1, 0.4], "to": [0.5, 0.5, 0.6],
                                          "window": 0.1},
                                         {"op": "smooth", "strength": 0.25}])");
  for (size_t i = 0; i < edits.size(); ++i) EXPECT_EQ(edit_to_json(edits[i], true), canonical[i]) << i;
  EXPECT_EQ(scene_to_json(scene)["edits"], canonical);

  // The file parser names the path of a bad frame and of a bad window.
  j["edits"][0]["frame"] = 21;
  EXPECT_NE(test::error_of([&] { scene_from_json(j, "test.json"); }).find("test.json: edits[0].frame: "),
            std::string::npos);
  j["edits"][0]["frame"] = 3;
  j["edits"][0]["window"] = 2;
  EXPECT_NE(test::error_of([&] { scene_from_json(j, "test.json"); }).find("edits[0].window: must be in [0, 1]"),
            std::string::npos);
}

TEST(Edits, DescribeNamesTheEdit) {
  CancelEdit c;
  c.frame = 40;
  c.pair = {Vec3(0.1, 0.2, 0), Vec3(0.15, 0.22, 0)};
  EXPECT_EQ(describe(c), "cancel the pair near (0.1, 0.2) and (0.15, 0.22) at frame 40");
  EXPECT_STREQ(op_name(Edit(SmoothEdit{0.5})), "smooth");
}

}  // namespace
}  // namespace tvf
