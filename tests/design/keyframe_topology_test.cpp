#include "tvf/design/keyframe_topology.h"

#include "tvf/analysis/topology.h"
#include "tvf/design/generate.h"
#include "tvf/design/keyframes.h"
#include "tvf/integrate/periodic_orbits.h"
#include "tvf/mesh/face_subdivision.h"
#include "tvf/mesh/mesh_io.h"
#include "tvf/mesh/primitives.h"
#include "tvf/scene/scene_json.h"
#include "tvf/solve/connection_laplacian.h"

#include "support/test_paths.h"

#include <gtest/gtest.h>
#include <nlohmann/json.hpp>

#include <algorithm>
#include <array>
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <functional>
#include <limits>
#include <regex>
#include <string>
#include <vector>

// The grids the planar cases run on. Under the sanitizers the finest is left out: it runs
// the 65² case's code paths again at four times the cost (minutes under ASan on two
// cores); the release suite runs all three.
#ifdef TVF_SANITIZE_BUILD
constexpr std::array kGridSides{33, 65};
constexpr bool kSanitize = true;
#else
constexpr std::array kGridSides{33, 65, 129};
constexpr bool kSanitize = false;
#endif

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

// A node (index +1) followed through the analysed frames from `at`: in each frame the one
// nearest to where it was in the last (null in a frame that has none).
std::vector<const Singularity*> node_followed_from(const Topology& topology, Vec3 at) {
  std::vector<const Singularity*> out;
  for (const auto& frame : topology.singularities) {
    const Singularity* best = nullptr;
    for (const Singularity& s : frame)
      if (s.index == 1 && (!best || (s.position - at).norm() < (best->position - at).norm())) best = &s;
    if (best) at = best->position;
    out.push_back(best);
  }
  return out;
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
    // Two paths per pair: the guide holds each pair's node to its key frame's type on the
    // way to the template (its G turns a whole turn there; unheld, the tracker split both
    // paths where the type turned: 8 paths at 33², 41 frames).
    EXPECT_EQ(g.topology.paths.size(), 2 * g.topology.bifurcations.size()) << creation;
  }
}

// Pairs created or cancelled within four frames of the key frame they leave or reach: the
// generator warns (the field changes abruptly there: example 26's max/median
// frame-to-frame change 5.1 three frames from it, 1.5 at twelve), naming the time set and
// the latest (earliest) time that has the room; none four frames away or more.
TEST(KeyframeTopology, PairsCreatedRightBeforeTheKeyFrameAreWarnedOf) {
  nlohmann::json scene = nlohmann::json::parse(test::read_text(test::source_dir() + "/examples/26_keyframe_topology/scene.json"));
  ASSERT_EQ(scene["time"]["frames"], 60);  // frames 1/59 apart
  auto warned = [&](double t) {
    scene["solver"]["bifurcation_times"] = {t};
    const Generated g = run(scene.dump());
    EXPECT_EQ(g.report.keyframe_intervals.at(0).created.size(), 1u);
    std::string out;
    for (const std::string& w : g.report.warnings)
      if (w.find("the pairs are created") != std::string::npos) out = w;
    return out;
  };
  EXPECT_EQ(warned(0.95),
            "scene: solver.bifurcation_times[0]: between keyframes[0] and keyframes[1] the pairs are created at "
            "t = 0.95, 3 frames before keyframes[1] (t = 1): they appear and reach their places in the key frame "
            "within those frames, so the field changes abruptly there; set the time 4 frames or more from the key "
            "frame (t ≤ 0.9322) or use more frames");
  EXPECT_EQ(warned(0.93), "");  // 4.1 frames
  EXPECT_EQ(warned(0.6), "");
}

// Links override the nearest match. Sources A (−0.6, 0) and B (0, 0) go to C (0.2, 0) and
// D (0.8, 0): nearest first takes B → C, then A → D, whose path runs through B's (bent
// around it); linking A → C and B → D moves both right side by side. Either way the
// frames in between are the guide field, whose zeros are the carried ones alone: no
// bifurcation (26 when the saddle between the two kept the key frames' axes, 14 with it
// turned, before the guide), at 33², 65² and 129².
std::string links_scene(int n, const std::string& links) {
  return R"({"tvf": 1, "domain": {"grid": {"size": [)" + std::to_string(n) + ", " + std::to_string(n) +
         R"(], "min": [-1, -1], "max": [1, 1]}},
      "time": {"frames": 33, "range": [0, 1]}, "generator": "spacetime", "falloff": 8,
      "solver": {"region_radius": 0.15, "keyframe_topology": "matched")" +
         links + R"(},
      "keyframes": [
        {"t": 0, "elements": [{"kind": "singular", "type": "source", "at": [-0.6, 0]},
                              {"kind": "singular", "type": "source", "at": [0, 0]}]},
        {"t": 1, "elements": [{"kind": "singular", "type": "source", "at": [0.2, 0]},
                              {"kind": "singular", "type": "source", "at": [0.8, 0]}]}]})";
}

TEST(KeyframeTopology, LinksChooseThePairs) {
  auto to_of = [](const Generated& g, double from_x) {
    for (const auto& m : g.report.keyframe_intervals.at(0).matched)
      if (std::abs(m.from.x() - from_x) < 0.05 && m.type == SingularityType::source) return m;
    ADD_FAILURE() << "no source matched from x = " << from_x;
    return KeyframeIntervalReport::Match{};
  };
  for (const int n : kGridSides) {
    SCOPED_TRACE(n);
    const Generated nearest = run(links_scene(n, ""));
    EXPECT_NEAR(to_of(nearest, 0.0).to.x(), 0.2, 0.05);
    EXPECT_NEAR(to_of(nearest, -0.6).to.x(), 0.8, 0.05);
    EXPECT_FALSE(to_of(nearest, -0.6).linked);
    const Generated linked =
        run(links_scene(n, R"(, "links": [{"from": [0, 0], "to": [1, 0]}, {"from": [0, 1], "to": [1, 1]}])"));
    EXPECT_NEAR(to_of(linked, -0.6).to.x(), 0.2, 0.05);
    EXPECT_NEAR(to_of(linked, 0.0).to.x(), 0.8, 0.05);
    EXPECT_TRUE(to_of(linked, 0.0).linked);
    EXPECT_TRUE(to_of(linked, -0.6).linked);
    std::printf("  links %d²: bifurcations %zu nearest first, %zu linked\n", n, nearest.topology.bifurcations.size(),
                linked.topology.bifurcations.size());
    for (const Generated* g : {&nearest, &linked}) {
      EXPECT_TRUE(g->report.keyframe_intervals[0].guided);
      EXPECT_EQ(g->topology.bifurcations.size(), 0u);
      // Every frame holds the carried singularities and no other.
      for (const auto& frame : g->topology.singularities)
        EXPECT_EQ(frame.size(), g->report.keyframe_intervals[0].matched.size());
    }
  }
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

// A source and another singularity of `other` type trading places across the grid.
std::string trading_scene(int n, int frames, const std::string& other, const std::string& solver_extra) {
  return R"({"tvf": 1, "domain": {"grid": {"size": [)" + std::to_string(n) + ", " + std::to_string(n) +
         R"(], "min": [-1, -1], "max": [1, 1]}},
  "time": {"frames": )" + std::to_string(frames) +
         R"(, "range": [0, 1]}, "generator": "spacetime", "falloff": 8,
  "solver": {"region_radius": 0.15, "keyframe_topology": "matched")" +
         solver_extra + R"(},
  "keyframes": [
    {"t": 0, "elements": [{"kind": "singular", "type": "source", "at": [-0.5, 0]},
                          {"kind": "singular", "type": ")" + other + R"(", "at": [0.5, 0]}]},
    {"t": 1, "elements": [{"kind": "singular", "type": "source", "at": [0.5, 0]},
                          {"kind": "singular", "type": ")" + other + R"(", "at": [-0.5, 0]}]}]})";
}

// A source and a sink trading places across the domain: matched by type, their straight
// paths meet head on half way.
std::string swap_scene(int n, int frames, const std::string& solver_extra = "") {
  return trading_scene(n, frames, "sink", solver_extra);
}

// The smallest distance between two singularities of one frame of the analysed field.
double closest_pair(const std::vector<Singularity>& frame) {
  double out = std::numeric_limits<double>::infinity();
  for (size_t a = 0; a < frame.size(); ++a)
    for (size_t b = a + 1; b < frame.size(); ++b) out = std::min(out, (frame[a].position - frame[b].position).norm());
  return out;
}

// Every frame of the analysed field holds the key frames' singularities, by index, and
// keeps them at least `separation` apart; the paths run from the first frame to the last,
// from where the first key frame has them to where the second does.
void expect_kept_apart(const Generated& g, double separation, double tol, const std::string& what) {
  SCOPED_TRACE(what);
  const KeyframeIntervalReport& r = g.report.keyframe_intervals.at(0);
  EXPECT_EQ(g.topology.bifurcations.size(), 0u);
  auto indices = [](const std::vector<Singularity>& frame) {
    std::vector<int> out;
    for (const Singularity& s : frame) out.push_back(s.index);
    std::sort(out.begin(), out.end());
    return out;
  };
  const std::vector<int> first = indices(g.topology.singularities.front());
  EXPECT_EQ(first.size(), r.matched.size());
  double worst = std::numeric_limits<double>::infinity();
  for (size_t f = 0; f < g.topology.singularities.size(); ++f) {
    EXPECT_EQ(indices(g.topology.singularities[f]), first) << "frame " << f;
    worst = std::min(worst, closest_pair(g.topology.singularities[f]));
  }
  std::printf("  %s: closest two singularities of any frame %.4f apart (separation %.3g, planned %.4f)\n",
              what.c_str(), worst, separation, r.closest_approach);
  EXPECT_GE(worst, separation - tol);
  EXPECT_GE(r.closest_approach, separation * (1 - 1e-9));
  ASSERT_EQ(g.topology.paths.size(), r.matched.size());
  for (const SingularityPath& p : g.topology.paths) {
    EXPECT_EQ(p.birth, 0.0);
    EXPECT_EQ(p.death, 1.0);
    const auto& m = *std::min_element(r.matched.begin(), r.matched.end(), [&](const auto& x, const auto& y) {
      return (x.from - p.points.front().position).norm() < (y.from - p.points.front().position).norm();
    });
    EXPECT_LT((m.from - p.points.front().position).norm(), 1e-9);
    EXPECT_LT((m.to - p.points.back().position).norm(), 1e-9);
    EXPECT_GT(m.detour, 0.0);
  }
}

TEST(KeyframeTopology, CrossingPathsAreBentAroundEachOther) {
  // 32 frames: none at t = 0.5 exactly, where the field far from the two is zero by
  // symmetry (the key frames are each other's negatives), so its zeros there are rounding.
  for (const auto& [n, frames] : {std::pair{33, 32}, std::pair{65, 32}, std::pair{129, 32}}) {
    const Generated g = run(swap_scene(n, frames));
    const KeyframeIntervalReport& r = g.report.keyframe_intervals.at(0);
    ASSERT_EQ(r.matched.size(), 2u) << n;
    EXPECT_EQ(r.separation, 0.3);  // twice region_radius
    // Shared by length (both paths are 1 long): each bends half the separation out, to
    // opposite sides, and the 2 % margin.
    for (const auto& m : r.matched) EXPECT_NEAR(m.detour, 0.5 * 0.3 * 1.02, 1e-3) << n;
    // Planar constraints are exact (the linear field's zero is the carried point), so the
    // analysed singularities keep the separation to rounding.
    expect_kept_apart(g, 0.3, 1e-6, std::to_string(n) + "²");
  }
  // Straight paths (path_separation 0): the two meet half way and the analysis shows it.
  const Generated straight = run(swap_scene(33, 32, R"(, "path_separation": 0)"));
  double worst = std::numeric_limits<double>::infinity();
  for (const auto& frame : straight.topology.singularities) worst = std::min(worst, closest_pair(frame));
  const bool collided = worst < 0.3 || !straight.topology.bifurcations.empty() || straight.topology.paths.size() != 2;
  std::printf("  straight: closest %.4f, %zu bifurcations, %zu paths\n", worst, straight.topology.bifurcations.size(),
              straight.topology.paths.size());
  EXPECT_TRUE(collided);
  EXPECT_EQ(straight.report.keyframe_intervals.at(0).matched.at(0).detour, 0.0);
  // A separation the scene sets.
  const Generated wide = run(swap_scene(33, 32, R"(, "path_separation": 0.5)"));
  expect_kept_apart(wide, 0.5, 1e-6, "33², separation 0.5");
}

TEST(KeyframeTopology, CrossingPathsOnASphereAreBentAroundEachOther) {
  const std::string text = R"({"tvf": 1, "domain": {"sphere": {"subdivisions": 4, "radius": 1}},
    "time": {"frames": 32, "range": [0, 1]}, "generator": "spacetime", "falloff": 8,
    "solver": {"region_radius": 0.15, "keyframe_topology": "matched"},
    "keyframes": [
      {"t": 0, "elements": [{"kind": "singular", "type": "source", "at": [0.6, 0.0, 0.8]},
                            {"kind": "singular", "type": "sink", "at": [-0.6, 0.0, 0.8]}]},
      {"t": 1, "elements": [{"kind": "singular", "type": "source", "at": [-0.6, 0.0, 0.8]},
                            {"kind": "singular", "type": "sink", "at": [0.6, 0.0, 0.8]}]}]})";
  const Generated g = run(text);
  ASSERT_EQ(g.report.keyframe_intervals.at(0).matched.size(), 2u);
  // On a surface the zero of the constrained field is found within the face holding it.
  expect_kept_apart(g, 0.3, 0.5 * g.space->mesh().mean_edge_length(), "sphere");
}

// Paths that do not come near each other are left exactly as they were.
TEST(KeyframeTopology, PathsThatDoNotMeetStayStraightBitForBit) {
  const Scene a = parse_scene(move_scene(33, R"(, "keyframe_topology": "matched")", 17), "a.json");
  const Scene b = parse_scene(move_scene(33, R"(, "keyframe_topology": "matched", "path_separation": 0)", 17), "b.json");
  const auto space = make_design_space(a);
  const ConnectionLaplacian lap = connection_laplacian(space->bundle(), LaplacianWeights::cotan);
  std::vector<std::vector<cplx>> keys;
  for (size_t k = 0; k < a.keyframes.size(); ++k) keys.push_back(keyframe_field(*space, a, k, lap));
  const KeyframeTopologyPlan pa(*space, a, keys), pb(*space, b, keys);
  const KeyframeIntervalReport& r = pa.intervals().at(0);
  ASSERT_GE(r.matched.size(), 2u);
  EXPECT_GE(r.closest_approach, r.separation);
  for (const auto& m : r.matched) EXPECT_EQ(m.detour, 0.0);
  for (int j = 1; j + 1 < a.time.frames; ++j) {
    const double t = a.time.time(j);
    const std::vector<Vec3> ca = pa.carried(t), cb = pb.carried(t);
    ASSERT_EQ(ca.size(), r.matched.size());
    ASSERT_EQ(ca.size(), cb.size());
    // The straight segment's point at the smoothstep of time, to the bit.
    const double u = t, s = u * u * (3 - 2 * u);
    for (size_t i = 0; i < ca.size(); ++i) {
      EXPECT_EQ(ca[i], cb[i]);
      EXPECT_EQ(ca[i], r.matched[i].from + s * (r.matched[i].to - r.matched[i].from));
    }
  }
  EXPECT_EQ(run(scene_to_text(a)).field.data(), run(scene_to_text(b)).field.data());
}

// A strip too narrow to pass (the separation asked, 0.2, in a strip 0.25 wide): the paths
// stay straight, and the report and a warning say so in one sentence naming the two paths.
std::string no_room_scene(const std::string& separation) {
  return R"({"tvf": 1, "domain": {"grid": {"size": [65, 9], "min": [-1, -0.125], "max": [1, 0.125]}},
    "time": {"frames": 17, "range": [0, 1]}, "generator": "spacetime", "falloff": 8,
    "solver": {"region_radius": 0.1, "keyframe_topology": "matched")" + separation + R"(},
    "keyframes": [
      {"t": 0, "elements": [{"kind": "singular", "type": "source", "at": [-0.5, 0]},
                            {"kind": "singular", "type": "sink", "at": [0.5, 0]}]},
      {"t": 1, "elements": [{"kind": "singular", "type": "source", "at": [0.5, 0]},
                            {"kind": "singular", "type": "sink", "at": [-0.5, 0]}]}]})";
}
TEST(KeyframeTopology, CrossingPathsWithNoRoomAreReported) {
  const std::string text = R"({"tvf": 1, "domain": {"grid": {"size": [65, 9], "min": [-1, -0.125], "max": [1, 0.125]}},
    "time": {"frames": 17, "range": [0, 1]}, "generator": "spacetime", "falloff": 8,
    "solver": {"region_radius": 0.1, "keyframe_topology": "matched", "path_separation": 0.2},
    "keyframes": [
      {"t": 0, "elements": [{"kind": "singular", "type": "source", "at": [-0.5, 0]},
                            {"kind": "singular", "type": "sink", "at": [0.5, 0]}]},
      {"t": 1, "elements": [{"kind": "singular", "type": "source", "at": [0.5, 0]},
                            {"kind": "singular", "type": "sink", "at": [-0.5, 0]}]}]})";
  const Generated g = run(text);
  const KeyframeIntervalReport& r = g.report.keyframe_intervals.at(0);
  EXPECT_EQ(r.collision,
            "scene: solver.path_separation: between keyframes[0] and keyframes[1] the paths of the source from "
            "(-0.5, 0) to (0.5, 0) and the sink from (0.5, 0) to (-0.5, 0) come 0 apart at t = 0.5, and no detour "
            "inside the domain keeps them 0.2 apart, so the paths stay straight and the singularities meet; set a "
            "smaller solver.path_separation, link them differently (solver.links) or add a key frame between");
  EXPECT_NE(std::find(g.report.warnings.begin(), g.report.warnings.end(), r.collision), g.report.warnings.end());
  for (const auto& m : r.matched) EXPECT_EQ(m.detour, 0.0);
  EXPECT_EQ(keyframe_intervals_json(g.report.keyframe_intervals)[0]["collision"], r.collision);
  // Where, as numbers (the designer's "show where"): the two at t = 0.5, both at the middle.
  ASSERT_TRUE(r.collision_at.has_value());
  const KeyframeIntervalReport::Collision& c = *r.collision_at;
  EXPECT_DOUBLE_EQ(c.t, 0.5);
  EXPECT_EQ(c.types[0], SingularityType::source);
  EXPECT_EQ(c.types[1], SingularityType::sink);
  EXPECT_FALSE(c.template_);
  EXPECT_NEAR(c.distance, 0, 1e-12);
  EXPECT_NEAR(c.required, 0.2, 1e-12);
  for (const Vec3& p : c.points) EXPECT_LT(p.norm(), 1e-12);
  EXPECT_NEAR((c.points[0] - c.points[1]).norm(), c.distance, 1e-12);
  // Read back from keyframe_topology.json as written.
  const auto back = keyframe_intervals_from_json({{"intervals", keyframe_intervals_json(g.report.keyframe_intervals)}});
  ASSERT_TRUE(back.has_value());
  ASSERT_TRUE(back->at(0).collision_at.has_value());
  EXPECT_EQ(collision_json(*back->at(0).collision_at), collision_json(c));
  EXPECT_EQ(r.lowered_from, 0.0);  // the separation was asked for: not lowered
}

// The same strip with no path_separation: the default (twice region_radius, 0.2) is not the
// user's, and where it cannot be kept three quarters of it are tried, then of that: 0.15
// does not pass either, 0.1125 does, by pairwise detours; the interval is guided, its report
// says from what the separation was lowered and why, and no warning is given.
TEST(KeyframeTopology, TheDefaultSeparationIsLoweredWhereItCannotBeKept) {
  const Generated g = run(no_room_scene(""));
  const KeyframeIntervalReport& r = g.report.keyframe_intervals.at(0);
  EXPECT_TRUE(r.collision.empty()) << r.collision;
  EXPECT_FALSE(r.collision_at.has_value());
  EXPECT_EQ(r.lowered_from, 0.2);
  EXPECT_DOUBLE_EQ(r.separation, 0.2 * 0.75 * 0.75);
  EXPECT_EQ(r.lowered_because.find("scene: solver.keyframe_topology: between keyframes[0] and keyframes[1] the paths of "
                                   "the source from (-0.5, 0) to (0.5, 0) and the sink"),
            0u)
      << r.lowered_because;
  EXPECT_EQ(r.routing, "pairwise");
  EXPECT_TRUE(r.guided) << r.unguided_reason;
  EXPECT_GE(r.closest_approach, r.separation * (1 - 1e-9));
  for (const std::string& w : g.report.warnings) EXPECT_EQ(w.find("could not"), std::string::npos) << w;
  EXPECT_TRUE(g.topology.bifurcations.empty()) << g.topology.bifurcations.size();
  const nlohmann::json j = keyframe_intervals_json(g.report.keyframe_intervals)[0];
  EXPECT_EQ(j.at("lowered_from"), 0.2);
  EXPECT_EQ(j.at("lowered_because"), r.lowered_because);
  const auto back = keyframe_intervals_from_json({{"intervals", keyframe_intervals_json(g.report.keyframe_intervals)}});
  ASSERT_TRUE(back.has_value());
  EXPECT_EQ(back->at(0).lowered_from, 0.2);
}

// Three key frames, the middle one's elements linked both ways (a chain 0 → 1 → 2, the
// links crosswise in each interval): accepted (an element is carried from once and into
// once; the check refused the chain until session 24, and the designer dropped a middle
// element's first link when the second was made), and each interval carries its two links.
TEST(KeyframeTopology, AMiddleKeyFramesElementsAreLinkedBothWays) {
  const std::string text = R"({"tvf": 1, "domain": {"grid": {"size": [33, 33], "min": [-1, -1], "max": [1, 1]}},
    "time": {"frames": 21, "range": [0, 1]}, "generator": "spacetime", "falloff": 8,
    "solver": {"region_radius": 0.15, "keyframe_topology": "matched",
               "links": [{"from": [0, 0], "to": [1, 1]}, {"from": [0, 1], "to": [1, 0]},
                         {"from": [1, 0], "to": [2, 1]}, {"from": [1, 1], "to": [2, 0]}]},
    "keyframes": [
      {"t": 0, "elements": [{"kind": "singular", "type": "source", "at": [-0.5, -0.3]},
                            {"kind": "singular", "type": "source", "at": [0.5, -0.3]}]},
      {"t": 0.5, "elements": [{"kind": "singular", "type": "source", "at": [-0.5, 0.1]},
                              {"kind": "singular", "type": "source", "at": [0.5, 0.1]}]},
      {"t": 1, "elements": [{"kind": "singular", "type": "source", "at": [-0.5, 0.5]},
                            {"kind": "singular", "type": "source", "at": [0.5, 0.5]}]}]})";
  const Scene scene = parse_scene(text, "scene.json");
  ASSERT_EQ(scene.solver.links.size(), 4u);
  const Generated g = run(text);
  ASSERT_EQ(g.report.keyframe_intervals.size(), 2u);
  for (const KeyframeIntervalReport& r : g.report.keyframe_intervals) {
    const auto linked = std::count_if(r.matched.begin(), r.matched.end(), [](const auto& m) { return m.linked; });
    EXPECT_EQ(linked, 2) << r.from_keyframe;
    // Crosswise: the linked sources trade sides.
    for (const auto& m : r.matched) {
      if (!m.linked) continue;
      EXPECT_LT(m.from.x() * m.to.x(), 0.0) << r.from_keyframe;
    }
  }
}

// Through a middle key frame the paths and the field go on moving: each interval's warp of
// time has slope 1 there (the rate of the free solve's linear interpolation), not the
// smoothstep's 0, which stopped every singularity and the whole field at every key frame
// (the sphere knot with its middle key frame: coherence 0.4 there against 5 to 11). A
// source carried straight up, −0.4 → 0 → 0.4, at even speed through t = 0.5: its steps
// next to the middle key frame are those of the rest of its way (with the smoothstep, a
// fifth of them), and so is the field's change there. With 20 frames t = 0.5 falls between
// frames 9 and 10: the key frame is held at frame 10 (t = 0.526), and the intervals meet
// there (planned to meet at t = 0.5, the steps next to frame 10 were half the others).
TEST(KeyframeTopology, PathsGoOnThroughAMiddleKeyFrame) {
  for (const auto& [n, frames] : {std::pair{33, 21}, std::pair{65, 21}, std::pair{33, 20}}) {
    const std::string text = R"({"tvf": 1, "domain": {"grid": {"size": [)" + std::to_string(n) + ", " +
                             std::to_string(n) + R"(], "min": [-1, -1], "max": [1, 1]}},
      "time": {"frames": )" + std::to_string(frames) + R"(, "range": [0, 1]}, "generator": "spacetime", "falloff": 8,
      "solver": {"region_radius": 0.15, "keyframe_topology": "matched"},
      "keyframes": [
        {"t": 0, "elements": [{"kind": "singular", "type": "source", "at": [-0.5, -0.4]},
                              {"kind": "singular", "type": "ccw_center", "at": [0.5, 0.4]}]},
        {"t": 0.5, "elements": [{"kind": "singular", "type": "source", "at": [-0.5, 0.0]},
                                {"kind": "singular", "type": "ccw_center", "at": [0.5, 0.0]}]},
        {"t": 1, "elements": [{"kind": "singular", "type": "source", "at": [-0.5, 0.4]},
                              {"kind": "singular", "type": "ccw_center", "at": [0.5, -0.4]}]}]})";
    const Generated g = run(text);
    ASSERT_EQ(g.report.keyframe_intervals.size(), 2u);
    for (const KeyframeIntervalReport& r : g.report.keyframe_intervals) ASSERT_FALSE(r.fallback) << n;
    ASSERT_EQ(g.topology.bifurcations.size(), 0u) << n;
    // The source: the repelling singularity nearest x = −0.5 in each frame.
    std::vector<double> y;
    for (const auto& frame : g.topology.singularities) {
      double best = std::numeric_limits<double>::infinity(), at = 0;
      for (const Singularity& s : frame)
        if ((s.type == SingularityType::source || s.type == SingularityType::repelling_focus) &&
            std::abs(s.position.x() + 0.5) < best)
          best = std::abs(s.position.x() + 0.5), at = s.position.y();
      ASSERT_LT(best, 0.1) << n << ", " << frames << " frames";
      y.push_back(at);
    }
    std::vector<double> steps;
    for (size_t j = 0; j + 1 < y.size(); ++j) steps.push_back(y[j + 1] - y[j]);
    std::vector<double> sorted = steps;
    std::sort(sorted.begin(), sorted.end());
    const double median = sorted[sorted.size() / 2];
    EXPECT_NEAR(median, 0.8 / (frames - 1), 0.015) << n;  // 0.8 over the steps, the ends eased
    // The key frame's frame (10 of 21 at t = 0.5; 10 of 20 at t = 0.526) and the steps
    // into and out of it.
    EXPECT_NEAR(g.report.keyframe_intervals[0].t1, 10.0 / (frames - 1), 1e-12) << n;
    EXPECT_NEAR(y[10], 0.0, 0.01) << n;
    for (const size_t j : {size_t{9}, size_t{10}})
      EXPECT_GT(steps[j], 0.6 * median) << n << ", " << frames << " frames: step " << j << " of "
                                        << ::testing::PrintToString(steps);
    // The field's change at the middle key frame against the rest (coherence y_i).
    std::vector<double> c = g.topology.coherence;
    ASSERT_EQ(c.size(), static_cast<size_t>(frames - 1));
    std::vector<double> cs = c;
    std::sort(cs.begin(), cs.end());
    const double c_median = cs[cs.size() / 2];
    for (const size_t j : {size_t{9}, size_t{10}})
      EXPECT_GT(c[j], 0.5 * c_median) << n << ", " << frames << " frames: coherence " << ::testing::PrintToString(c);
  }
}

// The guided field keeps the size of its key frames. Each node's size correction (Re λ,
// G against its own linear field) held only near it now; spread over the whole domain
// by Shepard's weights like the phase it set the far field's size by the nodes': example
// 26's knot (a source and a center trading places) was 13 to 15 times its key frames' size
// half-way (the median |V| of a frame), and the field's change from frame to frame peaked
// at 3.4 to 3.7 times its median. Directions are unchanged (the correction is a positive
// factor), and so are the singularities.
TEST(KeyframeTopology, TheGuidedFieldKeepsTheKeyFramesSize) {
  const std::string knot = test::read_text(test::source_dir() + "/examples/26_keyframe_topology/knot.json");
  for (const int n : kGridSides) {
    const std::string side = std::to_string(n);
    std::string text = knot;
    const std::string grid = R"("size": [65, 65])";
    ASSERT_NE(text.find(grid), std::string::npos);
    text.replace(text.find(grid), grid.size(), R"("size": [)" + side + ", " + side + "]");
    const Generated g = run(text);
    ASSERT_TRUE(g.report.keyframe_intervals.at(0).guided) << n;
    EXPECT_TRUE(g.topology.bifurcations.empty()) << n;
    std::vector<double> size;
    for (int j = 0; j < g.field.frames(); ++j) {
      std::vector<double> m;
      for (int v = 0; v < g.space->mesh().num_vertices(); ++v) m.push_back(std::abs(g.field.at(j, v)));
      std::nth_element(m.begin(), m.begin() + static_cast<std::ptrdiff_t>(m.size() / 2), m.end());
      size.push_back(m[m.size() / 2]);
    }
    const double lo = std::min(size.front(), size.back()), hi = std::max(size.front(), size.back());
    for (size_t j = 0; j < size.size(); ++j) {
      EXPECT_LT(size[j], 1.5 * hi) << n << ": frame " << j << " of " << ::testing::PrintToString(size);
      EXPECT_GT(size[j], 0.8 * lo) << n << ": frame " << j << " of " << ::testing::PrintToString(size);
    }
    std::vector<double> change = g.topology.coherence;
    std::sort(change.begin(), change.end());
    EXPECT_LT(change.back(), 2 * change[change.size() / 2]) << n << ": " << ::testing::PrintToString(g.topology.coherence);
  }
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
            "scene.json: solver.links[1].from: keyframes[0].elements[0] is already linked into the next key frame by "
            "an earlier link");
  EXPECT_EQ(err(R"(, "keyframe_topology": "matched", "links": [{"from": [0, 1], "to": [1, 1]}, {"from": [0, 0], "to": [1, 1]}])"),
            "scene.json: solver.links[1].to: keyframes[1].elements[1] is already linked from the previous key frame by "
            "an earlier link");
  EXPECT_EQ(err(R"(, "keyframe_topology": "matched", "bifurcation_times": [1.5])"),
            "scene.json: solver.bifurcation_times[0]: t = 1.5 is not inside the interval (0, 1) between keyframes[0] "
            "and keyframes[1]");
  EXPECT_EQ(err(R"(, "keyframe_topology": "matched", "bifurcation_times": [0.2, 0.4])"),
            "scene.json: solver.bifurcation_times: needs one time per interval between consecutive key frames (1), "
            "got 2");
  EXPECT_EQ(err(R"(, "path_separation": 0.2)"),
            "scene.json: solver.path_separation: applies only with \"keyframe_topology\": \"matched\"");
  EXPECT_NE(err(R"(, "keyframe_topology": "matched", "path_separation": -1)").find("scene.json: solver.path_separation: "),
            std::string::npos);
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
  EXPECT_FALSE(back.solver.path_separation);
  EXPECT_EQ(parse_scene(scene_to_text(parse_scene(move_scene(17, extra + R"(, "path_separation": 0.25)"), "s")), "s")
                .solver.path_separation,
            0.25);
  const Generated g = run(scene_to_text(s));
  const nlohmann::json j = keyframe_intervals_json(g.report.keyframe_intervals);
  ASSERT_EQ(j.size(), 1u);
  EXPECT_EQ(j[0]["interval"], nlohmann::json({0.0, 1.0}));
  EXPECT_EQ(j[0]["bifurcation_t"], 0.4);
  EXPECT_EQ(j[0]["matched"].size(), g.report.keyframe_intervals[0].matched.size());
  int linked = 0;
  for (const auto& m : j[0]["matched"]) linked += m["linked"].get<bool>();
  EXPECT_EQ(linked, 1);
  EXPECT_EQ(j[0]["separation"], 0.3);
  EXPECT_TRUE(j[0].contains("closest_approach"));
  for (const auto& m : j[0]["matched"]) EXPECT_EQ(m["detour"], 0.0);
}

// The knot on a surface: a source and a center trading places, 0.3 (chord) apart on a unit
// sphere near its north pole, or `half` either side of `centre` on a mesh. Matched with
// the static solve's other singularities (every one of both key frames), the interval is
// guided on a surface too (KeyframeTopologyPlan::SurfaceGuide): every frame holds the
// key frames' singularities and nothing else.
std::string surface_knot(const std::string& domain, const Vec3& a, const Vec3& b, double radius, double falloff) {
  auto at = [](const Vec3& p) { return fmt::format("[{}, {}, {}]", p.x(), p.y(), p.z()); };
  return R"({"tvf": 1, "domain": )" + domain + R"(,
    "time": {"frames": 32, "range": [0, 1]}, "generator": "spacetime", "falloff": )" +
         std::to_string(falloff) + R"(,
    "solver": {"region_radius": )" + std::to_string(radius) + R"(, "keyframe_topology": "matched"},
    "keyframes": [
      {"t": 0, "elements": [{"kind": "singular", "type": "source", "at": )" + at(a) + R"(},
                            {"kind": "singular", "type": "ccw_center", "at": )" + at(b) + R"(}]},
      {"t": 1, "elements": [{"kind": "singular", "type": "source", "at": )" + at(b) + R"(},
                            {"kind": "singular", "type": "ccw_center", "at": )" + at(a) + R"(}]}]})";
}

// Every frame holds as many singularities as the key frames, Poincaré–Hopf's sum, no
// bifurcation, and every path runs from the first frame to the last or ends at a type
// change (where the tracker splits it; no path is born or dies at a zero).
void expect_guided_knot(const Generated& g, const std::string& what, size_t allowed = 0) {
  const KeyframeIntervalReport& r = g.report.keyframe_intervals.at(0);
  EXPECT_TRUE(r.guided) << what;
  EXPECT_TRUE(r.created.empty() && r.cancelled.empty() && r.unpaired_first.empty() && r.unpaired_second.empty())
      << what;
  const size_t n = g.topology.singularities.front().size();
  EXPECT_EQ(n, r.matched.size()) << what;
  size_t lo = n, hi = n;
  for (const auto& frame : g.topology.singularities) {
    lo = std::min(lo, frame.size());
    hi = std::max(hi, frame.size());
    int sum = 0;
    for (const Singularity& s : frame) sum += s.index;
    EXPECT_EQ(sum, g.space->mesh().euler_characteristic()) << what;
  }
  std::printf("  %s: %zu singularities a frame (%zu–%zu), %zu bifurcations, %zu paths\n", what.c_str(), n, lo, hi,
              g.topology.bifurcations.size(), g.topology.paths.size());
  EXPECT_EQ(lo, n) << what;
  if (allowed == 0) {
    EXPECT_EQ(hi, n) << what;
  }
  EXPECT_LE(g.topology.bifurcations.size(), allowed) << what;
}

// Unguided (pairwise routing, the regions carried, the rest left to the solve) the same
// knot showed 6 and 10 bifurcations at subdivisions 3 and 4 (4–8 and 4–10 singularities a
// frame); guided, none.
TEST(KeyframeTopology, AKnotOnASphereIsGuided) {
  const double z = std::sqrt(0.75);
  for (const int sub : {3, 4}) {
    const Generated g = run(surface_knot(R"({"sphere": {"subdivisions": )" + std::to_string(sub) + R"(, "radius": 1}})",
                                         Vec3(-0.5, 0, z), Vec3(0.5, 0, z), 0.15, 8));
    expect_guided_knot(g, fmt::format("sphere, subdivisions {}", sub));
  }
}

// A surface guide whose every try holds other singularities than the plan's: the interval
// is left free, and its reason counts the wrong frames of the try and choice with fewest,
// every frame counted, though the check rejects each try at its first wrong frame (frames
// are counted on only when no try is kept). The knot of AKnotOnASphereIsGuided at
// subdivisions 1 (42 vertices): 8 of the 30 frames (counting each try only to its first
// wrong frame says 1). Both plans fail there, the static saddle and focus carried and
// paired (the second, which guides the knot at subdivisions 2 since session 21), and the
// report is the first's. At subdivisions 2 this test had 6 of 30. The second plan's frames
// hold the right number of zeros since session 23 (λ read at the poles' corners too), but
// its pairs' zeros jump 2.4 edge lengths from where it carries them, so the check's
// tracking (PhaseCheck::unplanned_events: 4 saddle–node events the plan does not have, as
// the analysis of the solved field found when it was kept) sets it aside too. The reason
// says where the first wrong frame goes wrong (session 37).
TEST(KeyframeTopology, AGuideRejectedAtEveryTryCountsAllItsWrongFrames) {
  const double z = std::sqrt(0.75);
  const Generated g =
      run(surface_knot(R"({"sphere": {"subdivisions": 1, "radius": 1}})", Vec3(-0.5, 0, z), Vec3(0.5, 0, z), 0.15, 8));
  const KeyframeIntervalReport& r = g.report.keyframe_intervals.at(0);
  EXPECT_FALSE(r.guided);
  EXPECT_TRUE(r.fallback);
  EXPECT_EQ(r.matched.size(), 4u);
  EXPECT_EQ(r.unguided_reason.rfind(
                "the surface guide's frames hold other singularities than the plan's at 8 of the 30 frames between "
                "the key frames (the first at t = ",
                0),
            0u)
      << r.unguided_reason;
  // Where the first wrong frame goes wrong: the count it holds against the plan's, and the
  // singularity farthest from where the plan has one (an extra, or one the plan carries
  // that the frame lacks), so that the user knows where a link or a key frame would help.
  EXPECT_NE(r.unguided_reason.find(" singularities where the plan carries 4; "), std::string::npos)
      << r.unguided_reason;
  EXPECT_TRUE(r.unguided_reason.find("; an extra ") != std::string::npos ||
              r.unguided_reason.find("; the plan's ") != std::string::npos)
      << r.unguided_reason;
  // The report's first_wrong is what the sentence says.
  ASSERT_TRUE(r.first_wrong.has_value());
  EXPECT_EQ(r.first_wrong->planned, 4);
  EXPECT_NE(r.first_wrong->found, 4);
  EXPECT_EQ(r.first_wrong->extra, r.first_wrong->found > 4);
  EXPECT_NE(r.unguided_reason.find(fmt::format("(the first at t = {:.3g}: {} singularities", r.first_wrong->t,
                                               r.first_wrong->found)),
            std::string::npos)
      << r.unguided_reason;
  EXPECT_TRUE(keyframe_intervals_json(g.report.keyframe_intervals)[0].contains("first_wrong"));
}

// The same knot at subdivisions 2 (162 vertices): carrying the static solve's saddle and
// focus (0.79 and 1.33 on a sphere of diameter 2) no surface guide try holds (6 of the 30
// frames wrong); planned again with the static solve's own matched within a quarter of the
// diameter, they are cancelled where they were and created where they will be: guided,
// and the analysis finds those two bifurcations and no other.
TEST(KeyframeTopology, AnUnguidedIntervalIsPlannedAgainWithTheFarOnesPaired) {
  const double z = std::sqrt(0.75);
  const Generated g =
      run(surface_knot(R"({"sphere": {"subdivisions": 2, "radius": 1}})", Vec3(-0.5, 0, z), Vec3(0.5, 0, z), 0.15, 8));
  const KeyframeIntervalReport& r = g.report.keyframe_intervals.at(0);
  EXPECT_TRUE(r.guided) << r.unguided_reason;
  EXPECT_EQ(r.matched.size(), 2u);
  EXPECT_EQ(r.cancelled.size(), 1u);
  EXPECT_EQ(r.created.size(), 1u);
  EXPECT_EQ(g.topology.bifurcations.size(), 2u);
  for (const auto& frame : g.topology.singularities) {
    int sum = 0;
    for (const Singularity& s : frame) sum += s.index;
    EXPECT_EQ(sum, 2);
  }
}

// A created or cancelled pair on a surface: the pair's factor in the guide is the planar
// template's as a ratio (docs/architecture.md "The guide on surfaces"). A saddle and a
// source 0.6 apart on the equator, present in one key frame only, beside matched paths:
// a source and a sink sliding 0.6 off the poles, or the knot of AKnotOnASphereIsGuided
// (whose key frames then differ in their saddle and focus too: 4 matched paths). Each
// frame holds the plan's singularities (Poincaré–Hopf: 2), and the analysis finds the
// planned bifurcation alone, of its kind, at the set time and where its template was put.
// Unguided (main), the knot with a created pair showed 15 and 19 bifurcations at
// subdivisions 3 and 4, with a cancelled pair 9 at subdivisions 4 (the sliding pair none:
// there it is the report's `guided` that tells). At subdivisions 4 the knot's pairs need
// the guide's second try, the weights' ramp twice as wide (12 and 6 of the 31 sampled
// frames held extra zeros with the first).
std::string pair_scene(int sub, bool knot, bool create) {
  auto el = [](const char* type, const Vec3& p) {
    return fmt::format(R"({{"kind": "singular", "type": "{}", "at": [{}, {}, {}]}})", type, p.x(), p.y(), p.z());
  };
  const double z = std::sqrt(0.75);
  const std::string pair = el("saddle", Vec3(0, -0.955, 0.296)) + ", " + el("source", Vec3(0, -0.955, -0.296));
  const std::string k0 = knot ? el("source", Vec3(-0.5, 0, z)) + ", " + el("ccw_center", Vec3(0.5, 0, z))
                              : el("source", Vec3(0, 0, 1)) + ", " + el("sink", Vec3(0, 0, -1));
  const std::string k1 = knot ? el("source", Vec3(0.5, 0, z)) + ", " + el("ccw_center", Vec3(-0.5, 0, z))
                              : el("source", Vec3(0.6, 0, 0.8)) + ", " + el("sink", Vec3(-0.6, 0, -0.8));
  return R"({"tvf": 1, "domain": {"sphere": {"subdivisions": )" + std::to_string(sub) + R"(, "radius": 1}},
    "time": {"frames": 32, "range": [0, 1]}, "generator": "spacetime", "falloff": 8,
    "solver": {"region_radius": 0.15, "keyframe_topology": "matched", "bifurcation_times": [0.4]},
    "keyframes": [{"t": 0, "elements": [)" + k0 + (create ? "" : ", " + pair) + R"(]},
                  {"t": 1, "elements": [)" + k1 + (create ? ", " + pair : "") + "]}]}";
}

TEST(KeyframeTopology, APairOnASphereIsCreatedOrCancelledByTheGuide) {
  struct Case {
    int sub;
    bool knot, create;
  };
  // Under the sanitizers four of the six (each kind of pair and each shape once: about
  // 80 s a case there on two cores, the subdivisions 3 ones less); the release suite runs
  // all six. The knot with a cancelled pair at subdivisions 3: its matched sink runs
  // nearly to its antipode, so its tube folds over every plane (the one-plane chart left
  // it unguided: 37 bifurcations carried, 3 free); the chart that follows the path
  // (follow_chart: Tutte's embedding of the tube) guides it with the planned one alone.
  std::vector<Case> cases{{4, false, true}, {3, true, true}, {4, true, false}, {3, true, false}};
  if (!kSanitize) cases.insert(cases.end(), {{4, false, false}, {4, true, true}});
  for (const Case c : cases) {
    const std::string what =
        fmt::format("{}, {} pair, subdivisions {}", c.knot ? "knot" : "sliding", c.create ? "created" : "cancelled", c.sub);
    const Generated g = run(pair_scene(c.sub, c.knot, c.create));
    const KeyframeIntervalReport& r = g.report.keyframe_intervals.at(0);
    EXPECT_TRUE(r.guided) << what;
    EXPECT_TRUE(r.unpaired_first.empty() && r.unpaired_second.empty()) << what;
    ASSERT_EQ(r.created.size(), c.create ? 1u : 0u) << what;
    ASSERT_EQ(r.cancelled.size(), c.create ? 0u : 1u) << what;
    const KeyframeIntervalReport::Pair& planned = c.create ? r.created[0] : r.cancelled[0];
    // Every frame: the matched paths, and the pair's two while it exists.
    const double dt = 1.0 / 31;
    for (size_t f = 0; f < g.topology.singularities.size(); ++f) {
      const auto& frame = g.topology.singularities[f];
      int sum = 0;
      for (const Singularity& s : frame) sum += s.index;
      EXPECT_EQ(sum, 2) << what << ", frame " << f;
      const double t = static_cast<double>(f) * dt;
      if (std::abs(t - 0.4) > dt) {
        EXPECT_EQ(frame.size(), r.matched.size() + ((t > 0.4) == c.create ? 2 : 0)) << what << ", frame " << f;
      }
    }
    std::printf("  %s: %zu bifurcations, %zu paths\n", what.c_str(), g.topology.bifurcations.size(),
                g.topology.paths.size());
    ASSERT_EQ(g.topology.bifurcations.size(), 1u) << what;
    const Bifurcation& b = g.topology.bifurcations[0];
    EXPECT_EQ(b.kind, c.create ? BifurcationKind::creation : BifurcationKind::cancellation) << what;
    EXPECT_NEAR(b.t, 0.4, dt) << what;
    EXPECT_LT((b.position - planned.at).norm(), 0.15) << what;
  }
}

// A created or cancelled pair's node is held to its key frame's type on a surface too
// (SurfaceGuide::PairHold, as Guide::PairPhase on the plane): in every frame where the
// pair exists (not within a frame of its event) the index +1 singularity nearest the
// node's key-frame place is a source, as designed. Without the hold, at subdivisions 3,
// the knot's created source was born a repelling focus and stayed one for 9 frames (with
// a Hopf event in `tvf analyze`), and the sliding pair's cancelled source was a repelling
// focus at frame 10.
TEST(KeyframeTopology, APairsNodeOnASphereKeepsItsType) {
  for (const bool knot : {true, false}) {
    const bool create = knot;
    const std::string what = fmt::format("{}, {} pair, subdivisions 3", knot ? "knot" : "sliding", create ? "created" : "cancelled");
    const Generated g = run(pair_scene(3, knot, create));
    const KeyframeIntervalReport& r = g.report.keyframe_intervals.at(0);
    ASSERT_TRUE(r.guided) << what;
    ASSERT_EQ((create ? r.created : r.cancelled).size(), 1u) << what;
    const KeyframeIntervalReport::Pair& planned = create ? r.created[0] : r.cancelled[0];
    const double dt = 1.0 / 31;
    int frames = 0, kept = 0;
    for (size_t f = 0; f < g.topology.singularities.size(); ++f) {
      const double t = static_cast<double>(f) * dt;
      if (std::abs(t - 0.4) <= dt || (t > 0.4) != create) continue;
      const Singularity* node = nullptr;
      for (const Singularity& s : g.topology.singularities[f])
        if (s.index > 0 && (!node || (s.position - planned.node).norm() < (node->position - planned.node).norm()))
          node = &s;
      ASSERT_NE(node, nullptr) << what << ", frame " << f;
      EXPECT_LT((node->position - planned.node).norm(), 0.4) << what << ", frame " << f;
      ++frames;
      if (node->type == planned.node_type) {
        ++kept;
      } else {
        ADD_FAILURE() << what << ", frame " << f << ": the pair's node is a " << to_string(node->type) << ", not a "
                      << to_string(planned.node_type);
      }
    }
    std::printf("  %s: the pair's node a %s in %d of %d frames\n", what.c_str(), to_string(planned.node_type), kept, frames);
  }
}

// A real mesh: CGAL's blobby (libcgal-demo's data archive, 2,027 vertices) and the same
// surface with every face split in four (8,102 vertices), the knot 0.3 across on its
// bumpy top. Unguided: 10 and 16 bifurcations (4–8 and 4–14 singularities a frame).
// Guided: none on the finer mesh; on the coarser one pair (the tube round a path is
// 2.5 edge lengths wide there, and the field turns fast across it).
TEST(KeyframeTopology, AKnotOnARealMeshIsGuided) {
  const test::TempDir dir;
  const std::optional<std::filesystem::path> blobby_off = test::cgal_mesh(dir, "blobby");
  if (!blobby_off)
    GTEST_SKIP() << test::kCgalArchive << " is missing or has no data/meshes/blobby.off (Debian package libcgal-demo)";
  const std::filesystem::path coarse = *blobby_off;
  // The finer mesh: each face split in four, written as OFF.
  save_mesh(subdivide_faces(load_mesh(coarse.string()).mesh, 2).mesh, (dir / "fine.off").string());
  for (const std::filesystem::path& mesh : {coarse, dir / "fine.off"}) {
    const Generated g = run(surface_knot(R"({"mesh": ")" + mesh.string() + R"("})", Vec3(-0.15, 0, 0.2),
                                         Vec3(0.15, 0, 0.2), 0.05, 60));
    const int nv = g.space->mesh().num_vertices();
    expect_guided_knot(g, fmt::format("blobby, {} vertices", nv), nv < 4000 ? 2 : 0);
  }
}

// bench/keyframe_topology_meshes.py's knot on a mesh: a source at p and a center at q
// trading places (32 frames, falloff 20).
std::string mesh_knot(const std::filesystem::path& mesh, const std::string& p, const std::string& q, double radius) {
  return R"({"tvf": 1, "domain": {"mesh": ")" + mesh.string() + R"("},
    "time": {"frames": 32, "range": [0, 1]}, "generator": "spacetime", "falloff": 20,
    "solver": {"region_radius": )" + fmt::format("{}", radius) + R"(, "keyframe_topology": "matched"},
    "keyframes": [
      {"t": 0, "elements": [{"kind": "singular", "type": "source", "at": )" + p + R"(},
                            {"kind": "singular", "type": "ccw_center", "at": )" + q + R"(}]},
      {"t": 1, "elements": [{"kind": "singular", "type": "source", "at": )" + q + R"(},
                            {"kind": "singular", "type": "ccw_center", "at": )" + p + R"(}]}]})";
}

// The knot on CGAL's mushroom (bench/keyframe_topology_meshes.py's scene: a source and a
// center 0.15 of the diagonal apart on the cap, trading places; the static solve adds a
// saddle). Bending one pair after the other chased its tail (300 rounds, the closest pair
// at 0.9996 of the separation), and the interval fell back as "the key frames' own
// collision" without trying the joint search, which routes the three and is guided: three
// singularities every frame, no saddle–node bifurcation. Routed without the phases (on
// surfaces the router had none), the source wound a whole turn round the saddle more than
// the center, so the guide could not keep their types: the center drifted into a focus and
// back with limit cycles (2 Hopf events) and the source weakened to a focus (trace/√det down
// to 0.79; a node's is 2). With the phases the three turn like a rigid body and the source
// stays a node (≥ 1.74 in every frame). The guide's node correction is then possible but
// turned single vertices six times the field's mean magnitude from frame to frame
// (coherence max/median 4.1, a saddle–node pair at t = 0.55), so it is not kept
// (PhaseCheck::accept). Since session 26 its far λ are averaged in time and it passes that
// bound (0.125 against 0.068 uncorrected), but the local correction is smoother (0.091) and
// kept; Shepard's blend, kept, left the center a focus in frames 7, 8, 12, 20 and 23
// (trace/√det 0.83 and −1.65 at 7 and 8) and the analysis found a Hopf event. The local
// correction (each node's λ near it alone, and within 1.5 edge lengths its own linear field
// scaled to G's magnitude) keeps the center a center, |trace|/√det ≤ 0.1 in every frame.
// Before session 22 it wandered −2.4 … 1.5 without limit cycles (a sink at one frame), and
// with the local correction but the scale 0 next to the first key frame (no value at a
// corner on the key frame's zero) up to 2.5.
TEST(KeyframeTopology, AKnotOnCGALsMushroomIsRoutedTogetherAndGuided) {
  const test::TempDir dir;
  const std::optional<std::filesystem::path> mushroom_off = test::cgal_mesh(dir, "mushroom");
  if (!mushroom_off)
    GTEST_SKIP() << test::kCgalArchive << " is missing or has no data/meshes/mushroom.off (Debian package libcgal-demo)";
  const Generated g =
      run(mesh_knot(*mushroom_off, "[0.226893, 0.000169333, 0.227341]", "[0.182076, 0.232276, 0.222321]", 0.0744));
  const KeyframeIntervalReport& r = g.report.keyframe_intervals.at(0);
  ASSERT_EQ(r.matched.size(), 3u);
  EXPECT_EQ(r.routing, "joint");
  EXPECT_TRUE(r.collision.empty()) << r.collision;
  EXPECT_TRUE(r.guided) << r.unguided_reason;
  EXPECT_TRUE(g.topology.bifurcations.empty());
  double center_most = 0;
  for (const auto& frame : g.topology.singularities) {
    EXPECT_EQ(frame.size(), 3u);
    // The source: the most repelling +1 singularity, trace/√det of its Jacobian; the
    // center: the other +1.
    std::vector<double> ratios;
    for (const Singularity& s : frame)
      if (s.index == 1) ratios.push_back(s.jacobian.trace() / std::sqrt(std::abs(s.jacobian.determinant())));
    ASSERT_EQ(ratios.size(), 2u);
    const double source = std::max(ratios[0], ratios[1]), center = std::min(ratios[0], ratios[1]);
    EXPECT_GT(source, 1.5) << "at t = " << (frame.empty() ? -1.0 : frame.front().t);
    EXPECT_LT(std::abs(center), 0.25) << "at t = " << (frame.empty() ? -1.0 : frame.front().t);
    center_most = std::max(center_most, std::abs(center));
  }
  const PeriodicOrbits orbits = find_periodic_orbits(g.space->bundle(), g.field, g.topology);
  EXPECT_TRUE(orbits.hopf.empty()) << orbits.hopf.size() << " Hopf events, the first at t = " << orbits.hopf.front().t;
  std::vector<double> c = g.topology.coherence;
  std::sort(c.begin(), c.end());
  const double ratio = c.back() / c[c.size() / 2];
  EXPECT_LT(ratio, 2.5);
  std::printf("  mushroom: routed %s, %zu bifurcations, %zu Hopf events, %zu paths, coherence max/median %.2f, "
              "the center's |trace|/√det at most %.3f\n",
              r.routing.c_str(), g.topology.bifurcations.size(), orbits.hopf.size(), g.topology.paths.size(), ratio,
              center_most);
}

// The knot on CGAL's bear (bench/keyframe_topology_meshes.py's scene). The two key frames'
// static solves have a saddle and a focus by the head in one and by the body in the other:
// matched by type they were carried 0.9 and 1.2 across the bear, through the knot's paths,
// and the pairwise router pushed a saddle to and fro between two paths until its detour
// (1.15 on a 0.27 path) was walked across the body and jumped: not guided, 4 events not
// asked for. Now no pairwise detour goes farther than twice the separation (the joint
// routing then finds the collision), and the unguided interval is planned again with the
// static solve's own carried within stability_reach alone (the far two cancelled by the
// head, created by the body: the plan's two bifurcations): guided, every saddle–node event
// the planned one. Release only (6 s; minutes under the sanitizers).
TEST(KeyframeTopology, AKnotOnCGALsBearIsGuidedWithItsFarSingularitiesPaired) {
  if (kSanitize) GTEST_SKIP() << "release only (a 13,826-vertex mesh)";
  const test::TempDir dir;
  const std::optional<std::filesystem::path> bear_off = test::cgal_mesh(dir, "bear");
  if (!bear_off)
    GTEST_SKIP() << test::kCgalArchive << " is missing or has no data/meshes/bear.off (Debian package libcgal-demo)";
  const Generated g =
      run(mesh_knot(*bear_off, "[-0.362001, 0.103117, 0.079689]", "[-0.309168, -0.239971, 0.193769]", 0.1123));
  const KeyframeIntervalReport& r = g.report.keyframe_intervals.at(0);
  EXPECT_EQ(r.matched.size(), 10u);
  ASSERT_EQ(r.cancelled.size(), 1u);
  ASSERT_EQ(r.created.size(), 1u);
  EXPECT_TRUE(r.collision.empty()) << r.collision;
  EXPECT_TRUE(r.guided) << r.unguided_reason;
  const double diameter = g.space->diameter();
  // Only the designed two are carried farther than a quarter of the diameter.
  for (const auto& m : r.matched) {
    if (m.type == SingularityType::source || m.type == SingularityType::center) continue;
    EXPECT_LE((m.from - m.to).norm(), 0.25 * diameter) << to_string(m.type) << " carried";
  }
  // The saddle–node events are the plan's two: the pair cancelled at the head and the
  // pair created by the body, each near where the plan puts it.
  ASSERT_EQ(g.topology.bifurcations.size(), 2u);
  // No Hopf event (one on the carried center at t = 0.041 before session 22), and the
  // designed center, followed from its first place frame by frame (the nearest +1
  // singularity), a center in every frame: |trace|/√det ≤ 0.04 (up to 1.37 before the
  // local correction).
  const PeriodicOrbits orbits = find_periodic_orbits(g.space->bundle(), g.field, g.topology);
  EXPECT_TRUE(orbits.hopf.empty()) << orbits.hopf.size() << " Hopf events, the first at t = " << orbits.hopf.front().t;
  double center_most = 0;
  for (const Singularity* nearest : node_followed_from(g.topology, Vec3(-0.309168, -0.239971, 0.193769))) {
    ASSERT_NE(nearest, nullptr);
    const double ratio = nearest->jacobian.trace() / std::sqrt(std::abs(nearest->jacobian.determinant()));
    EXPECT_LT(std::abs(ratio), 0.25) << "at t = " << nearest->t;
    center_most = std::max(center_most, std::abs(ratio));
  }
  // The smoother of the two node corrections is kept (PhaseCheck::accept): here the local
  // one (roughness 0.136), change max/median 1.46; Shepard's blend (0.166), which also passes
  // since its far λ are averaged in time (session 26), peaks mid-interval at 1.76.
  std::vector<double> c = g.topology.coherence;
  std::sort(c.begin(), c.end());
  const double ratio = c.back() / c[c.size() / 2];
  EXPECT_LT(ratio, 1.6);
  std::printf("  bear: routed %s, %zu matched, bifurcations at t = %.3g and %.3g, the center's |trace|/√det at most "
              "%.3f, change max/median %.2f\n",
              r.routing.c_str(), r.matched.size(), g.topology.bifurcations[0].t, g.topology.bifurcations[1].t,
              center_most, ratio);
}

// The knot on CGAL's head (bench/keyframe_topology_meshes.py's scene: its two points are
// vertices, as any point typed from the mesh's vertex list). F₀ / (z − p(t₀)) is 0/0 on
// such a vertex, and the guide left it to the solve, whose temporal term pulled it towards
// the key frame's zero there: the solved frames held a repelling focus and a saddle round
// it for five frames (6 saddle–node events not asked for, t = 0.69 … 0.85) that the
// acceptance check, which reads a free vertex as its neighbours' sum, had not seen. Now the
// guide fixes it too (the affine fit of its neighbours' values): the check reads what the
// solve gets, and the analysis finds the three carried singularities in every frame and
// no event.
TEST(KeyframeTopology, AKnotOnAVertexOfCGALsHeadHasNoEventNotAskedFor) {
  const test::TempDir dir;
  const std::optional<std::filesystem::path> head_off = test::cgal_mesh(dir, "head");
  if (!head_off)
    GTEST_SKIP() << test::kCgalArchive << " is missing or has no data/meshes/head.off (Debian package libcgal-demo)";
  const Generated g = run(mesh_knot(*head_off, "[0.79751, 8.532, -4.39904]", "[-0.68164, 12.122, -4.20598]", 1.2067));
  const KeyframeIntervalReport& r = g.report.keyframe_intervals.at(0);
  ASSERT_EQ(r.matched.size(), 3u);
  EXPECT_TRUE(r.guided) << r.unguided_reason;
  for (size_t f = 0; f < g.topology.singularities.size(); ++f) EXPECT_EQ(g.topology.singularities[f].size(), 3u) << "frame " << f;
  EXPECT_TRUE(g.topology.bifurcations.empty()) << g.topology.bifurcations.size() << " saddle–node events, the first at t = "
                                               << g.topology.bifurcations.front().t;
  const PeriodicOrbits orbits = find_periodic_orbits(g.space->bundle(), g.field, g.topology);
  EXPECT_TRUE(orbits.hopf.empty()) << orbits.hopf.size() << " Hopf events";
}

// A knot of three paths: a source and a center trading places across the saddle the
// static solve puts between them (matched by type: the saddle stays, the other two cross
// it and each other half way).
std::string knot_scene(int n, int frames, const std::string& solver_extra = "") {
  return trading_scene(n, frames, "ccw_center", solver_extra);
}

// The plan of a scene's key-frame topology (the generator makes the same one).
struct Planned {
  Scene scene;
  std::unique_ptr<DesignSpace> space;
  std::unique_ptr<KeyframeTopologyPlan> plan;
};
Planned plan_of(const std::string& text, const std::function<void()>& checkpoint = {}) {
  Planned p{parse_scene(text, "s"), nullptr, nullptr};
  p.space = make_design_space(p.scene);
  const ConnectionLaplacian lap = connection_laplacian(p.space->bundle(), LaplacianWeights::cotan);
  std::vector<std::vector<cplx>> keys;
  for (size_t k = 0; k < p.scene.keyframes.size(); ++k) keys.push_back(keyframe_field(*p.space, p.scene, k, lap));
  p.plan = std::make_unique<KeyframeTopologyPlan>(*p.space, p.scene, keys, checkpoint);
  return p;
}

// The plan calls its checkpoint between its steps, also inside the router and the surface
// guide's check (a frame counted, a joint-routing evaluation), and a checkpoint that throws
// stops it there: generation passes its cancellation check, so the designer's newer scene
// does not wait for a plan it made pointless (CGAL's man knot: its plan ran 11 s to its
// end; now stopped within 0.35 s of the newest call, docs/benchmarks.md). The checkpoint
// changes nothing of the plan. The knot of AKnotOnASphereIsGuided (subdivisions 3).
TEST(KeyframeTopology, ThePlanStopsAtItsCheckpoint) {
  const double z = std::sqrt(0.75);
  const std::string text =
      surface_knot(R"({"sphere": {"subdivisions": 3, "radius": 1}})", Vec3(-0.5, 0, z), Vec3(0.5, 0, z), 0.15, 8);
  const Planned plain = plan_of(text);
  ASSERT_TRUE(plain.plan->intervals().at(0).guided);
  int calls = 0;
  const Planned counted = plan_of(text, [&] { ++calls; });
  EXPECT_EQ(keyframe_intervals_json(counted.plan->intervals()), keyframe_intervals_json(plain.plan->intervals()));
  // At least once a frame the surface guide's check makes (the 30 between the key frames).
  EXPECT_GE(calls, 30);
  struct Stop {};
  for (const int at : {1, calls / 2, calls}) {
    int seen = 0;
    EXPECT_THROW(plan_of(text, [&] {
                   if (++seen == at) throw Stop{};
                 }),
                 Stop)
        << "call " << at << " of " << calls;
    EXPECT_EQ(seen, at);
  }
}

// The knot on CGAL's cow (bench/keyframe_topology_meshes.py's scene): the static solves put
// saddles on thin parts (a fold, a tip), where the mesh is finer (faces of 0.3 mean edge lengths)
// and the far side of the thin part lies within the tube's width in space, so neither chart
// fitted ("the surface folds over the chart of the saddle's path … within an edge length of
// it"). The tubes are now narrowed down to the edge length where the path runs and, where
// the chord tube is no disk, measured along the surface: every path has its chart, and the
// guide is built and checked (the cow still falls back, on the check: its frames hold
// other singularities than the plan's at 3 of 30). Release only (4 s).
// Its first wrong frame (t = 0.452) falls while the cancelled pair is its template's two
// zeros, no longer its tracks: the reason counts them among the plan's (26, not the 24
// tracks) and names an extra singularity that is not one of them (it named the pair's
// saddle, 1.2 region radii from every track, before session 38), and the size of its face.
TEST(KeyframeTopology, TheSaddlesOnCGALsCowsThinPartsHaveTheirCharts) {
  if (kSanitize) GTEST_SKIP() << "release only (a knot with 26 paths)";
  const test::TempDir dir;
  const std::optional<std::filesystem::path> cow_off = test::cgal_mesh(dir, "cow");
  if (!cow_off) GTEST_SKIP() << test::kCgalArchive << " is missing or has no data/meshes/cow.off (Debian package libcgal-demo)";
  const Planned p = plan_of(mesh_knot(*cow_off, "[0.0160599, 0.0323183, 0.122059]", "[-0.177465, 0.0578006, 0.148737]", 0.0609));
  const KeyframeIntervalReport& r = p.plan->intervals().at(0);
  EXPECT_TRUE(r.collision.empty()) << r.collision;
  EXPECT_EQ(r.unguided_reason.find("folds over the chart"), std::string::npos) << r.unguided_reason;
  EXPECT_EQ(r.unguided_reason.find("could not be built"), std::string::npos) << r.unguided_reason;
  std::printf("  cow: %zu matched, %s\n", r.matched.size(), r.guided ? "guided" : r.unguided_reason.c_str());
  if (r.guided) return;
  ASSERT_EQ(r.cancelled.size(), 1u);
  EXPECT_NE(r.unguided_reason.find(fmt::format("singularities where the plan carries {}; ", r.matched.size() + 2)),
            std::string::npos)
      << r.unguided_reason;
  const size_t extra = r.unguided_reason.find("an extra ");
  ASSERT_NE(extra, std::string::npos) << r.unguided_reason;
  const size_t open = r.unguided_reason.find(" at (", extra);
  ASSERT_NE(open, std::string::npos) << r.unguided_reason;
  Vec3 at;
  ASSERT_EQ(std::sscanf(r.unguided_reason.c_str() + open, " at (%lf, %lf, %lf)", &at.x(), &at.y(), &at.z()), 3)
      << r.unguided_reason;
  // The extra lies in one of the cow's coarse faces (2.8 mean edge lengths long), and the
  // reason says so.
  EXPECT_NE(r.unguided_reason.find(" mean edge lengths long)"), std::string::npos) << r.unguided_reason;
  const KeyframeIntervalReport::Pair& pair = r.cancelled[0];
  for (const Vec3& q : {pair.at, pair.node, pair.saddle})
    EXPECT_GT((at - q).norm(), 0.02) << r.unguided_reason << " names the cancelled pair's template";
  // The same in keyframe_topology.json's "first_wrong" (for tools and the designer), which
  // reads back as it was.
  ASSERT_TRUE(r.first_wrong.has_value());
  const KeyframeIntervalReport::WrongFrame& w = *r.first_wrong;
  EXPECT_TRUE(w.extra);
  EXPECT_EQ(w.planned, static_cast<int>(r.matched.size() + 2));
  EXPECT_GT(w.found, w.planned);
  EXPECT_LT((w.at - at).norm(), 1e-3);
  EXPECT_GE(w.face_edges, 2.0);
  EXPECT_TRUE(std::isfinite(w.distance));
  const nlohmann::json j = keyframe_intervals_json(p.plan->intervals());
  ASSERT_TRUE(j[0].contains("first_wrong"));
  EXPECT_EQ(j[0]["first_wrong"]["found"], w.found);
  EXPECT_EQ(j[0]["first_wrong"]["type"], to_string(w.type));
  const std::optional<std::vector<KeyframeIntervalReport>> back = keyframe_intervals_from_json({{"intervals", j}});
  ASSERT_TRUE(back.has_value());
  ASSERT_TRUE(back->at(0).first_wrong.has_value());
  const KeyframeIntervalReport::WrongFrame& b = *back->at(0).first_wrong;
  EXPECT_EQ(b.t, w.t);
  EXPECT_EQ(b.found, w.found);
  EXPECT_EQ(b.planned, w.planned);
  EXPECT_EQ(b.type, w.type);
  EXPECT_EQ(b.nearest_type, w.nearest_type);
  EXPECT_EQ(b.at, w.at);
  EXPECT_EQ(b.distance, w.distance);
  EXPECT_EQ(b.face_edges, w.face_edges);
}

// keyframe_topology.json's "middle_keyframe" (the key frame offered where a node turns a
// whole turn; Example26KnotOnASphereIsGuided makes and takes one) is a key frame in the
// scene's form, and reads back as it was, an element given by its Jacobian too.
TEST(KeyframeTopology, TheOfferedMiddleKeyFrameReadsBack) {
  KeyframeIntervalReport r;
  r.t1 = 1;
  r.guided = true;
  KeyframeIntervalReport::MiddleKeyframe m;
  m.keyframe.t = 15.0 / 31;
  KeyframeElement source;
  source.kind = "singular";
  source.type = SingularType::source;
  source.jacobian = jacobian_of(SingularType::source);
  source.at = Vec3(0.11, 0.125, 0.985);
  KeyframeElement custom = source;
  custom.type.reset();
  custom.jacobian << 0.5, -1, 1, 0.5;
  custom.at = Vec3(-0.057, -0.142, 0.987);
  m.keyframe.elements = {source, custom};
  m.from = {0, 1};
  m.to = {1, -1};
  r.middle_keyframe = m;
  const nlohmann::json j = keyframe_intervals_json({r});
  const nlohmann::json& written = j[0].at("middle_keyframe");
  EXPECT_EQ(written.at("keyframe").at("elements")[0].at("type"), "source") << written;
  EXPECT_TRUE(written.at("keyframe").at("elements")[1].contains("jacobian")) << written;
  EXPECT_EQ(written.at("keyframe").at("streamlines"), nlohmann::json::array()) << written;
  const std::optional<std::vector<KeyframeIntervalReport>> back = keyframe_intervals_from_json({{"intervals", j}});
  ASSERT_TRUE(back.has_value());
  ASSERT_TRUE(back->at(0).middle_keyframe.has_value());
  const KeyframeIntervalReport::MiddleKeyframe& b = *back->at(0).middle_keyframe;
  EXPECT_EQ(b.keyframe.t, m.keyframe.t);
  ASSERT_EQ(b.keyframe.elements.size(), 2u);
  EXPECT_EQ(b.keyframe.elements[0].type, SingularType::source);
  EXPECT_EQ(b.keyframe.elements[0].at, source.at);
  EXPECT_FALSE(b.keyframe.elements[1].type.has_value());
  EXPECT_EQ(b.keyframe.elements[1].jacobian, custom.jacobian);
  EXPECT_EQ(b.from, m.from);
  EXPECT_EQ(b.to, m.to);
  // Without one the key is absent.
  r.middle_keyframe.reset();
  EXPECT_FALSE(keyframe_intervals_json({r})[0].contains("middle_keyframe"));
}

// Two paths on a part of a closed surface thinner than the separation cannot be kept that
// far apart in space by any detour walked along the surface, and the collision says so,
// with the part's width:
// a source and a center trading places along a torus's tube 0.1 thick, the separation
// 0.2. It said "no detour inside the domain", which on a closed surface reads as a bug
// (CGAL's man: a knot along an arm 0.045 thick, the separation 0.11).
TEST(KeyframeTopology, PathsAlongAPartThinnerThanTheSeparationAreReportedSo) {
  const test::TempDir dir;
  save_mesh(make_torus(96, 12, 1.0, 0.05), (dir / "torus.off").string());
  const auto on_ring = [](double u) { return fmt::format("[{:.17g}, {:.17g}, 0]", 1.05 * std::cos(u), 1.05 * std::sin(u)); };
  const Planned p = plan_of(mesh_knot(dir / "torus.off", on_ring(0.0), on_ring(0.4), 0.1));
  const KeyframeIntervalReport& r = p.plan->intervals().at(0);
  EXPECT_FALSE(r.guided);
  EXPECT_NE(r.collision.find("no detour along the surface keeps them 0.2 apart"), std::string::npos) << r.collision;
  // ... and names the part's width: the tube's cross-section where they pass, 0.1 across
  // (its 12-gon's widest chord, cut between its vertices).
  std::smatch across;
  std::regex_search(r.collision, across, std::regex("on a part of the surface ([0-9.e-]+) across"));
  ASSERT_EQ(across.size(), 2u) << r.collision;
  EXPECT_NEAR(std::stod(across[1].str()), 0.1, 0.005) << r.collision;
}

// Between guided key frames every vertex is fixed to a finite value, also the key frames'
// zeros placed on vertices (the sphere knot's source and center on two of its vertices):
// none is left to the solve, which the acceptance check would not have read; and the
// frames hold the plan's zeros alone, where it carries them. (The affine fit at such a
// vertex rather than its neighbours' mean is not told apart here: on this regular mesh, and
// on the same sphere with its vertices moved about, both pass; on CGAL's cow the mean made
// the check see a focus beside each knot point at the first frame, docs/benchmarks.md.)
TEST(KeyframeTopology, TheSurfaceGuideFixesAKeyFramesZeroOnAVertex) {
  const std::unique_ptr<DesignSpace> sphere = make_design_space(parse_scene(
      R"({"tvf": 1, "domain": {"sphere": {"subdivisions": 3, "radius": 1}}, "time": {"frames": 2, "range": [0, 1]}})", "s"));
  const Mesh& mesh = sphere->mesh();
  auto vertex_near = [&](const Vec3& x) {
    int best = 0;
    for (int v = 1; v < mesh.num_vertices(); ++v)
      if ((mesh.position(v) - x).norm() < (mesh.position(best) - x).norm()) best = v;
    const Vec3& p = mesh.position(best);
    return fmt::format("[{:.17g}, {:.17g}, {:.17g}]", p.x(), p.y(), p.z());
  };
  const double z = std::sqrt(0.75);
  const std::string a = vertex_near(Vec3(-0.5, 0, z)), b = vertex_near(Vec3(0.5, 0, z));
  const std::string text = R"({"tvf": 1, "domain": {"sphere": {"subdivisions": 3, "radius": 1}},
    "time": {"frames": 32, "range": [0, 1]}, "generator": "spacetime", "falloff": 8,
    "solver": {"region_radius": 0.15, "keyframe_topology": "matched"},
    "keyframes": [
      {"t": 0, "elements": [{"kind": "singular", "type": "source", "at": )" + a + R"(},
                            {"kind": "singular", "type": "ccw_center", "at": )" + b + R"(}]},
      {"t": 1, "elements": [{"kind": "singular", "type": "source", "at": )" + b + R"(},
                            {"kind": "singular", "type": "ccw_center", "at": )" + a + R"(}]}]})";
  const Planned p = plan_of(text);
  ASSERT_TRUE(p.plan->intervals().at(0).guided) << p.plan->intervals().at(0).unguided_reason;
  const auto nv = static_cast<size_t>(p.space->mesh().num_vertices());
  const double d = p.scene.falloff / (p.space->diameter() * p.space->diameter());
  const double h = p.space->mesh().mean_edge_length();
  for (int f = 1; f + 1 < p.scene.time.frames; ++f) {
    std::vector<char> fixed(nv, 0);
    std::vector<cplx> values(nv, cplx(0, 0));
    p.plan->constrain(*p.space, p.scene, p.scene.time.time(f), d, fixed, values);
    size_t free = 0, bad = 0;
    for (size_t v = 0; v < nv; ++v) {
      free += !fixed[v];
      bad += fixed[v] && !(std::isfinite(values[v].real()) && std::isfinite(values[v].imag()));
    }
    EXPECT_EQ(free, 0u) << "frame " << f;
    EXPECT_EQ(bad, 0u) << "frame " << f;
    // And those frames hold the plan's zeros alone, each within half an edge of where the
    // plan carries it (also at the first frames, where the carried zero is within an edge
    // of the vertex it left).
    const std::vector<Singularity> found = find_singularities(p.space->bundle(), values);
    const std::vector<Vec3> carried = p.plan->carried(p.scene.time.time(f));
    EXPECT_EQ(found.size(), carried.size()) << "frame " << f;
    for (const Vec3& c : carried) {
      double nearest = std::numeric_limits<double>::infinity();
      for (const Singularity& s : found) nearest = std::min(nearest, (s.position - c).norm());
      EXPECT_LT(nearest, 0.5 * h) << "frame " << f;
    }
  }
}

// Over the frames between the key frames: the farthest a carried singularity is from the
// analysed field's nearest singularity, and the closest two of those nearest ones come.
std::pair<double, double> followed(const Generated& g, const Planned& p) {
  double worst = 0, closest = std::numeric_limits<double>::infinity();
  for (int f = 1; f + 1 < g.field.frames(); ++f) {
    const auto& frame = g.topology.singularities[static_cast<size_t>(f)];
    std::vector<Vec3> found;
    for (const Vec3& c : p.plan->carried(p.scene.time.time(f))) {
      double best = std::numeric_limits<double>::infinity();
      Vec3 at = c;
      for (const Singularity& s : frame)
        if ((s.position - c).norm() < best) best = (s.position - c).norm(), at = s.position;
      worst = std::max(worst, best);
      found.push_back(at);
    }
    for (size_t a = 0; a < found.size(); ++a)
      for (size_t b = a + 1; b < found.size(); ++b) closest = std::min(closest, (found[a] - found[b]).norm());
  }
  return {worst, closest};
}

// Routed one pair at a time the bends chase each other (at 33², 65² and 129² the paths
// stayed straight with a warning and the source and the center merged on the saddle);
// routed together, the source passes below the saddle and the center above, the three
// turning round each other like a rigid body (the phases of the product model kept), and
// every frame of the analysed field has the three where the plan carries them, 0.3 apart,
// and nothing else: the guide field between the key frames has no other zero (4, 12 and
// 22 bifurcations at 33², 65² and 129² before it), so no bifurcation and three paths.
TEST(KeyframeTopology, AKnotOfThreePathsIsRoutedTogether) {
  // Under the sanitizers 33² alone (65² runs the same code paths at four times the cost).
  for (const int n : kGridSides) {
    if (kSanitize && n > 33) continue;
    const std::string text = knot_scene(n, 32);
    const Generated g = run(text);
    const KeyframeIntervalReport& r = g.report.keyframe_intervals.at(0);
    ASSERT_EQ(r.matched.size(), 3u) << n;
    EXPECT_EQ(r.collision, "") << n;
    EXPECT_EQ(r.routing, "joint") << n;
    EXPECT_TRUE(g.report.warnings.empty()) << n;
    EXPECT_GE(r.closest_approach, 0.3 * (1 - 1e-9)) << n;
    for (const auto& m : r.matched) EXPECT_GT(m.detour, 0.05) << n;
    const Planned p = plan_of(text);
    const auto [worst, closest] = followed(g, p);
    std::printf("  knot %d²: routed %s, carried singularities found within %.2g, kept %.4f apart; %zu bifurcations, "
                "%zu paths\n",
                n, r.routing.c_str(), worst, closest, g.topology.bifurcations.size(), g.topology.paths.size());
    // The nodes' regions hold their linear fields, whose zeros are the carried points; the
    // saddle is the guide field's own zero, found by the analysis's linear interpolation
    // within O(h²), h = 2 / (n − 1) (0.0052, 0.0015, 0.00031 measured).
    const double h = 2.0 / (n - 1);
    EXPECT_LT(worst, 2 * h * h) << n;
    EXPECT_GE(closest, 0.3 - 4 * h * h) << n;
    EXPECT_TRUE(r.guided) << n;
    EXPECT_EQ(g.topology.bifurcations.size(), 0u) << n;
    EXPECT_EQ(g.topology.paths.size(), 3u) << n;
    // The paths start and end on the key frames' singularities.
    for (const Singularity& s : g.topology.singularities.front()) {
      double d = 1e9;
      for (const auto& m : r.matched) d = std::min(d, (m.from - s.position).norm());
      EXPECT_LT(d, 1e-9) << n;
    }
  }
  // Straight, the source and the center would run into the saddle: the planned paths come
  // closer than 0.3, and the guide cannot be built, so the interval falls back to "free"
  // (carried straight, the regions made the singularities meet on the way).
  const std::string straight_text = knot_scene(33, 32, R"(, "path_separation": 0)");
  const Generated straight = run(straight_text);
  const KeyframeIntervalReport& r = straight.report.keyframe_intervals.at(0);
  std::printf("  knot straight: closest planned %.4f, %s (%s), %zu bifurcations, %zu paths\n", r.closest_approach,
              r.guided ? "guided" : "not guided", r.unguided_reason.c_str(), straight.topology.bifurcations.size(),
              straight.topology.paths.size());
  EXPECT_LT(r.closest_approach, 0.3);
  EXPECT_TRUE(r.fallback);
}

// The knot's carried center is an exact rotation in every frame (|Re λ / Im λ| < 1e-4):
// its trace's sign is rounding, and at 33² × 60 frames it flipped between the last two
// frames beside an attracting cycle of the guide's nonlinear part that had ended 4 frames
// before. The analysis reported a supercritical Hopf event at t = 1, and the design check
// one bifurcation not asked for; a Hopf event needs a focus of each stability
// (periodic_orbits.h), and the center is a center throughout.
TEST(KeyframeTopology, TheKnotsCarriedCenterIsNoHopfEvent) {
  const Generated g = run(knot_scene(33, 60));
  ASSERT_TRUE(g.report.keyframe_intervals.at(0).guided);
  const PeriodicOrbits orbits = find_periodic_orbits(g.space->bundle(), g.field, g.topology);
  EXPECT_FALSE(orbits.orbits.empty());  // the cycles are there; they are no Hopf event
  EXPECT_TRUE(orbits.hopf.empty()) << orbits.hopf.size() << " Hopf events, the first at t = " << orbits.hopf[0].t;
}

// A sink crossing the place where a saddle and a source are cancelled, while the template
// holds: the template is an obstacle, so the sink's path goes round it (pairwise routing
// knew only paths, and led the sink through the template).
TEST(KeyframeTopology, PathsGoRoundTheTemplatesOfCancelledPairs) {
  const std::string text = R"({"tvf": 1, "domain": {"grid": {"size": [33, 33], "min": [-1, -1], "max": [1, 1]}},
    "time": {"frames": 41, "range": [0, 1]}, "generator": "spacetime", "falloff": 8,
    "solver": {"region_radius": 0.15, "keyframe_topology": "matched"},
    "keyframes": [
      {"t": 0, "elements": [{"kind": "singular", "type": "sink", "at": [0, -0.7]},
                            {"kind": "singular", "type": "saddle", "at": [-0.2, 0]},
                            {"kind": "singular", "type": "source", "at": [0.2, 0]}]},
      {"t": 1, "elements": [{"kind": "singular", "type": "sink", "at": [0, 0.7]}]}]})";
  const Generated g = run(text);
  const KeyframeIntervalReport& r = g.report.keyframe_intervals.at(0);
  ASSERT_EQ(r.cancelled.size(), 1u);
  EXPECT_EQ(r.collision, "");
  EXPECT_EQ(r.routing, "joint");
  const Vec3 at = r.cancelled[0].at;
  const double tau = 0.25 * 0.5;
  // The plan: every path that is not the pair's keeps the separation from the template's
  // centre while it holds.
  const Planned p = plan_of(text);
  double planned = std::numeric_limits<double>::infinity();
  for (int k = 0; k <= 64; ++k) {
    const double t = 0.5 - tau + 2 * tau * k / 64.0;
    for (const Vec3& c : p.plan->carried(t)) planned = std::min(planned, (c - at).norm());
  }
  double found = std::numeric_limits<double>::infinity();
  for (size_t f = 0; f < g.topology.singularities.size(); ++f) {
    const double t = p.scene.time.time(static_cast<int>(f));
    if (t < 0.5 - tau || t > 0.5 + tau) continue;
    for (const Singularity& s : g.topology.singularities[f])
      if (s.type == SingularityType::sink) found = std::min(found, (s.position - at).norm());
  }
  std::printf("  template obstacle: planned %.4f, nearest sink found %.4f from the template, %zu bifurcations (%zu "
              "planned)\n",
              planned, found, g.topology.bifurcations.size(), r.cancelled.size());
  EXPECT_GE(planned, 0.3 * (1 - 1e-6));
  EXPECT_GE(r.closest_approach, 0.25);
  // The planned cancellation and nothing else (10 through the template, 6 round it, before
  // the guide field).
  EXPECT_EQ(g.topology.bifurcations.size(), r.cancelled.size());
}

}  // namespace
}  // namespace tvf

namespace tvf {
namespace {

// A node that changes stability between key frames (issue 20's last resort): a source at
// one key frame where the next has a sink nearby, beside a center both key frames hold (on
// the plane; on a sphere the source at the north pole, the center at the south). Neither type
// nor stability matches and no saddle is left to pair them with, so only the last resort
// carries them: the interval is guided, its analysis has no saddle–node bifurcation, each
// frame the key frames' singularities (Poincaré–Hopf's sum), and the carried node turns
// from repelling to attracting through a center (its index +1 all the way).
std::string stability_scene(const std::string& domain, const std::string& k0, const std::string& k1) {
  return R"({"tvf": 1, "domain": )" + domain + R"(,
    "time": {"frames": 32, "range": [0, 1]}, "generator": "spacetime", "falloff": 8,
    "solver": {"region_radius": 0.15, "keyframe_topology": "matched"},
    "keyframes": [{"t": 0, "elements": [)" + k0 + R"(]}, {"t": 1, "elements": [)" + k1 + "]}]}";
}

std::string planar_stability_scene(int n) {
  const std::string center = R"({"kind": "singular", "type": "ccw_center", "at": [0.4, 0.3]})";
  return stability_scene(R"({"grid": {"size": [)" + std::to_string(n) + ", " + std::to_string(n) +
                             R"(], "min": [-1, -1], "max": [1, 1]}})",
                         R"({"kind": "singular", "type": "source", "at": [-0.4, -0.3]}, )" + center,
                         R"({"kind": "singular", "type": "sink", "at": [-0.3, -0.35]}, )" + center);
}

std::string sphere_stability_scene(int sub) {
  return stability_scene(R"({"sphere": {"subdivisions": )" + std::to_string(sub) + R"(, "radius": 1}})",
                         R"({"kind": "singular", "type": "source", "at": [0, 0, 1]},
                            {"kind": "singular", "type": "ccw_center", "at": [0, 0, -1]})",
                         R"({"kind": "singular", "type": "sink", "at": [0.2, 0, 0.98]},
                            {"kind": "singular", "type": "ccw_center", "at": [0, 0, -1]})");
}

void expect_stability_carried(const Generated& g, const std::string& what) {
  const KeyframeIntervalReport& r = g.report.keyframe_intervals.at(0);
  EXPECT_TRUE(r.guided) << what;
  EXPECT_TRUE(r.created.empty() && r.cancelled.empty() && r.unpaired_first.empty() && r.unpaired_second.empty())
      << what;
  int changes = 0;
  for (const auto& m : r.matched) {
    const bool flips = (m.type == SingularityType::source || m.type == SingularityType::repelling_focus) !=
                       (m.to_type == SingularityType::source || m.to_type == SingularityType::repelling_focus);
    if (flips) {
      ++changes;
      // The carried node, every frame: the singularity nearest its straight path is a +1.
      for (size_t f = 0; f < g.topology.singularities.size(); ++f) {
        const double s = static_cast<double>(f) / static_cast<double>(g.topology.singularities.size() - 1);
        const Vec3 p = m.from + s * s * (3 - 2 * s) * (m.to - m.from);
        const auto& frame = g.topology.singularities[f];
        ASSERT_FALSE(frame.empty()) << what;
        const auto& near = *std::min_element(frame.begin(), frame.end(), [&](const auto& x, const auto& y) {
          return (x.position - p).norm() < (y.position - p).norm();
        });
        EXPECT_EQ(near.index, 1) << what << ", frame " << f;
        EXPECT_GT(near.jacobian.determinant(), 0) << what << ", frame " << f;
        EXPECT_LT((near.position - p).norm(), 0.1) << what << ", frame " << f;
      }
    }
  }
  EXPECT_GE(changes, 1) << what;
  const size_t n = r.matched.size();
  const int sum = [&] {
    int s = 0;
    for (const Singularity& x : g.topology.singularities.front()) s += x.index;
    return s;
  }();
  for (size_t f = 0; f < g.topology.singularities.size(); ++f) {
    int s = 0;
    for (const Singularity& x : g.topology.singularities[f]) s += x.index;
    EXPECT_EQ(s, sum) << what << ", frame " << f;
    EXPECT_EQ(g.topology.singularities[f].size(), n) << what << ", frame " << f;
  }
  const double turn = worst_mean_turn(g, 3 * g.space->mesh().mean_edge_length());
  std::printf("  %s: %zu matched (%d changing stability), %zu bifurcations, %zu paths, %d type changes, worst mean "
              "turn per frame %.3f rad\n",
              what.c_str(), n, changes, g.topology.bifurcations.size(), g.topology.paths.size(),
              g.topology.stats.type_changes, turn);
  EXPECT_EQ(g.topology.bifurcations.size(), 0u) << what;
  // One path per match, split only where a type changes (none leaving through the
  // boundary), and coherent in time: no frame half a turn off the next.
  EXPECT_EQ(g.topology.paths.size(), n + static_cast<size_t>(g.topology.stats.type_changes)) << what;
  EXPECT_LT(turn, 0.25) << what;
  // The report says the type changes.
  const nlohmann::json j = keyframe_intervals_json(g.report.keyframe_intervals);
  int reported = 0;
  for (const auto& m : j[0]["matched"]) reported += m["type"] != m["to_type"];
  EXPECT_GE(reported, changes) << what;
}

// With the last resort off: 2 matched, 2 unpaired, not guided, 6 bifurcations at 33² and at
// 65², 2 at subdivisions 3 and 4; with α blended linearly instead of through its phase
// (det J = |α|² − |β|² through zero): 8 bifurcations at 33², extra zeros on the sphere.
// With α always the shorter way round, 65²'s last guided frame was half a turn off the key
// frame between the center and the changing node (the two nodes' phases ending a whole
// turn apart): a saddle path left through the boundary and another entered.
TEST(KeyframeTopology, ANodeThatChangesStabilityIsCarriedThroughACenter) {
  for (const int n : {33, 65}) expect_stability_carried(run(planar_stability_scene(n)), fmt::format("{}²", n));
}

TEST(KeyframeTopology, ANodeThatChangesStabilityOnASphereIsCarriedThroughACenter) {
  for (const int sub : {3, 4}) expect_stability_carried(run(sphere_stability_scene(sub)), fmt::format("sphere, subdivisions {}", sub));
}

// An interval that cannot be guided falls back to "free": carrying the matched
// singularities' regions alone leaves the band between them to the solve's blend of the
// two key frames, which made far more bifurcations than no constraint at all. On the
// narrow strip a sink and a source 0.15 apart at the first key frame cross head on (the
// paths cannot be kept apart: 35 bifurcations with the regions carried, 3 free). The
// matched field is then the free one, and the report says it fell back and why. (The
// surface case this had, paths whose straight segments run through the sphere's centre,
// is guided since the paths are curves on the surface: AMatchedPathOnASurfaceIsACurveOnIt.)
std::string held_strip_scene(const std::string& topology) {
  return R"({"tvf": 1, "domain": {"grid": {"size": [65, 9], "min": [-1, -0.125], "max": [1, 0.125]}},
    "time": {"frames": 17, "range": [0, 1]}, "generator": "spacetime", "falloff": 8,
    "solver": {"region_radius": 0.1, "keyframe_topology": ")" + topology + R"("},
    "keyframes": [
      {"t": 0, "elements": [{"kind": "singular", "type": "source", "at": [-0.5, 0]},
                            {"kind": "singular", "type": "sink", "at": [-0.35, 0]}]},
      {"t": 1, "elements": [{"kind": "singular", "type": "source", "at": [0.5, 0]},
                            {"kind": "singular", "type": "sink", "at": [-0.65, 0]}]}]})";
}

TEST(KeyframeTopology, AnIntervalThatCannotBeGuidedIsLeftFree) {
  struct Case {
    std::string what, matched, free, reason, also;
  };
  const std::vector<Case> cases{{"strip", held_strip_scene("matched"), held_strip_scene("free"),
                                 "two of its paths could not be kept apart (see collision)", ""}};
  for (const Case& c : cases) {
    const Generated matched = run(c.matched), free = run(c.free);
    const KeyframeIntervalReport& r = matched.report.keyframe_intervals.at(0);
    EXPECT_FALSE(r.guided) << c.what;
    EXPECT_TRUE(r.fallback) << c.what;
    EXPECT_EQ(r.unguided_reason.substr(0, c.reason.size()), c.reason) << c.what;
    EXPECT_NE(r.unguided_reason.find(c.also), std::string::npos) << c.what << ": " << r.unguided_reason;
    std::printf("  %s: %zu bifurcations matched (left free: %s), %zu free\n", c.what.c_str(),
                matched.topology.bifurcations.size(), r.unguided_reason.c_str(), free.topology.bifurcations.size());
    EXPECT_LE(matched.topology.bifurcations.size(), free.topology.bifurcations.size()) << c.what;
    // The key frames alone constrain the frames: the free solve's field.
    double worst = 0, largest = 0;
    for (int j = 0; j < free.field.frames(); ++j)
      for (int v = 0; v < free.space->mesh().num_vertices(); ++v) {
        worst = std::max(worst, std::abs(matched.field.at(j, v) - free.field.at(j, v)));
        largest = std::max(largest, std::abs(free.field.at(j, v)));
      }
    EXPECT_LE(worst, 1e-12 * largest) << c.what;
    const nlohmann::json j = keyframe_intervals_json(matched.report.keyframe_intervals)[0];
    EXPECT_EQ(j["fallback"], true) << c.what;
    EXPECT_EQ(j["unguided_reason"], r.unguided_reason) << c.what;
  }
  // A guided interval does not fall back and has no reason.
  const Generated guided = run(move_scene(33, R"(, "keyframe_topology": "matched")"));
  EXPECT_TRUE(guided.report.keyframe_intervals.at(0).guided);
  EXPECT_FALSE(guided.report.keyframe_intervals.at(0).fallback);
  EXPECT_FALSE(keyframe_intervals_json(guided.report.keyframe_intervals)[0].contains("unguided_reason"));
}

// A matched path on a surface is a curve on it (surface_curve: the shortest edge path
// straightened on the surface, a detour walked along it). On a sphere (subdivisions 3) a
// source and a sink trade antipodal places: their straight segments run through the
// sphere's centre, and their nearest surface points jumped across it (1.9, 12 edge
// lengths, between two of 257 samples), so the interval fell back to "free" (main before
// this: not guided, `unguided_reason` "the sink's path from … leaves the surface"). Now
// each path runs along a great circle through the two points, the two bent apart where
// they meet (they take the same one), and the interval is guided: every frame holds the
// two, and the analysis finds no bifurcation (none planned). The plan's points lie on the
// surface (the mesh is inscribed in the unit sphere: |p| within 2 % of 1; the straight
// segment's middle is the centre) and each path within an edge length of the great circle
// through its ends and its middle.
TEST(KeyframeTopology, AMatchedPathOnASurfaceIsACurveOnIt) {
  const std::string text = R"({"tvf": 1, "domain": {"sphere": {"subdivisions": 3, "radius": 1}},
    "time": {"frames": 32, "range": [0, 1]}, "generator": "spacetime", "falloff": 8,
    "solver": {"region_radius": 0.15, "keyframe_topology": "matched"},
    "keyframes": [
      {"t": 0, "elements": [{"kind": "singular", "type": "source", "at": [0.6, 0, 0.8]},
                            {"kind": "singular", "type": "sink", "at": [-0.6, 0, -0.8]}]},
      {"t": 1, "elements": [{"kind": "singular", "type": "source", "at": [-0.6, 0, -0.8]},
                            {"kind": "singular", "type": "sink", "at": [0.6, 0, 0.8]}]}]})";
  const Generated g = run(text);
  const KeyframeIntervalReport& r = g.report.keyframe_intervals.at(0);
  EXPECT_TRUE(r.guided) << r.unguided_reason;
  EXPECT_FALSE(r.fallback);
  ASSERT_EQ(r.matched.size(), 2u);
  EXPECT_TRUE(r.created.empty() && r.cancelled.empty());
  for (const auto& frame : g.topology.singularities) EXPECT_EQ(frame.size(), 2u);
  EXPECT_EQ(g.topology.bifurcations.size(), 0u);
  // The plan's paths: on the surface, each along one great circle.
  const Planned p = plan_of(text);
  const double h = p.space->mesh().mean_edge_length();
  double off_sphere = 0, off_circle = 0;
  std::vector<std::vector<Vec3>> at(2);
  for (int k = 1; k < 64; ++k) {
    const std::vector<Vec3> c = p.plan->carried(k / 64.0);
    ASSERT_EQ(c.size(), 2u);
    for (size_t i = 0; i < 2; ++i) at[i].push_back(c[i]), off_sphere = std::max(off_sphere, std::abs(c[i].norm() - 1));
  }
  for (const std::vector<Vec3>& path : at) {
    const Vec3 n = Vec3(0.6, 0, 0.8).cross(path[path.size() / 2]).normalized();
    for (const Vec3& x : path) off_circle = std::max(off_circle, std::abs(x.dot(n)));
  }
  std::printf("  antipodes, sphere 3: %s, %zu bifurcations; paths within %.3g of the sphere and %.3g of a great "
              "circle (h %.3g), detours %.3g and %.3g\n",
              r.routing.c_str(), g.topology.bifurcations.size(), off_sphere, off_circle, h, r.matched[0].detour,
              r.matched[1].detour);
  EXPECT_LT(off_sphere, 0.02);
  EXPECT_LT(off_circle, h);
}

// Through a middle key frame a carried singularity goes on in one direction (C¹): the path
// into it ends with the velocity the path out of it starts with, Bessel's tangent (the
// slope of the parabola through its three places), no more than twice the slower leg's
// speed. Until session 36 each path ran straight to the key frame and turned there: a
// source carried right, 0.6 in half the time, then up 0.6, turned 90° in one frame step
// (65², 33 frames) and arrived at 1.2 going right, left at 1.2 going up. Now it arrives and
// leaves at (0.6, 0.6) (the two legs' mean: equal times), and the analysis of the field
// finds it turning at most 15° between steps, with no bifurcation. A singularity that stays
// put on one side sets off from rest (the cap: the hold's speed is 0) and stays put there;
// one that turns back comes to rest at the key frame. The sphere's knot with its middle
// key frame (example 26) is C¹ through it too: the source's steps turned 81° at the key
// frame, now under 30° every frame.
std::string corner_scene(int n, const std::string& last) {
  return R"({"tvf": 1, "domain": {"grid": {"size": [)" + std::to_string(n) + ", " + std::to_string(n) +
         R"(], "min": [-1, -1], "max": [1, 1]}},
    "time": {"frames": 33, "range": [0, 1]}, "generator": "spacetime", "falloff": 8,
    "solver": {"region_radius": 0.15, "keyframe_topology": "matched"},
    "keyframes": [
      {"t": 0, "elements": [{"kind": "singular", "type": "source", "at": [-0.6, -0.4]},
                            {"kind": "singular", "type": "sink", "at": [0.6, 0.6]}]},
      {"t": 0.5, "elements": [{"kind": "singular", "type": "source", "at": [0.0, -0.4]},
                              {"kind": "singular", "type": "sink", "at": [0.6, 0.6]}]},
      {"t": 1, "elements": [{"kind": "singular", "type": "source", "at": )" +
         last + R"(},
                            {"kind": "singular", "type": "sink", "at": [0.6, 0.6]}]}]})";
}

// Generation says what it does before the frames' progress starts: each interval of the
// key-frame topology plan, in order (a terminal's progress line and the designer's status
// show it), then the frames.
TEST(KeyframeTopology, GenerationSaysWhichIntervalItPlans) {
  const Scene s = parse_scene(corner_scene(17, "[0.6, -0.4]"), "scene.json");
  const std::unique_ptr<DesignSpace> space = make_design_space(s);
  std::vector<std::string> said;
  GenerateOptions options;
  options.parallel = false;
  options.stage = [&](const std::string& what) { said.push_back(what); };
  options.progress = [&](int done, int total) {
    if (said.empty() || said.back().rfind("frames", 0) != 0) said.push_back(fmt::format("frames {}/{}", done, total));
  };
  generate(*space, s, options);
  ASSERT_GE(said.size(), 3u);
  EXPECT_EQ(said[0], "planning the topology between key frames (interval 1 of 2)");
  EXPECT_EQ(said[1], "planning the topology between key frames (interval 2 of 2)");
  EXPECT_EQ(said[2].rfind("frames ", 0), 0u) << said[2];
  // Free (no plan): nothing but frames.
  said.clear();
  Scene free = s;
  free.solver.keyframe_topology = KeyframeTopology::free;
  generate(*space, free, options);
  for (const std::string& w : said) EXPECT_EQ(w.rfind("frames ", 0), 0u) << w;
}

// The largest turn (degrees) between consecutive steps of the repelling node nearest the
// previous frame's, over the frames, and the frames where it was not found within 0.1.
std::pair<double, int> largest_step_turn(const Topology& topo, Vec3 at) {
  std::vector<Vec3> path;
  int lost = 0;
  for (const auto& frame : topo.singularities) {
    double best = 0.1;
    const Singularity* found = nullptr;
    for (const Singularity& s : frame)
      if ((s.type == SingularityType::source || s.type == SingularityType::repelling_focus) &&
          (s.position - at).norm() < best)
        best = (s.position - at).norm(), found = &s;
    if (!found) {
      ++lost;
      continue;
    }
    at = found->position;
    path.push_back(at);
  }
  double worst = 0;
  for (size_t k = 0; k + 2 < path.size(); ++k) {
    const Vec3 a = path[k + 1] - path[k], b = path[k + 2] - path[k + 1];
    if (a.norm() < 1e-9 || b.norm() < 1e-9) continue;
    worst = std::max(worst, std::acos(std::clamp(a.dot(b) / (a.norm() * b.norm()), -1.0, 1.0)) * 180 / std::numbers::pi);
  }
  return {worst, lost};
}

TEST(KeyframeTopology, ASingularityGoesOnThroughAMiddleKeyFrameInOneDirection) {
  // The plan's velocity of the path nearest `near` just before and just after the middle key
  // frame's time (one-sided differences over 1e-5).
  auto velocities = [](const KeyframeTopologyPlan& plan, const Vec3& near, double key_t = 0.5) {
    auto nearest = [&](double t) {
      Vec3 best = Vec3::Constant(std::numeric_limits<double>::infinity());
      for (const Vec3& x : plan.carried(t))
        if ((x - near).norm() < (best - near).norm()) best = x;
      return best;
    };
    const double e = 1e-5;
    return std::pair{Vec3((nearest(key_t - e) - nearest(key_t - 2 * e)) / e),
                     Vec3((nearest(key_t + 2 * e) - nearest(key_t + e)) / e)};
  };
  const Vec3 key(0, -0.4, 0);
  for (const int n : kGridSides) {
    const std::string text = corner_scene(n, "[0.0, 0.2]");
    const Planned p = plan_of(text);
    const auto [in, out] = velocities(*p.plan, key);
    EXPECT_LT((in - Vec3(0.6, 0.6, 0)).norm(), 0.01) << n << ": arrives at " << in.transpose();
    EXPECT_LT((out - Vec3(0.6, 0.6, 0)).norm(), 0.01) << n << ": leaves at " << out.transpose();
    // The field: both intervals guided, no bifurcation, the source found in every frame
    // and turning little from step to step.
    const Generated g = run(text);
    for (const KeyframeIntervalReport& r : g.report.keyframe_intervals) EXPECT_TRUE(r.guided) << n << ": " << r.unguided_reason;
    EXPECT_EQ(g.topology.bifurcations.size(), 0u) << n;
    const auto [turn, lost] = largest_step_turn(g.topology, Vec3(-0.6, -0.4, 0));
    std::printf("  corner, %d²: arrives (%.3f, %.3f), leaves (%.3f, %.3f); the analysed source turns at most %.1f° a "
                "step\n",
                n, in.x(), in.y(), out.x(), out.y(), turn);
    EXPECT_EQ(lost, 0) << n;
    EXPECT_LT(turn, 30.0) << n;
  }
  // A hold after the key frame: the source comes to rest there and stays put after it.
  {
    const Planned p = plan_of(corner_scene(33, "[0.0, -0.4]"));
    const auto [in, out] = velocities(*p.plan, key);
    EXPECT_LT(in.norm(), 1e-3) << in.transpose();
    EXPECT_LT(out.norm(), 1e-9) << out.transpose();
    // (Where the key frames' field has it: within a hair of the element's place.)
    std::vector<Vec3> held;
    for (const double t : {0.6, 0.75, 0.9})
      for (const Vec3& x : p.plan->carried(t))
        if ((x - key).norm() < 1e-3) held.push_back(x);
    ASSERT_EQ(held.size(), 3u);
    EXPECT_EQ(held[0], held[1]);
    EXPECT_EQ(held[0], held[2]);
  }
  // Turning back: at rest at the key frame.
  {
    const Planned p = plan_of(corner_scene(33, "[-0.6, -0.4]"));
    const auto [in, out] = velocities(*p.plan, key);
    EXPECT_LT(in.norm(), 1e-3) << in.transpose();
    EXPECT_LT(out.norm(), 1e-3) << out.transpose();
  }
  // The sphere's knot with its middle key frame: C¹ on the surface too (32 frames: the key
  // frame at t = 0.5 is held at frame 16, t = 16/31).
  const std::string text =
      test::read_text(test::source_dir() + "/examples/26_keyframe_topology/knot_sphere_middle.json");
  const Planned p = plan_of(text);
  const Vec3 sphere_key(0, -0.5, 0.8660254037844386);
  const auto [in_faces, out_faces] = velocities(*p.plan, sphere_key, 16.0 / 31);
  // Tangent to the sphere (either side runs on its own faces of the mesh, bent 0.03 off
  // the tangent plane one way and the other).
  const Vec3 normal = sphere_key.normalized();
  const Vec3 in = in_faces - in_faces.dot(normal) * normal, out = out_faces - out_faces.dot(normal) * normal;
  EXPECT_GT(in.norm(), 0.5);
  EXPECT_LT((in - out).norm(), 0.02 * in.norm()) << in.transpose() << " against " << out.transpose();
  const Generated g = run(text);
  const auto [turn, lost] = largest_step_turn(g.topology, Vec3(-0.5, 0, 0.8660254037844386));
  std::printf("  the sphere knot with its middle key frame: arrives at %.3f, leaves at %.3f; turns at most %.1f° a step\n",
              in.norm(), out.norm(), turn);
  EXPECT_EQ(lost, 0);
  EXPECT_LT(turn, 30.0);
}

// The knot of mesh_knot with a key frame half-way: the source at m0, the center at m1.
std::string mesh_knot_with_middle(const std::filesystem::path& mesh, const std::string& p, const std::string& q,
                                  const std::string& m0, const std::string& m1, double radius) {
  std::string text = mesh_knot(mesh, p, q, radius);
  const std::string last = R"(
      {"t": 1,)";
  const size_t at = text.find(last);
  text.insert(at, R"(
      {"t": 0.5, "elements": [{"kind": "singular", "type": "source", "at": )" + m0 + R"(},
                              {"kind": "singular", "type": "ccw_center", "at": )" + m1 + R"(}]},)");
  return text;
}

// The same on scanned surfaces: CGAL's mushroom knot with a key frame half-way, the source
// and the center a quarter turn round their middle (as example 26's sphere knot), is guided
// in both intervals with no bifurcation, and the source passes the key frame without
// turning on the spot (59° between the steps into and out of it before session 36). The
// Hermite terms were one world vector per end, walked from the curve over the whole leg,
// and on a long leg round a thin part that walk crossed it: CGAL's camel with such a key
// frame has a static solve's focus carried from the body down to a hoof (0.76), whose bent
// path then left the surface (its nearest points jumped 0.039, 3 edge lengths) where the
// straight legs only collided; such an interval keeps its corners (not guided either way:
// the collision). Since session 37 they are carried along the curve in its frame
// (ASingularityThatTurnsBackAtAMiddleKeyFrameStaysOnItsCurve) and kept on the camel; where
// a path still leaves the surface with them they are dropped for its interval.
TEST(KeyframeTopology, OnScannedSurfacesTheMiddleKeyFramesPathsAreC1WhereTheyStayOnTheSurface) {
  const test::TempDir dir;
  const std::optional<std::filesystem::path> mushroom_off = test::cgal_mesh(dir, "mushroom");
  const std::optional<std::filesystem::path> camel_off = test::cgal_mesh(dir, "camel");
  if (!mushroom_off || !camel_off)
    GTEST_SKIP() << test::kCgalArchive << " is missing or lacks mushroom.off or camel.off (Debian package libcgal-demo)";
  const std::string p = "[0.226893, 0.000169333, 0.227341]", q = "[0.182076, 0.232276, 0.222321]";
  const Generated g = run(mesh_knot_with_middle(*mushroom_off, p, q, "[0.3205378, 0.1386312, 0.224831]",
                                                "[0.0884312, 0.0938142, 0.224831]", 0.0744));
  ASSERT_EQ(g.report.keyframe_intervals.size(), 2u);
  for (const KeyframeIntervalReport& r : g.report.keyframe_intervals) EXPECT_TRUE(r.guided) << r.unguided_reason;
  EXPECT_TRUE(g.topology.bifurcations.empty());
  // The source (repelling) from frame 15 through the key frame's (16 of 32) to 17.
  std::vector<Vec3> source;
  for (const Singularity* s : node_followed_from(g.topology, Vec3(0.226893, 0.000169333, 0.227341))) {
    ASSERT_NE(s, nullptr);
    source.push_back(s->position);
  }
  double worst = 0;
  for (const size_t k : {size_t{15}, size_t{16}}) {
    const Vec3 a = source[k] - source[k - 1], b = source[k + 1] - source[k];
    worst = std::max(worst, std::acos(std::clamp(a.dot(b) / (a.norm() * b.norm()), -1.0, 1.0)) * 180 / std::numbers::pi);
  }
  std::printf("  mushroom with a middle key frame: the source turns %.1f° at most through it\n", worst);
  EXPECT_LT(worst, 20.0);
  // The camel: no interval fails because a path leaves the surface.
  const Planned camel =
      plan_of(mesh_knot_with_middle(*camel_off, "[0.117342, 0.103119, 0.0155613]", "[0.113892, 0.154959, -0.214399]",
                                    "[0.115617, 0.0140589, -0.1253389]", "[0.115617, 0.2440192, -0.0734989]", 0.0716));
  ASSERT_EQ(camel.plan->intervals().size(), 2u);
  for (const KeyframeIntervalReport& r : camel.plan->intervals())
    EXPECT_EQ(r.unguided_reason.find("leaves the surface"), std::string::npos) << r.unguided_reason;
}

// A path's curve whose straightened chords cut across a concave crease (the polyline's
// points pulled out of it, its samples' nearest surface points jumping to the other side)
// is the route instead, every segment a walk on the surface: on CGAL's man a source
// carried from the chest up past the armpit (the second leg of the bench's knot with a key
// frame half-way, bench/keyframe_topology_meshes.py) left the surface (jump 0.016, 2 edge
// lengths); now it reaches the router (and collides: the body is narrower there than the
// separation).
TEST(KeyframeTopology, ACurveAcrossACreaseIsRoutedOnTheSurface) {
  const test::TempDir dir;
  const std::optional<std::filesystem::path> man_off = test::cgal_mesh(dir, "man");
  if (!man_off) GTEST_SKIP() << test::kCgalArchive << " is missing or lacks man.off (Debian package libcgal-demo)";
  const Planned man = plan_of(R"({"tvf": 1, "domain": {"mesh": ")" + man_off->string() + R"("},
    "time": {"frames": 32, "range": [0, 1]}, "generator": "spacetime", "falloff": 20,
    "solver": {"region_radius": 0.0563, "keyframe_topology": "matched"},
    "keyframes": [
      {"t": 0, "elements": [{"kind": "singular", "type": "source", "at": [0.047548985, -0.0669547, 0.086664985]},
                            {"kind": "singular", "type": "ccw_center", "at": [0.229064015, -0.0669547, 0.090609985]}]},
      {"t": 1, "elements": [{"kind": "singular", "type": "source", "at": [0.136334, -0.050443, 0.179395]},
                            {"kind": "singular", "type": "ccw_center", "at": [0.140279, -0.0834664, -0.00212003]}]}]})");
  ASSERT_EQ(man.plan->intervals().size(), 1u);
  const KeyframeIntervalReport& r = man.plan->intervals().front();
  EXPECT_EQ(r.unguided_reason.find("leaves the surface"), std::string::npos) << r.unguided_reason;
}

// Through a middle key frame where a singularity turns back (it comes to rest there), its
// Hermite term lies along its path, and carried along the curve in the curve's frame it
// keeps the singularity on the curve it came by: on a torus, whose shortest paths twist
// (no plane holds them), a source carried from the top of the tube down its side and back
// runs on the same curve as the plan with the two key frames alone. (Before session 37
// each term was one world vector of its end, projected into the faces along the way: it
// turned sideways off the curve where the curve twists.)
TEST(KeyframeTopology, ASingularityThatTurnsBackAtAMiddleKeyFrameStaysOnItsCurve) {
  const double R = 1.0, r = 0.4;
  auto on_torus = [&](double u, double v) {
    return Vec3((R + r * std::cos(v)) * std::cos(u), (R + r * std::cos(v)) * std::sin(u), r * std::sin(v));
  };
  const Vec3 a = on_torus(0.0, 1.5), b = on_torus(0.8, -0.6), c = on_torus(3.0, 0.0);
  auto json_of = [](const Vec3& p) { return fmt::format("[{:.9g}, {:.9g}, {:.9g}]", p.x(), p.y(), p.z()); };
  auto keyframe = [&](double t, const Vec3& source) {
    return fmt::format(R"({{"t": {}, "elements": [{{"kind": "singular", "type": "source", "at": {}}},
                                                   {{"kind": "singular", "type": "ccw_center", "at": {}}}]}})",
                       t, json_of(source), json_of(c));
  };
  auto scene = [&](const std::string& keyframes) {
    return R"({"tvf": 1, "domain": {"torus": {"nu": 96, "nv": 32, "major_radius": 1, "minor_radius": 0.4}},
      "time": {"frames": 32, "range": [0, 1]}, "generator": "spacetime", "falloff": 20,
      "solver": {"region_radius": 0.1, "keyframe_topology": "matched"}, "keyframes": [)" +
           keyframes + "]}";
  };
  const Planned two = plan_of(scene(keyframe(0, a) + "," + keyframe(1, b)));
  const Planned three = plan_of(scene(keyframe(0, a) + "," + keyframe(0.5, b) + "," + keyframe(1, a)));
  ASSERT_EQ(three.plan->intervals().size(), 2u);
  for (const KeyframeIntervalReport& rep : three.plan->intervals()) ASSERT_TRUE(rep.guided) << rep.unguided_reason;
  ASSERT_TRUE(two.plan->intervals().front().guided) << two.plan->intervals().front().unguided_reason;
  // The source followed through the carried points from a, nearest first.
  auto source_path = [&](const KeyframeTopologyPlan& plan, double t0, double t1, int n) {
    std::vector<Vec3> out;
    Vec3 at = a;
    for (int k = 1; k < n; ++k) {
      const std::vector<Vec3> now = plan.carried(t0 + (t1 - t0) * k / n);
      if (now.empty()) continue;
      at = *std::min_element(now.begin(), now.end(),
                             [&](const Vec3& x, const Vec3& y) { return (x - at).norm() < (y - at).norm(); });
      out.push_back(at);
    }
    return out;
  };
  const std::vector<Vec3> curve = source_path(*two.plan, 0, 1, 800);
  const std::vector<Vec3> there = source_path(*three.plan, 0, 0.5, 200);
  ASSERT_GT(curve.size(), 700u);
  ASSERT_GT(there.size(), 150u);
  double length = 0, off = 0;
  for (size_t k = 1; k < curve.size(); ++k) length += (curve[k] - curve[k - 1]).norm();
  for (const Vec3& p : there) {
    double d = std::numeric_limits<double>::infinity();
    for (size_t k = 1; k < curve.size(); ++k) {
      const Vec3 e = curve[k] - curve[k - 1];
      const double u = std::clamp((p - curve[k - 1]).dot(e) / e.squaredNorm(), 0.0, 1.0);
      d = std::min(d, (p - curve[k - 1] - u * e).norm());
    }
    off = std::max(off, d);
  }
  std::printf("  torus: the source's path %.3f long; with the middle key frame at most %.2g off it (%.3g from b at "
              "the end)\n",
              length, off, (there.back() - b).norm());
  EXPECT_LT((there.back() - b).norm(), 0.02);  // it gets there
  EXPECT_LT(off, 0.01 * length);               // 0.066 before session 37
}

// A singularity of a key frame for the matching tests: its type and place (index from the type).
Singularity singularity_at(SingularityType type, double x, double y) {
  Singularity s;
  s.type = type;
  s.index = type == SingularityType::saddle ? -1 : 1;
  s.position = Vec3(x, y, 0);
  return s;
}

// Matching (match_keyframe_singularities): the static solve's own foci that trade places
// (a repelling one at p and an attracting one at q in the first key frame, the other way
// round in the second) turn over where they are instead of each travelling to the other's
// place; a designed singularity keeps its type (a source and a center trading places are
// meant to), and so does a linked one.
TEST(KeyframeTopology, TheStaticSolvesOwnFociTurnOverInPlace) {
  const auto at = singularity_at;
  using T = SingularityType;
  // Two far foci swapping stability (1 apart), a source and a center trading places (0.3).
  const std::vector<Singularity> A{at(T::repelling_focus, -0.5, 0.8), at(T::attracting_focus, 0.5, 0.8),
                                   at(T::source, -0.15, 0), at(T::center, 0.15, 0)};
  const std::vector<Singularity> B{at(T::attracting_focus, -0.5, 0.8), at(T::repelling_focus, 0.5, 0.8),
                                   at(T::center, -0.15, 0), at(T::source, 0.15, 0)};
  KeyframeMatchRules rules;
  rules.turnover_cost = 0.3;
  using Pairs = std::vector<std::pair<size_t, size_t>>;
  // Nobody designed any: everything turns over in place (the source and the center too:
  // same stability class, nothing to pay).
  KeyframeMatch m = match_keyframe_singularities(A, B, rules);
  std::sort(m.matched.begin(), m.matched.end());
  EXPECT_EQ(m.matched, (Pairs{{0, 0}, {1, 1}, {2, 2}, {3, 3}}));
  // The source and the center designed: they trade places, the foci still turn over.
  rules.designed_a = {0, 0, 1, 1};
  rules.designed_b = {0, 0, 1, 1};
  m = match_keyframe_singularities(A, B, rules);
  std::sort(m.matched.begin(), m.matched.end());
  EXPECT_EQ(m.matched, (Pairs{{0, 0}, {1, 1}, {2, 3}, {3, 2}}));
  EXPECT_TRUE(m.cancelled.empty());
  EXPECT_TRUE(m.created.empty());
  // Two foci 0.2 apart trading stability: by type each would run through the other (no
  // detour parts them where the key frames hold them closer than the separation), so they
  // turn over in place although that counts 2 × 0.3 against 0.4 of travel.
  const std::vector<Singularity> A2{at(T::repelling_focus, -0.1, 0.8), at(T::attracting_focus, 0.1, 0.8)};
  const std::vector<Singularity> B2{at(T::attracting_focus, -0.1, 0.8), at(T::repelling_focus, 0.1, 0.8)};
  m = match_keyframe_singularities(A2, B2, KeyframeMatchRules{{}, {}, {}, 0.3});
  std::sort(m.matched.begin(), m.matched.end());
  EXPECT_EQ(m.matched, (Pairs{{0, 0}, {1, 1}}));
  // Paths that do not cross: by type 2 × 0.78; the other way 2 × 0.64 of travel but two
  // turnovers at 0.3 each: kept by type. Free turnovers take the shorter travel.
  const std::vector<Singularity> A3{at(T::repelling_focus, 0, 0), at(T::attracting_focus, 1, 0)};
  const std::vector<Singularity> B3{at(T::repelling_focus, 0.6, 0.5), at(T::attracting_focus, 0.4, -0.5)};
  m = match_keyframe_singularities(A3, B3, KeyframeMatchRules{{}, {}, {}, 0.3});
  std::sort(m.matched.begin(), m.matched.end());
  EXPECT_EQ(m.matched, (Pairs{{0, 0}, {1, 1}}));
  m = match_keyframe_singularities(A3, B3, KeyframeMatchRules{{}, {}, {}, 0.0});
  std::sort(m.matched.begin(), m.matched.end());
  EXPECT_EQ(m.matched, (Pairs{{0, 1}, {1, 0}}));
  // Linked pairs are kept as linked.
  m = match_keyframe_singularities(A, B, KeyframeMatchRules{{{0, 1}}, {}, {}, 0.3});
  EXPECT_EQ(m.matched.front(), (std::pair<size_t, size_t>{0, 1}));
}

// Matching with carry_reach (the plan's second try for an unguided interval): the static
// solve's own singularities are carried only within it; farther, each key frame has its own
// there and they are cancelled and created in pairs (CGAL's bear: a saddle and a focus by
// the head in one key frame, by the body in the other, were carried 0.9 and 1.2 across the
// others' paths). A designed one is carried however far, and what no pair takes is still
// carried.
TEST(KeyframeTopology, TheStaticSolvesOwnAreCarriedOnlyWithinReach) {
  const auto at = singularity_at;
  using T = SingularityType;
  using Pairs = std::vector<std::pair<size_t, size_t>>;
  // A saddle and a focus near (-1, 1) in the first key frame, near (1, -1) in the second;
  // a sink that stays, off their way.
  const std::vector<Singularity> A{at(T::saddle, -1, 1), at(T::attracting_focus, -1.1, 1.05), at(T::sink, 1, 1)};
  const std::vector<Singularity> B{at(T::saddle, 1, -1), at(T::attracting_focus, 1.1, -0.95), at(T::sink, 1.05, 1)};
  KeyframeMatchRules rules;
  rules.turnover_cost = 0.3;
  rules.stability_reach = 0.6;
  // Without a reach: carried 2.8 across the domain.
  KeyframeMatch m = match_keyframe_singularities(A, B, rules);
  std::sort(m.matched.begin(), m.matched.end());
  EXPECT_EQ(m.matched, (Pairs{{0, 0}, {1, 1}, {2, 2}}));
  EXPECT_TRUE(m.cancelled.empty());
  // Within 0.6: the pair is cancelled in the first key frame and created in the second.
  rules.carry_reach = 0.6;
  m = match_keyframe_singularities(A, B, rules);
  EXPECT_EQ(m.matched, (Pairs{{2, 2}}));
  EXPECT_EQ(m.cancelled, (Pairs{{0, 1}}));
  EXPECT_EQ(m.created, (Pairs{{0, 1}}));
  // Designed (the user placed them there): carried.
  rules.designed_a = {1, 1, 0};
  rules.designed_b = {1, 1, 0};
  m = match_keyframe_singularities(A, B, rules);
  std::sort(m.matched.begin(), m.matched.end());
  EXPECT_EQ(m.matched, (Pairs{{0, 0}, {1, 1}, {2, 2}}));
  // A focus alone far away, with no saddle to pair with: still carried.
  const std::vector<Singularity> A1{at(T::attracting_focus, -1, 1)};
  const std::vector<Singularity> B1{at(T::attracting_focus, 1, -1)};
  m = match_keyframe_singularities(A1, B1, KeyframeMatchRules{{}, {}, {}, 0.3, 0.6, 0.6});
  EXPECT_EQ(m.matched, (Pairs{{0, 0}}));
}

// Matching: a node the key frame leaves to a saddle–node pair takes the match of a node
// carried far where that moves the singularities less in all (CGAL's elephant: a sink was
// carried 0.49 to where a repelling focus turns attracting in place, and that focus
// cancelled with a saddle 0.47 away, where the sink and a saddle beside it are the pair).
// The same for a pair created in the second key frame; a designed node keeps its pair.
TEST(KeyframeTopology, ANodeLeftToAPairTakesTheMatchOfOneCarriedFar) {
  const auto at = singularity_at;
  using T = SingularityType;
  using Pairs = std::vector<std::pair<size_t, size_t>>;
  KeyframeMatchRules rules;
  rules.turnover_cost = 0.2;
  // First key frame: a repelling focus at the origin, a sink at (1, 0), a saddle by it; the
  // second: an attracting focus at the origin. By stability the sink is carried 1.0 and the
  // focus cancelled with the saddle 1.1 away (2.1 in all); in place 0.01 + 0.2 + 0.1.
  const std::vector<Singularity> A{at(T::repelling_focus, 0, 0), at(T::sink, 1, 0), at(T::saddle, 1.1, 0)};
  const std::vector<Singularity> B{at(T::attracting_focus, 0, 0.01)};
  KeyframeMatch m = match_keyframe_singularities(A, B, rules);
  EXPECT_EQ(m.matched, (Pairs{{0, 0}}));
  EXPECT_EQ(m.cancelled, (Pairs{{2, 1}}));
  EXPECT_TRUE(m.created.empty());
  // The same with the key frames' order reversed: the pair is created beside the sink.
  m = match_keyframe_singularities(B, A, rules);
  EXPECT_EQ(m.matched, (Pairs{{0, 0}}));
  EXPECT_EQ(m.created, (Pairs{{2, 1}}));
  EXPECT_TRUE(m.cancelled.empty());
  // Where the turnover costs more than it saves (2.61 against 2.1 in all), carried as before.
  rules.turnover_cost = 2.5;
  m = match_keyframe_singularities(A, B, rules);
  EXPECT_EQ(m.matched, (Pairs{{1, 0}}));
  EXPECT_EQ(m.cancelled, (Pairs{{2, 0}}));
  // The focus designed (the user placed it, then cancels it with the saddle): kept.
  rules.turnover_cost = 0.2;
  rules.designed_a = {1, 0, 0};
  m = match_keyframe_singularities(A, B, rules);
  EXPECT_EQ(m.matched, (Pairs{{1, 0}}));
  EXPECT_EQ(m.cancelled, (Pairs{{2, 0}}));
  // The sink designed (carried however far, as the user placed it): kept.
  rules.designed_a = {0, 1, 0};
  m = match_keyframe_singularities(A, B, rules);
  EXPECT_EQ(m.matched, (Pairs{{1, 0}}));
}

// Two singularities the key frames hold closer than path_separation and that barely move
// are not bent apart in between: two whose straight paths do not approach keep what those
// keep (the static solve's own saddles and foci on scanned meshes sit that close and barely
// move; bending them apart set off the router on every such pair).
TEST(KeyframeTopology, PairsTheKeyFramesHoldCloseAreNotPartedInBetween) {
  const std::string text = R"({"tvf": 1, "domain": {"grid": {"size": [33, 33], "min": [-1, -1], "max": [1, 1]}},
    "time": {"frames": 17, "range": [0, 1]}, "generator": "spacetime", "falloff": 8,
    "solver": {"region_radius": 0.1, "path_separation": 0.4, "keyframe_topology": "matched"},
    "keyframes": [
      {"t": 0, "elements": [{"kind": "singular", "type": "source", "at": [-0.15, 0]},
                            {"kind": "singular", "type": "sink", "at": [0.15, 0]}]},
      {"t": 1, "elements": [{"kind": "singular", "type": "source", "at": [-0.15, 0.02]},
                            {"kind": "singular", "type": "sink", "at": [0.15, -0.02]}]}]})";
  const Generated g = run(text);
  const KeyframeIntervalReport& r = g.report.keyframe_intervals.at(0);
  // The source, the sink and the two saddles the static solve puts above and below them,
  // each moving 0.02–0.09; the nearest two 0.26 apart at the key frames. Asked for the
  // separation in between, all four were bent (detours 0.09–0.21, routed pairwise).
  ASSERT_EQ(r.matched.size(), 4u);
  EXPECT_EQ(r.routing, "straight");
  EXPECT_TRUE(r.collision.empty()) << r.collision;
  for (const auto& m : r.matched) EXPECT_EQ(m.detour, 0.0);
  EXPECT_GT(r.closest_approach, 0.26);
  EXPECT_TRUE(r.guided);
  EXPECT_EQ(g.topology.bifurcations.size(), 0u);
  for (const auto& frame : g.topology.singularities) EXPECT_EQ(frame.size(), 4u);
}

// Two paths a key frame already holds closer than the separation, which no detour of their
// own parts: the collision is the key frames' own, so the router says so at once instead
// of searching for a joint detour of every path (CGAL's elephant: two saddles 0.065 apart
// at the first key frame, separation 0.1; 16 s of the joint search before). The report
// names the key frame and the distance it holds them at.
TEST(KeyframeTopology, PathsAKeyFrameHoldsTooCloseAreReportedAtOnce) {
  const Planned p = plan_of(held_strip_scene("matched"));
  const KeyframeIntervalReport& r = p.plan->intervals().at(0);
  EXPECT_EQ(r.collision,
            "scene: solver.keyframe_topology: between keyframes[0] and keyframes[1] the paths of the sink from (-0.35, 0) "
            "to (-0.65, 0) and the source from (-0.5, 0) to (0.5, 0) come 0.000869 apart at t = 0.211, and no detour "
            "(the key frame at t = 0 holds them 0.15 apart already) keeps them 0.2 apart, so the paths stay straight "
            "and the singularities meet; set a smaller solver.path_separation, link them differently (solver.links) or "
            "add a key frame between");
  EXPECT_EQ(r.routing, "straight");
  for (const auto& m : r.matched) EXPECT_EQ(m.detour, 0.0);
}

}  // namespace
}  // namespace tvf
