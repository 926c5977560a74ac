#include "tvf/design/keyframe_topology.h"

#include "tvf/analysis/topology.h"
#include "tvf/design/generate.h"
#include "tvf/design/keyframes.h"
#include "tvf/scene/scene_json.h"
#include "tvf/solve/connection_laplacian.h"

#include "support/test_paths.h"

#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <string>

namespace tvf {
namespace {

// Two key frames whose singularities are far apart (DESIGN §12's case): a source and a
// center on the left at t = 0, on the right at t = 1 (with the saddle the solve puts between
// them). The free solve fades each out and the other in, through pairs created and
// cancelled in between; the matched solve carries them across.
std::string move_scene(int n, const std::string& solver_extra = "", int frames = 33) {
  return R"({"tvf": 1, "domain": {"grid": {"size": [)" + std::to_string(n) + ", " + std::to_string(n) +
         R"(], "min": [-1, -1], "max": [1, 1]}},
  "time": {"frames": )" + std::to_string(frames) +
         R"(, "range": [0, 1]}, "generator": "spacetime", "falloff": 8,
  "solver": {"region_radius": 0.15)" +
         solver_extra + R"(},
  "keyframes": [
    {"t": 0, "elements": [{"kind": "singular", "type": "source", "at": [-0.6, -0.4]},
                          {"kind": "singular", "type": "ccw_center", "at": [-0.6, 0.4]}]},
    {"t": 1, "elements": [{"kind": "singular", "type": "source", "at": [0.6, -0.4]},
                          {"kind": "singular", "type": "ccw_center", "at": [0.6, 0.4]}]}]})";
}

struct Generated {
  std::unique_ptr<DesignSpace> space;
  Field field;
  GenerateReport report;
  Topology topology;
};

Generated run(const std::string& text) {
  const Scene s = parse_scene(text, "scene.json");
  Generated g{make_design_space(s), Field(), {}, {}};
  g.field = generate(*g.space, s, {}, &g.report);
  g.topology = analyze_topology(g.space->bundle(), g.field);
  return g;
}

// The largest, over consecutive frames, of the mean angle (radians) the field's direction
// turns from one frame to the next at vertices farther than `keep_out` from every
// singularity of both frames: the frame-to-frame coherence away from the singularities.
double worst_mean_turn(const Generated& g, double keep_out) {
  const Mesh& mesh = g.space->mesh();
  double worst = 0;
  for (int j = 0; j + 1 < g.field.frames(); ++j) {
    double sum = 0;
    int count = 0;
    for (int v = 0; v < mesh.num_vertices(); ++v) {
      bool near = false;
      for (int f : {j, j + 1})
        for (const Singularity& s : g.topology.singularities[static_cast<size_t>(f)])
          near = near || (s.position - mesh.position(v)).norm() < keep_out;
      const cplx a = g.field.at(j, v), b = g.field.at(j + 1, v);
      if (near || std::abs(a) == 0 || std::abs(b) == 0) continue;
      sum += std::abs(std::arg(b / a));
      ++count;
    }
    if (count > 0) worst = std::max(worst, sum / count);
  }
  return worst;
}

TEST(KeyframeTopology, FreeSolveShowsSpuriousBifurcationsMatchedShowsNone) {
  for (int n : {33, 65}) {
    const Generated free = run(move_scene(n));
    const Generated matched = run(move_scene(n, R"(, "keyframe_topology": "matched")"));
    // The free solve: singularities fade out and in through pairs the key frames never asked for.
    EXPECT_GE(free.topology.bifurcations.size(), 2u) << n;
    // The matched solve: no bifurcation at all; one path per matched singularity, each from
    // the first frame to the last, ending where the next key frame has it.
    ASSERT_EQ(matched.report.keyframe_intervals.size(), 1u);
    const KeyframeIntervalReport& r = matched.report.keyframe_intervals[0];
    EXPECT_TRUE(r.created.empty() && r.cancelled.empty()) << n;
    EXPECT_EQ(matched.topology.bifurcations.size(), 0u) << n;
    ASSERT_EQ(matched.topology.paths.size(), r.matched.size()) << n;
    for (const SingularityPath& p : matched.topology.paths) {
      EXPECT_EQ(p.birth, 0.0);
      EXPECT_EQ(p.death, 1.0);
      const auto& m = *std::min_element(r.matched.begin(), r.matched.end(), [&](const auto& x, const auto& y) {
        return (x.from - p.points.front().position).norm() < (y.from - p.points.front().position).norm();
      });
      EXPECT_LT((m.from - p.points.front().position).norm(), 1e-9);
      EXPECT_LT((m.to - p.points.back().position).norm(), 1e-9);
    }
    // The designed source and center are matched to their own kind across the domain.
    int sources = 0, centers = 0;
    for (const auto& m : r.matched) {
      if (m.type == SingularityType::source && (m.to - Vec3(0.6, -0.4, 0)).norm() < 0.05) ++sources;
      if (m.type == SingularityType::center && (m.to - Vec3(0.6, 0.4, 0)).norm() < 0.05) ++centers;
    }
    EXPECT_EQ(sources, 1) << n;
    EXPECT_EQ(centers, 1) << n;
    // Coherent in time away from the singularities: the mean turn per frame stays small
    // (free: where a singularity fades, the direction turns over the whole neighbourhood).
    const double h = matched.space->mesh().mean_edge_length();
    const double turn_free = worst_mean_turn(free, 3 * h), turn_matched = worst_mean_turn(matched, 3 * h);
    std::printf("  %d²: worst mean turn per frame %.3f rad free, %.3f rad matched; bifurcations %zu free, %zu matched\n",
                n, turn_free, turn_matched, free.topology.bifurcations.size(), matched.topology.bifurcations.size());
    EXPECT_LT(turn_matched, 0.25) << n;
  }
}

TEST(KeyframeTopology, FreeIsTodaysSolveBitForBit) {
  const Generated a = run(move_scene(17, "", 9));
  const Generated b = run(move_scene(17, R"(, "keyframe_topology": "free")", 9));
  EXPECT_EQ(a.field.data(), b.field.data());
  EXPECT_TRUE(b.report.keyframe_intervals.empty());
  // The canonical scene keeps its keys for "free" scenes.
  EXPECT_FALSE(scene_to_json(parse_scene(move_scene(17), "s")).at("solver").contains("keyframe_topology"));
}

// A pair that only the first key frame holds is cancelled at the time the scene sets, and
// one only the second holds is created then; nothing else happens.
TEST(KeyframeTopology, UnmatchedPairsAreCancelledAndCreatedAtTheSetTime) {
  const std::string pair = R"([{"kind": "singular", "type": "saddle", "at": [-0.3, 0]},
                                {"kind": "singular", "type": "source", "at": [0.3, 0]}])";
  const std::string flow = R"("streamlines": [{"points": [[-1, -0.7], [1, -0.7]], "speed": 0.1},
                                               {"points": [[-1, 0.7], [1, 0.7]], "speed": 0.1}])";
  for (int creation = 0; creation < 2; ++creation) {
    const std::string k0 = creation ? "{\"t\": 0, " + flow + "}" : "{\"t\": 0, \"elements\": " + pair + ", " + flow + "}";
    const std::string k1 = creation ? "{\"t\": 1, \"elements\": " + pair + ", " + flow + "}" : "{\"t\": 1, " + flow + "}";
    const std::string text = R"({"tvf": 1, "domain": {"grid": {"size": [33, 33], "min": [-1, -1], "max": [1, 1]}},
      "time": {"frames": 41, "range": [0, 1]}, "generator": "spacetime", "falloff": 8,
      "solver": {"region_radius": 0.15, "keyframe_topology": "matched", "bifurcation_times": [0.3]},
      "keyframes": [)" + k0 + ", " + k1 + "]}";
    const Generated g = run(text);
    const KeyframeIntervalReport& r = g.report.keyframe_intervals.at(0);
    EXPECT_EQ(r.bifurcation_t, 0.3);
    EXPECT_EQ(r.matched.size(), 0u);
    // The designed pair, and any other pair the key frame's static solve has, each planned
    // once and found once: only the forced bifurcations, all at the set time.
    EXPECT_GE(creation ? r.created.size() : r.cancelled.size(), 1u);
    EXPECT_EQ(creation ? r.cancelled.size() : r.created.size(), 0u);
    EXPECT_TRUE(r.unpaired_first.empty() && r.unpaired_second.empty());
    ASSERT_EQ(g.topology.bifurcations.size(), r.created.size() + r.cancelled.size()) << creation;
    // Each where its template was put (between the two it joins).
    const auto& planned = creation ? r.created : r.cancelled;
    for (const Bifurcation& b : g.topology.bifurcations) {
      EXPECT_EQ(b.kind, creation ? BifurcationKind::creation : BifurcationKind::cancellation);
      EXPECT_NEAR(b.t, 0.3, 1.5 / 40) << creation;
      double nearest = 1e9;
      for (const auto& p : planned) nearest = std::min(nearest, (b.position - p.at).norm());
      EXPECT_LT(nearest, 0.15) << creation;
    }
    EXPECT_EQ(g.topology.paths.size(), 2 * g.topology.bifurcations.size()) << creation;
  }
}

// Links override the nearest match. Sources A (−0.6, 0) and B (0, 0) go to C (0.2, 0) and
// D (0.8, 0): nearest first takes B → C, then A → D, whose path runs through B's (a
// collision the analysis shows); linking A → C and B → D moves both right side by side.
TEST(KeyframeTopology, LinksChooseThePairs) {
  auto scene = [](const std::string& links) {
    return R"({"tvf": 1, "domain": {"grid": {"size": [33, 33], "min": [-1, -1], "max": [1, 1]}},
      "time": {"frames": 33, "range": [0, 1]}, "generator": "spacetime", "falloff": 8,
      "solver": {"region_radius": 0.15, "keyframe_topology": "matched")" +
           links + R"(},
      "keyframes": [
        {"t": 0, "elements": [{"kind": "singular", "type": "source", "at": [-0.6, 0]},
                              {"kind": "singular", "type": "source", "at": [0, 0]}]},
        {"t": 1, "elements": [{"kind": "singular", "type": "source", "at": [0.2, 0]},
                              {"kind": "singular", "type": "source", "at": [0.8, 0]}]}]})";
  };
  auto to_of = [](const Generated& g, double from_x) {
    for (const auto& m : g.report.keyframe_intervals.at(0).matched)
      if (std::abs(m.from.x() - from_x) < 0.05 && m.type == SingularityType::source) return m;
    ADD_FAILURE() << "no source matched from x = " << from_x;
    return KeyframeIntervalReport::Match{};
  };
  const Generated nearest = run(scene(""));
  EXPECT_NEAR(to_of(nearest, 0.0).to.x(), 0.2, 0.05);
  EXPECT_NEAR(to_of(nearest, -0.6).to.x(), 0.8, 0.05);
  EXPECT_FALSE(to_of(nearest, -0.6).linked);
  const Generated linked =
      run(scene(R"(, "links": [{"from": [0, 0], "to": [1, 0]}, {"from": [0, 1], "to": [1, 1]}])"));
  EXPECT_NEAR(to_of(linked, -0.6).to.x(), 0.2, 0.05);
  EXPECT_NEAR(to_of(linked, 0.0).to.x(), 0.8, 0.05);
  EXPECT_TRUE(to_of(linked, 0.0).linked);
  EXPECT_TRUE(to_of(linked, -0.6).linked);
  std::printf("  links: bifurcations %zu nearest first, %zu linked\n", nearest.topology.bifurcations.size(),
              linked.topology.bifurcations.size());
  EXPECT_EQ(linked.topology.bifurcations.size(), 0u);
  EXPECT_EQ(linked.topology.paths.size(), linked.report.keyframe_intervals[0].matched.size());
}

TEST(KeyframeTopology, OnASphereTheMatchedPathsHaveNoBifurcation) {
  const std::string text = R"({"tvf": 1, "domain": {"sphere": {"subdivisions": 4, "radius": 1}},
    "time": {"frames": 25, "range": [0, 1]}, "generator": "spacetime", "falloff": 8,
    "solver": {"region_radius": 0.15, "keyframe_topology": "matched"},
    "keyframes": [
      {"t": 0, "elements": [{"kind": "singular", "type": "source", "at": [0.0, 0.0, 1.0]},
                            {"kind": "singular", "type": "sink", "at": [0.0, 0.0, -1.0]}]},
      {"t": 1, "elements": [{"kind": "singular", "type": "source", "at": [0.8, 0.0, 0.6]},
                            {"kind": "singular", "type": "sink", "at": [-0.8, 0.0, -0.6]}]}]})";
  const Generated g = run(text);
  const KeyframeIntervalReport& r = g.report.keyframe_intervals.at(0);
  EXPECT_TRUE(r.unpaired_first.empty() && r.unpaired_second.empty());
  EXPECT_EQ(g.topology.bifurcations.size(), r.created.size() + r.cancelled.size());
  EXPECT_EQ(g.topology.bifurcations.size(), 0u);
  // Poincaré–Hopf holds at every frame; every path spans the whole time.
  for (const auto& frame : g.topology.singularities) {
    int sum = 0;
    for (const Singularity& s : frame) sum += s.index;
    EXPECT_EQ(sum, 2);
  }
  for (const SingularityPath& p : g.topology.paths) {
    EXPECT_EQ(p.birth, 0.0);
    EXPECT_EQ(p.death, 1.0);
  }
  const double h = g.space->mesh().mean_edge_length();
  std::printf("  sphere: worst mean turn per frame %.3f rad matched, %zu paths\n", worst_mean_turn(g, 3 * h),
              g.topology.paths.size());
  EXPECT_LT(worst_mean_turn(g, 3 * h), 0.25);
}

TEST(KeyframeTopology, BadLinksAndTimesAreRefusedInOneSentence) {
  auto err = [](const std::string& solver_extra) {
    return test::error_of([&] { parse_scene(move_scene(17, solver_extra), "scene.json"); });
  };
  EXPECT_EQ(err(R"(, "keyframe_topology": "kept")"),
            "scene.json: solver.keyframe_topology: unknown key-frame topology \"kept\" (expected one of free, matched)");
  EXPECT_EQ(err(R"(, "links": [])"), "scene.json: solver.links: applies only with \"keyframe_topology\": \"matched\"");
  EXPECT_EQ(err(R"(, "keyframe_topology": "matched", "links": [{"from": [0, 0], "to": [1, 1]}])"),
            "scene.json: solver.links[0]: links a source (keyframes[0].elements[0]) with a ccw_center "
            "(keyframes[1].elements[1]); linked singularities must have the same type");
  EXPECT_EQ(err(R"(, "keyframe_topology": "matched", "links": [{"from": [0, 0], "to": [1, 2]}])"),
            "scene.json: solver.links[0].to[1]: must be an integer in [0, 1], got 2");
  EXPECT_EQ(err(R"(, "keyframe_topology": "matched", "links": [{"from": [0, 0], "to": [3, 0]}])"),
            "scene.json: solver.links[0].to[0]: must be an integer in [0, 1], got 3");
  EXPECT_EQ(err(R"(, "keyframe_topology": "matched", "links": [{"from": [1, 0], "to": [0, 0]}])"),
            "scene.json: solver.links[0].to: links key frame 1 with key frame 0; a link joins a key frame with the "
            "next one (k and k + 1)");
  EXPECT_EQ(err(R"(, "keyframe_topology": "matched", "links": [{"from": [0, 0], "to": [1, 0]}, {"from": [0, 0], "to": [1, 0]}])"),
            "scene.json: solver.links[1].from: keyframes[0].elements[0] is already linked by an earlier link");
  EXPECT_EQ(err(R"(, "keyframe_topology": "matched", "bifurcation_times": [1.5])"),
            "scene.json: solver.bifurcation_times[0]: t = 1.5 is not inside the interval (0, 1) between keyframes[0] "
            "and keyframes[1]");
  EXPECT_EQ(err(R"(, "keyframe_topology": "matched", "bifurcation_times": [0.2, 0.4])"),
            "scene.json: solver.bifurcation_times: needs one time per interval between consecutive key frames (1), "
            "got 2");
  // One line each.
  EXPECT_EQ(test::count_lines(err(R"(, "keyframe_topology": "matched", "bifurcation_times": [1.5])")), 0);
}

TEST(KeyframeTopology, ReportAndSceneRoundTripAsJson) {
  const std::string extra = R"(, "keyframe_topology": "matched", "links": [{"from": [0, 1], "to": [1, 1]}], "bifurcation_times": [0.4])";
  const Scene s = parse_scene(move_scene(17, extra), "s");
  const Scene back = parse_scene(scene_to_text(s), "s");
  EXPECT_EQ(back.solver.keyframe_topology, KeyframeTopology::matched);
  ASSERT_EQ(back.solver.links.size(), 1u);
  EXPECT_EQ(back.solver.links[0].from_element, 1);
  EXPECT_EQ(back.solver.links[0].to_keyframe, 1);
  EXPECT_EQ(back.solver.bifurcation_times, std::vector<double>{0.4});
  const Generated g = run(scene_to_text(s));
  const nlohmann::json j = keyframe_intervals_json(g.report.keyframe_intervals);
  ASSERT_EQ(j.size(), 1u);
  EXPECT_EQ(j[0]["interval"], nlohmann::json({0.0, 1.0}));
  EXPECT_EQ(j[0]["bifurcation_t"], 0.4);
  EXPECT_EQ(j[0]["matched"].size(), g.report.keyframe_intervals[0].matched.size());
  int linked = 0;
  for (const auto& m : j[0]["matched"]) linked += m["linked"].get<bool>();
  EXPECT_EQ(linked, 1);
}

}  // namespace
}  // namespace tvf
