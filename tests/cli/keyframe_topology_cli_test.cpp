// `tvf generate` on a scene with "keyframe_topology": "matched": one line per key-frame
// interval and keyframe_topology.json; `tvf analyze` then finds what it planned.
#include "support/test_paths.h"
#include "tvf/field/npy.h"

#include <gtest/gtest.h>
#include <nlohmann/json.hpp>

#include <algorithm>
#include <array>
#include <cmath>
#include <filesystem>
#include <fstream>
#include <map>
#include <string>
#include <vector>

namespace tvf {
namespace {

namespace fs = std::filesystem;

nlohmann::json read_json(const fs::path& file) {
  std::ifstream in(file);
  EXPECT_TRUE(in.good()) << file;
  return in.good() ? nlohmann::json::parse(in) : nlohmann::json();
}

// `tvf generate SCENE -o DIR/out --no-vtk`, then `tvf analyze DIR/out -o DIR/a.json`: both
// printed reports, keyframe_topology.json (null when not written) and the analysis.
struct GeneratedAndAnalysed {
  test::CommandResult generated, analysed;
  nlohmann::json topology, analysis;
};
GeneratedAndAnalysed generate_and_analyze(const test::TempDir& dir, const std::string& scene, const std::string& analyze_options = "") {
  GeneratedAndAnalysed r;
  r.generated = test::run_tvf("generate " + test::quoted(scene) + " -o " + test::quoted(dir / "out") + " --no-vtk");
  EXPECT_EQ(r.generated.exit_code, 0) << r.generated.output;
  if (r.generated.exit_code != 0) return r;
  if (fs::exists(dir / "out" / "keyframe_topology.json")) r.topology = read_json(dir / "out" / "keyframe_topology.json");
  r.analysed = test::run_tvf("analyze " + test::quoted(dir / "out") + " -o " + test::quoted(dir / "a.json") +
                             analyze_options);
  EXPECT_EQ(r.analysed.exit_code, 0) << r.analysed.output;
  if (r.analysed.exit_code == 0) r.analysis = read_json(dir / "a.json");
  return r;
}

// A +1 singularity followed frame by frame from `start` (the nearest of index +1 to its
// place in the frame before): trace/√det of its Jacobian per frame (0 a center, 2 a
// source, −2 a sink).
std::vector<double> followed_node_ratios(const nlohmann::json& analysis, std::array<double, 3> start, size_t frames) {
  std::vector<double> ratios;
  for (size_t f = 0; f < frames; ++f) {
    const nlohmann::json* nearest = nullptr;
    double best = 1e300;
    for (const auto& s : analysis.at("singularities")) {
      if (s.at("frame").get<size_t>() != f || s.at("index").get<int>() != 1) continue;
      const auto p = s.at("position").get<std::array<double, 3>>();
      const double d = std::hypot(p[0] - start[0], p[1] - start[1], p[2] - start[2]);
      if (d < best) best = d, nearest = &s;
    }
    if (!nearest) {
      ADD_FAILURE() << "no +1 singularity at frame " << f;
      return ratios;
    }
    start = nearest->at("position").get<std::array<double, 3>>();
    const auto j = nearest->at("jacobian").get<std::array<std::array<double, 2>, 2>>();
    ratios.push_back((j[0][0] + j[1][1]) / std::sqrt(std::abs(j[0][0] * j[1][1] - j[0][1] * j[1][0])));
  }
  return ratios;
}

// The index-+1 singularity nearest `center` in the analysis's first frame, followed frame by
// frame (the nearest +1 to where it was), is a center in each of `frames` frames:
// |trace| / √|det| of its Jacobian below 0.25 (a focus turning one way or the other is
// above; a node 2).
void expect_center_followed(const nlohmann::json& analysis, std::array<double, 3> center, size_t frames) {
  const std::vector<double> ratios = followed_node_ratios(analysis, center, frames);
  EXPECT_EQ(ratios.size(), frames);
  for (size_t f = 0; f < ratios.size(); ++f) EXPECT_LT(std::abs(ratios[f]), 0.25) << "the designed center at frame " << f;
}

TEST(CliKeyframeTopology, Example26ReportsItsIntervalAndTheAnalysisAgrees) {
  test::TempDir dir;
  const std::string scene = test::source_dir() + "/examples/26_keyframe_topology/scene.json";
  const GeneratedAndAnalysed r = generate_and_analyze(dir, scene);
  ASSERT_FALSE(r.analysis.is_null());
  EXPECT_NE(r.generated.output.find("key frames 0 → 1 (t 0 → 1): 3 matched, 1 pairs created and 0 cancelled at t = 0.6"),
            std::string::npos)
      << r.generated.output;
  ASSERT_EQ(r.topology.at("intervals").size(), 1u);
  const nlohmann::json& i = r.topology["intervals"][0];
  EXPECT_EQ(i.at("bifurcation_t"), 0.6);
  EXPECT_EQ(i.at("matched").size(), 3u);
  ASSERT_EQ(i.at("created").size(), 1u);
  EXPECT_EQ(i["created"][0].at("node_type"), "sink");
  EXPECT_TRUE(i.at("cancelled").empty());

  // The design check counts the planned creation as designed.
  EXPECT_NE(r.analysed.output.find("designed 6 singularities, 1 bifurcation: all found; no extras"), std::string::npos)
      << r.analysed.output;
  const nlohmann::json& analysis = r.analysis;
  // Exactly the planned creation, where and when the template put it; no other event.
  ASSERT_EQ(analysis.at("bifurcations").size(), 1u) << analysis["bifurcations"].dump();
  const nlohmann::json& b = analysis["bifurcations"][0];
  EXPECT_EQ(b.at("kind"), "creation");
  EXPECT_NEAR(b.at("t").get<double>(), 0.6, 1.5 / 59);
  const auto at = i["created"][0]["at"];
  const double dx = b["position"][0].get<double>() - at[0].get<double>();
  const double dy = b["position"][1].get<double>() - at[1].get<double>();
  EXPECT_LT(std::hypot(dx, dy), 0.1);
  EXPECT_EQ(analysis.at("paths").size(), 5u);

  // The design check takes the plan from the folder's keyframe_topology.json (it is not
  // made again): without the file, or with one that does not parse, it plans again and
  // says the same; with the planned creation taken out of the file, the creation is extra.
  const nlohmann::json design = read_json(dir / "a_design.json");
  const fs::path plan = dir / "out" / "keyframe_topology.json";
  nlohmann::json edited = r.topology;
  edited["intervals"][0]["created"] = nlohmann::json::array();
  // A plan for other key-frame times is another scene's: planned again too.
  nlohmann::json other = edited;
  other["intervals"][0]["interval"][1] = 0.9;
  for (const std::string& content :
       {std::string("none"), std::string("{\"intervals\": 3}"), other.dump(), edited.dump()}) {
    SCOPED_TRACE(content.substr(0, 40));
    if (content == "none") fs::remove(plan);
    else test::write_text(plan, content);
    const auto again = test::run_tvf("analyze " + test::quoted(dir / "out") + " -q -o " + test::quoted(dir / "b.json"));
    ASSERT_EQ(again.exit_code, 0) << again.output;
    const nlohmann::json d = read_json(dir / "b_design.json");
    if (content == edited.dump()) {
      EXPECT_EQ(d.at("extra").at("bifurcations").size(), 1u) << d.dump();
      EXPECT_EQ(d.at("keyframe_intervals").at(0).at("planned_bifurcations"), 0) << d.dump();
    } else {
      EXPECT_EQ(d, design);
    }
  }

  // The same scene with "free": bifurcations nobody designed, and no keyframe_topology.json.
  test::TempDir free_dir;
  nlohmann::json free = read_json(scene);
  free["solver"] = {{"region_radius", 0.15}};
  test::write_text(free_dir / "free.json", free.dump());
  const GeneratedAndAnalysed f = generate_and_analyze(free_dir, (free_dir / "free.json").string());
  ASSERT_FALSE(f.analysis.is_null());
  EXPECT_TRUE(f.topology.is_null());
  EXPECT_GE(f.analysis.at("bifurcations").size(), 3u);
}

// Example 26's crossing.json: a source and a sink trading places. `tvf generate` says it
// bent both paths, keyframe_topology.json gives their detours and closest approach, and
// the analysis finds the two paths alone, kept apart at every frame.
// On a terminal (TVF_PROGRESS=1 stands for one) the progress line says when the key-frame
// topology is being planned, before the frames' count starts (a plan takes seconds on a
// scanned mesh), each step rewriting the line whole; in a pipeline nothing of it.
TEST(CliKeyframeTopology, TheProgressLineSaysWhenTheTopologyIsPlanned) {
  test::TempDir dir;
  const std::string scene = test::source_dir() + "/examples/26_keyframe_topology/scene.json";
  const auto args = " generate " + test::quoted(scene) + " -o " + test::quoted(dir / "out") + " --no-vtk";
  const auto shown = test::run_command("TVF_PROGRESS=1 " + test::quoted(test::cli_path()) + args);
  ASSERT_EQ(shown.exit_code, 0) << shown.output;
  const size_t planning = shown.output.find("\r\033[Ktvf generate: planning the topology between key frames (interval 1 of 1)");
  const size_t frames = shown.output.find("\r\033[Ktvf generate: 60/60 frames");
  EXPECT_NE(planning, std::string::npos) << shown.output;
  EXPECT_NE(frames, std::string::npos) << shown.output;
  EXPECT_LT(planning, frames);
  const auto piped = test::run_command("TVF_PROGRESS=0 " + test::quoted(test::cli_path()) + args);
  ASSERT_EQ(piped.exit_code, 0) << piped.output;
  EXPECT_EQ(piped.output.find("planning the topology"), std::string::npos) << piped.output;
}

TEST(CliKeyframeTopology, Example26CrossingPathsAreBentApart) {
  test::TempDir dir;
  const std::string scene = test::source_dir() + "/examples/26_keyframe_topology/crossing.json";
  const GeneratedAndAnalysed r = generate_and_analyze(dir, scene);
  ASSERT_FALSE(r.analysis.is_null());
  EXPECT_NE(r.generated.output.find("key frames 0 → 1 (t 0 → 1): 2 matched (2 bent to keep 0.3 apart), 0 pairs created "
                                    "and 0 cancelled at t = 0.5"),
            std::string::npos)
      << r.generated.output;
  EXPECT_EQ(r.generated.output.find("warning"), std::string::npos) << r.generated.output;
  const nlohmann::json& i = r.topology.at("intervals").at(0);
  EXPECT_EQ(i.at("separation"), 0.3);
  EXPECT_GE(i.at("closest_approach").get<double>(), 0.3);
  EXPECT_FALSE(i.contains("collision"));
  for (const auto& m : i.at("matched")) EXPECT_GT(m.at("detour").get<double>(), 0.15);

  const nlohmann::json& analysis = r.analysis;
  EXPECT_EQ(analysis.at("paths").size(), 2u);
  EXPECT_TRUE(analysis.at("bifurcations").empty());
  std::vector<std::vector<std::array<double, 2>>> frames(60);
  for (const auto& s : analysis.at("singularities"))
    frames.at(s.at("frame").get<size_t>()).push_back({s["position"][0].get<double>(), s["position"][1].get<double>()});
  for (size_t f = 0; f < frames.size(); ++f) {
    ASSERT_EQ(frames[f].size(), 2u) << f;
    EXPECT_GE(std::hypot(frames[f][0][0] - frames[f][1][0], frames[f][0][1] - frames[f][1][1]), 0.3 - 1e-6) << f;
  }
}

// Example 26's knot.json: three knotted paths. `tvf generate` says it bent them together,
// keyframe_topology.json says "routing": "joint" with no collision, and the analysis finds
// the three designed singularities (a source, a center and the saddle) in every frame, 0.3
// or more apart (the extra pairs it also finds are docs/architecture.md's).
TEST(CliKeyframeTopology, Example26KnotIsRoutedTogether) {
  test::TempDir dir;
  const std::string scene = test::source_dir() + "/examples/26_keyframe_topology/knot.json";
  const GeneratedAndAnalysed r = generate_and_analyze(dir, scene);
  ASSERT_FALSE(r.analysis.is_null());
  EXPECT_NE(r.generated.output.find("3 matched (3 bent together to keep 0.3 apart)"), std::string::npos)
      << r.generated.output;
  EXPECT_EQ(r.generated.output.find("warning"), std::string::npos) << r.generated.output;
  const nlohmann::json& i = r.topology.at("intervals").at(0);
  EXPECT_EQ(i.at("routing"), "joint");
  EXPECT_FALSE(i.contains("collision"));
  EXPECT_GE(i.at("closest_approach").get<double>(), 0.3);
  const nlohmann::json& analysis = r.analysis;
  // Per frame: a source, a center and a saddle among the found ones, pairwise 0.3 apart
  // (the first of each type nearest to the previous frame's).
  std::map<std::string, std::array<double, 2>> prev;
  std::vector<std::map<std::string, std::vector<std::array<double, 2>>>> frames(60);
  for (const auto& s : analysis.at("singularities"))
    frames.at(s.at("frame").get<size_t>())[s.at("type").get<std::string>()].push_back(
        {s["position"][0].get<double>(), s["position"][1].get<double>()});
  prev = {{"source", {-0.5, 0}}, {"center", {0.5, 0}}, {"saddle", {0, 0.29}}};
  for (size_t f = 0; f < frames.size(); ++f) {
    std::map<std::string, std::array<double, 2>> cur;
    for (const auto& [type, last] : prev) {
      const auto& found = frames[f][type];
      ASSERT_FALSE(found.empty()) << type << " at frame " << f;
      cur[type] = *std::min_element(found.begin(), found.end(), [&](const auto& x, const auto& y) {
        return std::hypot(x[0] - last[0], x[1] - last[1]) < std::hypot(y[0] - last[0], y[1] - last[1]);
      });
      EXPECT_LT(std::hypot(cur[type][0] - last[0], cur[type][1] - last[1]), 0.1) << type << " at frame " << f;
    }
    for (const auto& [ta, pa] : cur)
      for (const auto& [tb, pb] : cur)
        if (ta < tb) {
          EXPECT_GE(std::hypot(pa[0] - pb[0], pa[1] - pb[1]), 0.3 - 1e-4) << ta << " " << tb << " at frame " << f;
        }
    prev = cur;
  }
}

// Example 26's knot_sphere.json: the knot on a sphere, every singularity of both key frames
// matched, so the interval is guided on the surface (SurfaceGuide). The analysis finds four
// singularities in every frame (index sum 2, the sphere's) and no saddle–node event; the
// designed center, followed frame by frame from its place in the first key frame, is a
// center in every frame (|trace|/√det < 0.25: the local choice keeps it, though the
// source's λ ends a whole turn; before, with no correction, a focus for half the interval,
// up to 1.46).
TEST(CliKeyframeTopology, Example26KnotOnASphereIsGuided) {
  test::TempDir dir;
  const std::string scene = test::source_dir() + "/examples/26_keyframe_topology/knot_sphere.json";
  const GeneratedAndAnalysed r = generate_and_analyze(dir, scene, " --no-plots");
  ASSERT_FALSE(r.analysis.is_null());
  EXPECT_NE(r.generated.output.find("4 matched"), std::string::npos) << r.generated.output;
  const nlohmann::json& i = r.topology.at("intervals").at(0);
  EXPECT_TRUE(i.at("guided").get<bool>()) << i;
  EXPECT_TRUE(i.at("created").empty() && i.at("cancelled").empty()) << i;
  EXPECT_NE(r.analysed.output.find("0 bifurcations planned, 0 not asked for"), std::string::npos) << r.analysed.output;
  const nlohmann::json& analysis = r.analysis;
  std::vector<int> count(32, 0), index_sum(32, 0);
  for (const auto& s : analysis.at("singularities")) {
    const auto f = s.at("frame").get<size_t>();
    ++count.at(f);
    index_sum.at(f) += s.at("index").get<int>();
  }
  for (size_t f = 0; f < count.size(); ++f) {
    EXPECT_EQ(count[f], 4) << "frame " << f;
    EXPECT_EQ(index_sum[f], 2) << "frame " << f;
  }
  for (const auto& b : analysis.at("bifurcations")) EXPECT_EQ(b.at("kind"), "hopf") << b;
  expect_center_followed(analysis, {0.5, 0.0, std::sqrt(0.75)}, 32);
  // The source is the node the guide leaves turning (its λ ends a whole turn: the key
  // frames set it, docs/architecture.md). The report and the warning say so, and the
  // analysis agrees: followed from its first place, it is attracting in some frame.
  for (const auto& m : i.at("matched")) {
    const bool source = m.at("type") == "source";
    EXPECT_EQ(std::abs(m.at("phase_turns").get<int>()), source ? 1 : 0) << m;
    if (source) EXPECT_GT(m.at("phase_swing").get<double>(), 6.0) << m;
    else EXPECT_EQ(m.at("phase_swing").get<double>(), 0.0) << m;
  }
  EXPECT_NE(r.generated.output.find("1 turning a whole turn"), std::string::npos) << r.generated.output;
  EXPECT_NE(r.generated.output.find("warning: between keyframes[0] and keyframes[1] the source carried from (-0.500, "),
            std::string::npos)
      << r.generated.output;
  EXPECT_NE(r.generated.output.find("is not held to its type: it turns 1 whole turn"), std::string::npos)
      << r.generated.output;
  const std::vector<double> source = followed_node_ratios(analysis, {-0.5, 0.0, std::sqrt(0.75)}, 32);
  ASSERT_EQ(source.size(), 32u);
  EXPECT_GT(source.front(), 1.5);
  EXPECT_GT(source.back(), 1.5);
  EXPECT_LT(*std::min_element(source.begin(), source.end()), -0.5) << "the source never attracting";
  // The key frame that would hold it: the two designed elements at the frame nearest the
  // middle (t = 15/31), where the plan carries them then (on the sphere, near the pole,
  // each moved off its first place), each carried from and to its own element; the
  // warning names it.
  ASSERT_TRUE(i.contains("middle_keyframe")) << i;
  const nlohmann::json& middle = i.at("middle_keyframe");
  EXPECT_NEAR(middle.at("keyframe").at("t").get<double>(), 15.0 / 31, 1e-12) << middle;
  EXPECT_EQ(middle.at("from"), nlohmann::json::parse("[0, 1]")) << middle;
  EXPECT_EQ(middle.at("to"), nlohmann::json::parse("[0, 1]")) << middle;
  const nlohmann::json& held = middle.at("keyframe").at("elements");
  ASSERT_EQ(held.size(), 2u) << middle;
  EXPECT_EQ(held[0].at("type"), "source");
  EXPECT_EQ(held[1].at("type"), "ccw_center");
  for (const auto& e : held) {
    const auto p = e.at("at").get<std::array<double, 3>>();
    EXPECT_NEAR(std::hypot(p[0], p[1], p[2]), 1.0, 0.01) << e;  // on the sphere (its faces' chords)
    EXPECT_GT(std::min(std::hypot(p[0] + 0.5, p[1]), std::hypot(p[0] - 0.5, p[1])), 0.3) << e;  // half-way
  }
  EXPECT_NE(r.generated.output.find("a key frame at t = 0.4839 holding the source at ("), std::string::npos)
      << r.generated.output;

  // Taken (inserted between the two): no node turns, no warning, the source a source in
  // every frame, four singularities per frame and no event.
  nlohmann::json with_middle = read_json(scene);
  with_middle["keyframes"].insert(with_middle["keyframes"].begin() + 1, middle.at("keyframe"));
  test::TempDir taken_dir;
  test::write_text(taken_dir / "scene.json", with_middle.dump());
  const GeneratedAndAnalysed taken = generate_and_analyze(taken_dir, (taken_dir / "scene.json").string(), " --no-plots");
  ASSERT_FALSE(taken.analysis.is_null());
  EXPECT_EQ(taken.generated.output.find("warning"), std::string::npos) << taken.generated.output;
  for (const auto& interval : taken.topology.at("intervals")) {
    EXPECT_TRUE(interval.at("guided").get<bool>()) << interval;
    EXPECT_FALSE(interval.contains("middle_keyframe")) << interval;
    for (const auto& m : interval.at("matched")) EXPECT_EQ(m.at("phase_turns").get<int>(), 0) << m;
  }
  EXPECT_TRUE(taken.analysis.at("bifurcations").empty()) << taken.analysis.at("bifurcations");
  std::vector<int> taken_count(32, 0);
  for (const auto& s : taken.analysis.at("singularities")) ++taken_count.at(s.at("frame").get<size_t>());
  for (size_t f = 0; f < taken_count.size(); ++f) EXPECT_EQ(taken_count[f], 4) << "frame " << f;
  const std::vector<double> held_source = followed_node_ratios(taken.analysis, {-0.5, 0.0, std::sqrt(0.75)}, 32);
  ASSERT_EQ(held_source.size(), 32u);
  for (size_t f = 0; f < held_source.size(); ++f) EXPECT_GT(held_source[f], 1.5) << "the source at frame " << f;
  // Coherent in time up to the second key frame: no frame-to-frame step above 3× the
  // median (1.3× now; 5.7× with a phase correction whose nodes ended on different whole
  // turns, the last step reversing the vectors between them).
  std::vector<double> steps = analysis.at("coherence").get<std::vector<double>>();
  ASSERT_FALSE(steps.empty());
  const double largest = *std::max_element(steps.begin(), steps.end());
  std::nth_element(steps.begin(), steps.begin() + static_cast<std::ptrdiff_t>(steps.size() / 2), steps.end());
  EXPECT_LE(largest, 3 * steps[steps.size() / 2]) << analysis.at("coherence");
}


// Example 26's knot_sphere_middle.json: the same knot with a key frame at t = 0.5, the
// source and the center half-way round their trade. What the warning above advises takes
// the source's whole turn out: both intervals are guided with no node left turning (every
// phase_turns and phase_swing 0, no warning), and the analysis agrees: the source, followed
// from its first place, is a source in every frame (trace/√det > 1.5; it dipped to −2 with
// two key frames) and the center a center, four singularities per frame, no event.
TEST(CliKeyframeTopology, Example26KnotOnASphereWithAMiddleKeyFrameHoldsEveryNode) {
  test::TempDir dir;
  const std::string scene = test::source_dir() + "/examples/26_keyframe_topology/knot_sphere_middle.json";
  const GeneratedAndAnalysed r = generate_and_analyze(dir, scene, " --no-plots");
  ASSERT_FALSE(r.analysis.is_null());
  EXPECT_EQ(r.generated.output.find("warning"), std::string::npos) << r.generated.output;
  EXPECT_EQ(r.generated.output.find("turning"), std::string::npos) << r.generated.output;
  ASSERT_EQ(r.topology.at("intervals").size(), 2u);
  for (const auto& i : r.topology.at("intervals")) {
    EXPECT_TRUE(i.at("guided").get<bool>()) << i;
    ASSERT_EQ(i.at("matched").size(), 4u) << i;
    for (const auto& m : i.at("matched")) {
      EXPECT_EQ(m.at("phase_turns").get<int>(), 0) << m;
      EXPECT_EQ(m.at("phase_swing").get<double>(), 0.0) << m;
    }
  }
  EXPECT_TRUE(r.analysis.at("bifurcations").empty()) << r.analysis.at("bifurcations");
  std::vector<int> count(32, 0);
  for (const auto& s : r.analysis.at("singularities")) ++count.at(s.at("frame").get<size_t>());
  for (size_t f = 0; f < count.size(); ++f) EXPECT_EQ(count[f], 4) << "frame " << f;
  const std::vector<double> source = followed_node_ratios(r.analysis, {-0.5, 0.0, std::sqrt(0.75)}, 32);
  ASSERT_EQ(source.size(), 32u);
  for (size_t f = 0; f < source.size(); ++f) EXPECT_GT(source[f], 1.5) << "the source at frame " << f;
  expect_center_followed(r.analysis, {0.5, 0.0, std::sqrt(0.75)}, 32);
  // The field goes on through the middle key frame (t = 0.5, held at frame 16, t = 0.516,
  // where the two intervals now meet): its change across frame 16 is of the order of the
  // rest (6.9 and 7.7 against a median 6.3; 0.4 when each interval eased in and out, and
  // 3.4 then 10.9 while the intervals met at t = 0.5, half a frame off).
  EXPECT_NEAR(r.topology.at("intervals").at(0).at("interval").at(1).get<double>(), 16.0 / 31, 1e-12);
  std::vector<double> change = r.analysis.at("coherence").get<std::vector<double>>();
  ASSERT_EQ(change.size(), 31u);
  std::vector<double> sorted = change;
  std::sort(sorted.begin(), sorted.end());
  const double median = sorted[sorted.size() / 2];
  for (const size_t j : {size_t{15}, size_t{16}})
    EXPECT_GT(change[j], 0.7 * median) << "the change " << j << " → " << j + 1 << " of " << r.analysis.at("coherence");
  // The far hemisphere (z < 0: the focus alone, far from the knot) turns steadily: its mean
  // direction turn from frame to frame changes by at most 0.45 of its median between one
  // step and the next (0.26 now; 0.70 when each node's phase λ_j, read in the face holding
  // it and jumping where the node crosses an edge, was spread to the far field as it is).
  const NpyArray field = read_npy((dir / "out" / "field.npy").string());
  const NpyArray verts = read_npy((dir / "out" / "vertices.npy").string());
  ASSERT_EQ(field.shape.size(), 3u);
  const size_t frames = field.shape[0], nv = field.shape[1];
  std::vector<double> turns;
  for (size_t f = 0; f + 1 < frames; ++f) {
    double sum = 0;
    int counted = 0;
    for (size_t v = 0; v < nv; ++v) {
      if (verts.values[3 * v + 2] >= 0) continue;
      const double* a = &field.values[3 * (f * nv + v)];
      const double* b = &field.values[3 * ((f + 1) * nv + v)];
      const double na = std::hypot(a[0], a[1], a[2]), nb = std::hypot(b[0], b[1], b[2]);
      if (!(na > 0 && nb > 0)) continue;
      sum += std::acos(std::clamp((a[0] * b[0] + a[1] * b[1] + a[2] * b[2]) / (na * nb), -1.0, 1.0));
      ++counted;
    }
    ASSERT_GT(counted, 0);
    turns.push_back(sum / counted);
  }
  std::vector<double> sorted_turns = turns;
  std::sort(sorted_turns.begin(), sorted_turns.end());
  const double median_turn = sorted_turns[sorted_turns.size() / 2];
  for (size_t j = 0; j + 1 < turns.size(); ++j)
    EXPECT_LE(std::abs(turns[j + 1] - turns[j]), 0.45 * median_turn)
        << "the far hemisphere's turn " << j << " → " << j + 1 << " and the next: " << turns[j] << ", " << turns[j + 1];
}

// Example 26's knot_bunny.json: the knot on CGAL's bunny. Its paths are curves on the
// surface; with the plain ratio R = (z − p(t)) / (z − p(t₀)) the guide's frames held an extra
// pair where a very anisotropic focus (|β|/|α| 0.86) leaves or reaches its place on its 0.97
// path across the bunny (frame 1 with the wider ramp, frame 29 with the narrow one), so the
// interval was left free. The shaped ratio (the key frames' own linear parts in R,
// SurfaceGuide::Path::a) has no such frame: the interval is guided, every frame holds the
// plan's singularities (6, and 8 once the pair is created) and the analysis shows the
// planned creation alone of the saddle–node events, half a frame after t = 0.5 (the
// designed center's Hopf events aside), at the template the report gives: the middle of the
// pair's ends in the pair's chart, where the guide puts it (the surface middle the plan
// first chose is 0.027 from it, beyond the design check's 0.020, and the check then called
// the planned creation "not asked for"). Release only: ~4 s there (12 s before session 17).
TEST(CliKeyframeTopology, Example26KnotOnTheBunnyIsGuidedWithThePlannedCreationAlone) {
#ifdef TVF_SANITIZE_BUILD
  GTEST_SKIP() << "the bunny's guide is ~4 s in release; its code runs under the sanitizers in KeyframeTopology.*";
#endif
  if (!fs::exists(test::source_dir() + "/examples/04_surface_mesh/bunny.off"))
    GTEST_SKIP() << "examples/04_surface_mesh/bunny.off is not extracted (scripts/install-deps.sh does it)";
  test::TempDir dir;
  const std::string scene = test::source_dir() + "/examples/26_keyframe_topology/knot_bunny.json";
  const GeneratedAndAnalysed r = generate_and_analyze(dir, scene, " --no-plots");
  ASSERT_FALSE(r.analysis.is_null());
  const nlohmann::json& i = r.topology.at("intervals").at(0);
  EXPECT_TRUE(i.at("guided").get<bool>()) << i;
  EXPECT_FALSE(i.at("fallback").get<bool>()) << i;
  EXPECT_EQ(r.generated.output.find("not guided"), std::string::npos) << r.generated.output;
  std::vector<int> count(32, 0);
  for (const auto& s : r.analysis.at("singularities")) ++count.at(s.at("frame").get<size_t>());
  for (size_t f = 0; f < count.size(); ++f) EXPECT_EQ(count[f], f <= 15 ? 6 : 8) << "frame " << f;
  int saddle_node = 0;
  for (const auto& b : r.analysis.at("bifurcations")) {
    if (b.at("kind") == "hopf") continue;
    ++saddle_node;
    EXPECT_EQ(b.at("kind"), "creation") << b;
    EXPECT_NEAR(b.at("t").get<double>(), 0.5, 1.0 / 31) << b;
  }
  EXPECT_EQ(saddle_node, 1) << r.analysis.at("bifurcations");
  EXPECT_NE(r.analysed.output.find("1 bifurcations planned, 0 not asked for"), std::string::npos)
      << r.analysed.output;
  // The designed center stays one: the source's phase ends a whole turn, the center's 0, and
  // the local correction keeps the center alone (≤ 0.012; before session 23 neither was kept).
  expect_center_followed(r.analysis, {0.15, -0.09, 0.33}, 32);
}

// Example 26's stability.json: a source in the first key frame, a sink near it in the
// second. Matched across stability as the last resort, the node is carried through a
// center: `tvf generate` says so, keyframe_topology.json gives its to_type, and the
// analysis finds three singularities in every frame and no bifurcation ("free": two).
TEST(CliKeyframeTopology, Example26NodeChangesStabilityWithoutABifurcation) {
  test::TempDir dir;
  const std::string scene = test::source_dir() + "/examples/26_keyframe_topology/stability.json";
  const GeneratedAndAnalysed r = generate_and_analyze(dir, scene, " --no-plots");
  ASSERT_FALSE(r.analysis.is_null());
  EXPECT_NE(r.generated.output.find("3 matched (1 changing stability through a center), 0 pairs created"),
            std::string::npos)
      << r.generated.output;
  const nlohmann::json& i = r.topology.at("intervals").at(0);
  EXPECT_TRUE(i.at("guided").get<bool>()) << i;
  int turning = 0;
  for (const auto& m : i.at("matched"))
    if (m.at("type") != m.at("to_type")) {
      ++turning;
      EXPECT_EQ(m.at("type"), "source") << m;
      EXPECT_EQ(m.at("to_type"), "sink") << m;
    }
  EXPECT_EQ(turning, 1) << i;
  EXPECT_TRUE(r.analysis.at("bifurcations").empty()) << r.analysis.at("bifurcations");
  // The key frames' saddle that no element names is the plan's matched path, not an extra.
  EXPECT_NE(r.analysed.output.find("designed 4 singularities, 0 bifurcations: all found; no extras"), std::string::npos)
      << r.analysed.output;
  std::vector<int> count(60, 0);
  for (const auto& s : r.analysis.at("singularities")) ++count.at(s.at("frame").get<size_t>());
  for (size_t f = 0; f < count.size(); ++f) EXPECT_EQ(count[f], 3) << "frame " << f;

  test::TempDir free_dir;
  nlohmann::json free = read_json(scene);
  free["solver"]["keyframe_topology"] = "free";
  test::write_text(free_dir / "free.json", free.dump());
  const GeneratedAndAnalysed f = generate_and_analyze(free_dir, (free_dir / "free.json").string(), " --no-plots");
  ASSERT_FALSE(f.analysis.is_null());
  EXPECT_GE(f.analysis.at("bifurcations").size(), 2u);
}

}  // namespace
}  // namespace tvf
