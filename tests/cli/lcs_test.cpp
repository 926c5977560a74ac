// `tvf ftle`, `tvf streaklines` and `tvf timelines` as a user meets them (DESIGN §12): the
// files and their shapes, the closed form of a rotation's streakline, a scene as input, and
// bad options refused with one sentence, a non-zero exit and nothing written.
#include "support/test_fields.h"
#include "support/test_paths.h"
#include "tvf/field/field_io.h"
#include "tvf/field/npy.h"
#include "tvf/mesh/grid.h"
#include "tvf/render/image.h"

#include <gtest/gtest.h>
#include <nlohmann/json.hpp>

#include <algorithm>
#include <cmath>
#include <filesystem>
#include <string>

namespace tvf {
namespace {

namespace fs = std::filesystem;
using test::count_lines;
using test::quoted;
using test::run_tvf;
using test::TempDir;

// A field file of V(x, t) on a grid, in `dir`.
void write_field(const fs::path& dir, const GridSpec& spec, TimeSampling time,
                 const std::function<Vec3(const Vec3&, double)>& v) {
  fs::create_directories(dir);
  const Mesh grid = make_grid(spec);
  const TangentBundle bundle(grid);
  save_field_file((dir / "field.tvff").string(), grid, test::field_from(bundle, time, v), nullptr);
}

TEST(CliLcs, FtleOfTheDoubleGyreWritesArraysPicturesAndVtk) {
  TempDir dir;
  write_field(dir / "gyre", GridSpec{41, 21, {0, 0}, {2, 1}}, TimeSampling{0, 10, 41}, test::double_gyre);
  const auto r = run_tvf("ftle " + quoted(dir / "gyre") + " --horizon 5 -o " + quoted(dir / "ftle") +
                         " --pictures 2 -s 200 --dt 0.25");
  ASSERT_EQ(r.exit_code, 0) << r.output;
  // The note on the 20 + 20 frames whose window was cut, the summary, the folder.
  EXPECT_EQ(count_lines(r.output), 3) << r.output;
  EXPECT_NE(r.output.find("20 forward and 20 backward frames reach past the time range"), std::string::npos)
      << r.output;
  for (const char* name : {"ftle_forward", "ftle_backward"}) {
    const NpyArray a = read_npy((dir / "ftle" / (std::string(name) + ".npy")).string());
    EXPECT_EQ(a.dtype, "<f4");
    ASSERT_EQ(a.shape, (std::vector<size_t>{41, 861}));
    // The walls hold the flow: every frame with a window has a value everywhere.
    const size_t first = std::string(name) == "ftle_forward" ? 0 : 40;
    for (size_t v = 0; v < 861; ++v) EXPECT_FALSE(std::isnan(a.values[first * 861 + v])) << name << " " << v;
  }
  const nlohmann::json meta = nlohmann::json::parse(test::read_text(dir / "ftle" / "ftle.json"));
  EXPECT_EQ(meta["horizon"], 5.0);
  EXPECT_EQ(meta["forward"]["cut_frames"], 20);
  EXPECT_EQ(meta["forward"]["span"][39], 0.25);  // t = 9.75: cut to the range's end
  EXPECT_EQ(meta["forward"]["span"][40], 0.0);
  for (const char* f : {"ftle_forward_0000.png", "ftle_forward_0039.png", "ftle_backward_0001.png",
                        "ftle_backward_0040.png", "ftle.pvd", "ftle_0040.vtu"})
    EXPECT_TRUE(fs::exists(dir / "ftle" / f)) << f;
  // NaN for the frames that do not fit.
  const auto n = run_tvf("ftle " + quoted(dir / "gyre") + " --horizon 5 -o " + quoted(dir / "nan") +
                         " --beyond-range nan --direction forward --pictures 0 --no-vtk -q --dt 0.25");
  ASSERT_EQ(n.exit_code, 0) << n.output;
  EXPECT_FALSE(fs::exists(dir / "nan" / "ftle_backward.npy"));
  const NpyArray f = read_npy((dir / "nan" / "ftle_forward.npy").string());
  EXPECT_FALSE(std::isnan(f.values[20 * 861 + 400]));
  EXPECT_TRUE(std::isnan(f.values[21 * 861 + 400]));
}

TEST(CliLcs, FtleIntoTheFolderOfAnEarlierRunLeavesOnlyItsOwnFiles) {
  // Every 10th frame, then every 20th backward alone into the same folder: the earlier run's
  // other frames (pictures, VTK files: ParaView groups ftle_*.vtu as one series) and its
  // forward arrays go; a file of the user's stays. Each VTK file is numbered by its frame,
  // as the pictures are.
  TempDir dir;
  write_field(dir / "gyre", GridSpec{41, 21, {0, 0}, {2, 1}}, TimeSampling{0, 10, 41}, test::double_gyre);
  const std::string run = "ftle " + quoted(dir / "gyre") + " --horizon 2 --dt 0.25 -q -s 64 -o " + quoted(dir / "out");
  ASSERT_EQ(run_tvf(run + " --every 10 --pictures 5").exit_code, 0);
  // json, pvd, 5 vtu, 2 npy, 4 + 4 png (frame 40 has no forward window, frame 0 no backward one)
  EXPECT_EQ(test::listing(dir / "out").size(), 17u);
  EXPECT_TRUE(fs::exists(dir / "out" / "ftle_0030.vtu"));
  test::write_text(dir / "out" / "notes.txt", "mine");
  const auto r = run_tvf(run + " --every 20 --pictures 2 --direction backward");
  ASSERT_EQ(r.exit_code, 0) << r.output;
  EXPECT_EQ(test::listing(dir / "out"),
            (std::vector<std::string>{"ftle.json", "ftle.pvd", "ftle_0000.vtu", "ftle_0020.vtu", "ftle_0040.vtu",
                                      "ftle_backward.npy", "ftle_backward_0020.png", "ftle_backward_0040.png",
                                      "notes.txt"}));
  const std::string pvd = test::read_text(dir / "out" / "ftle.pvd");
  EXPECT_NE(pvd.find("timestep=\"5\" part=\"0\" file=\"ftle_0020.vtu\""), std::string::npos) << pvd;
}

TEST(CliLcs, FtleComposedIsCloseToDirect) {
  // --compose (flow-map composition, planar grids): the same arrays to a small error, the
  // same cut windows, and ftle.json says how they were made.
  TempDir dir;
  write_field(dir / "gyre", GridSpec{41, 21, {0, 0}, {2, 1}}, TimeSampling{0, 10, 41}, test::double_gyre);
  const std::string common = " --horizon 5 --direction forward --pictures 0 --no-vtk -q --dt 0.125 -o ";
  const auto a = run_tvf("ftle " + quoted(dir / "gyre") + common + quoted(dir / "direct"));
  const auto b = run_tvf("ftle " + quoted(dir / "gyre") + common + quoted(dir / "composed") + " --compose");
  ASSERT_EQ(a.exit_code, 0) << a.output;
  ASSERT_EQ(b.exit_code, 0) << b.output;
  const NpyArray d = read_npy((dir / "direct" / "ftle_forward.npy").string());
  const NpyArray c = read_npy((dir / "composed" / "ftle_forward.npy").string());
  ASSERT_EQ(c.shape, d.shape);
  std::vector<double> errors;
  for (size_t i = 0; i < d.values.size(); ++i) {
    ASSERT_EQ(std::isnan(c.values[i]), std::isnan(d.values[i])) << i;  // frame 40: nothing to integrate
    if (!std::isnan(d.values[i])) errors.push_back(std::abs(static_cast<double>(c.values[i]) - d.values[i]));
  }
  ASSERT_EQ(errors.size(), 40u * 861u);
  std::sort(errors.begin(), errors.end());
  EXPECT_LT(errors[errors.size() / 2], 0.005);
  EXPECT_LT(errors[errors.size() * 9 / 10], 0.02);
  const nlohmann::json meta = nlohmann::json::parse(test::read_text(dir / "composed" / "ftle.json"));
  EXPECT_EQ(meta["compose"], true);
  EXPECT_EQ(meta["forward"]["cut_frames"], 20);
  EXPECT_FALSE(nlohmann::json::parse(test::read_text(dir / "direct" / "ftle.json")).contains("compose"));
}

TEST(CliLcs, StreaklineOfARotationIsTheCircleThroughTheSeed) {
  TempDir dir;
  write_field(dir / "rot", GridSpec{33, 33, {-1, -1}, {1, 1}}, TimeSampling{0, 2, 9},
              [](const Vec3& x, double) { return Vec3(-x.y(), x.x(), 0); });
  // Into a folder that does not exist yet: made, as the other commands make theirs.
  const auto r = run_tvf("streaklines " + quoted(dir / "rot") + " --seed 0.5 0 --from 0.5 --to 2 " +
                         "--release-spacing 0.1 -s 200 -o " + quoted(dir / "new" / "streak.json"));
  ASSERT_EQ(r.exit_code, 0) << r.output;
  EXPECT_EQ(count_lines(r.output), 1) << r.output;
  EXPECT_TRUE(fs::exists(dir / "new" / "streak.png"));
  const nlohmann::json j = nlohmann::json::parse(test::read_text(dir / "new" / "streak.json"));
  EXPECT_EQ(j["t"], 2.0);
  ASSERT_EQ(j["points"].size(), 16u);
  for (const auto& p : j["points"]) {
    const double angle = 2.0 - p[3].get<double>();
    EXPECT_NEAR(p[0].get<double>(), 0.5 * std::cos(angle), 1e-4);
    EXPECT_NEAR(p[1].get<double>(), 0.5 * std::sin(angle), 1e-4);
    EXPECT_EQ(p[2], 0.0);
  }
  // Neighbours 0.1 rad apart on the circle of radius 0.5: within a mean edge length.
  EXPECT_NEAR(j["largest_gap"].get<double>(), std::sin(0.05), 1e-4);
  EXPECT_EQ(j["unresolved"], 0);
  EXPECT_TRUE(j["unresolved_by"].is_null());
  EXPECT_GT(j["resolution"].get<double>(), j["largest_gap"].get<double>());
  // Asked for neighbours a millionth apart, the 20,000 added releases fall short: said so.
  const auto fine = run_tvf("streaklines " + quoted(dir / "rot") + " --seed 0.5 0 --from 0.5 --to 2 " +
                            "--max-gap 1e-6 --no-picture -q -o " + quoted(dir / "fine.json"));
  ASSERT_EQ(fine.exit_code, 0) << fine.output;
  EXPECT_NE(fine.output.find("needs more than 20000 added releases to keep neighbours within 1e-06 of each other at "
                             "t = 2"),
            std::string::npos)
      << fine.output;
  EXPECT_NE(fine.output.find("give a smaller --release-spacing or a larger --max-gap"), std::string::npos)
      << fine.output;
  const nlohmann::json fj = nlohmann::json::parse(test::read_text(dir / "fine.json"));
  EXPECT_EQ(fj["resolution"], 1e-6);
  EXPECT_GT(fj["unresolved"].get<int>(), 0);
  EXPECT_EQ(fj["unresolved_by"], "particles");
  // A timeline across the centre turns with it: by 2 radians from t = 0.
  const auto t = run_tvf("timelines " + quoted(dir / "rot") + " --line -0.5 0 0.5 0 --count 11 --max-gap 1 --to 2 -s 200 -o " +
                         quoted(dir / "time.json"));
  ASSERT_EQ(t.exit_code, 0) << t.output;
  const nlohmann::json tl = nlohmann::json::parse(test::read_text(dir / "time.json"));
  EXPECT_EQ(tl["from"], 0.0);
  ASSERT_EQ(tl["points"].size(), 11u);
  for (const auto& p : tl["points"]) {
    const double s = -0.5 + p[3].get<double>();
    EXPECT_NEAR(p[0].get<double>(), s * std::cos(2.0), 1e-4);
    EXPECT_NEAR(p[1].get<double>(), s * std::sin(2.0), 1e-4);
  }
  EXPECT_TRUE(fs::exists(dir / "time.png"));
}

TEST(CliLcs, TakesASceneAsAnalyzeDoes) {
  TempDir dir;
  test::write_text(dir / "scene.json", R"({"tvf": 1,
    "domain": {"grid": {"size": [17, 17], "min": [-1, -1], "max": [1, 1]}},
    "time": {"frames": 5, "range": [0, 1]},
    "elements": [{"kind": "singular", "type": "ccw_center", "path": [[0, 0, 0]]}]})");
  const auto r = run_tvf("streaklines " + quoted(dir / "scene.json") + " --seed 0.3 0.2 -q --no-picture -o " +
                         quoted(dir / "s.json"));
  ASSERT_EQ(r.exit_code, 0) << r.output;
  EXPECT_EQ(r.output, "");
  const nlohmann::json j = nlohmann::json::parse(test::read_text(dir / "s.json"));
  EXPECT_EQ(j["t"], 1.0);
  EXPECT_GT(j["points"].size(), 10u);
  EXPECT_FALSE(fs::exists(dir / "s.png"));
}

TEST(CliLcs, StreaklinesOfASketchedElementDrawTheSketchAndMeasureTheDistance) {
  // A straight sketch from (−0.5, −0.3) to (0.5, −0.3) released over [0.2, 0.8] (issue 20):
  // --element 1 takes its seed and interval and reports how far the traced dye is from it.
  TempDir dir;
  test::write_text(dir / "scene.json", R"({"tvf": 1, "generator": "spacetime",
    "domain": {"grid": {"size": [33, 33], "min": [-1, -1], "max": [1, 1]}},
    "time": {"frames": 21, "range": [0, 1]},
    "elements": [{"kind": "singular", "type": "ccw_center", "path": [[0.5, 0.5, 0]]},
                 {"kind": "streakline", "points": [[-0.5, -0.3], [0.5, -0.3]], "t": 0.8, "from": 0.2}]})");
  const auto r = run_tvf("streaklines " + quoted(dir / "scene.json") + " --element 1 -s 64 -o " + quoted(dir / "s.json"));
  ASSERT_EQ(r.exit_code, 0) << r.output;
  EXPECT_NE(r.output.find("from elements[1]'s sketch: Hausdorff"), std::string::npos) << r.output;
  const nlohmann::json j = nlohmann::json::parse(test::read_text(dir / "s.json"));
  EXPECT_EQ(j["t"], 0.8);
  EXPECT_EQ(j["from"], 0.2);
  EXPECT_EQ(j["seed"], nlohmann::json::parse("[-0.5, -0.3, 0.0]"));
  EXPECT_EQ(j["sketch"]["element"], 1);
  EXPECT_LT(j["sketch"]["hausdorff"].get<double>(), 0.5 * j["sketch"]["mean_edge_length"].get<double>()) << j["sketch"];
  EXPECT_LT(j["sketch"]["frechet"].get<double>(), 0.5 * j["sketch"]["mean_edge_length"].get<double>()) << j["sketch"];
  EXPECT_NE(r.output.find(", Fréchet "), std::string::npos) << r.output;
  EXPECT_TRUE(fs::exists(dir / "s.png"));
  EXPECT_EQ(r.output.find("note:"), std::string::npos) << r.output;
  // Dye to another time than the sketch's: compared all the same, with a note that the
  // distances are then two shapes' difference, not the field's error.
  const auto early = run_tvf("streaklines " + quoted(dir / "scene.json") + " --element 1 --to 0.5 --no-picture -o " +
                             quoted(dir / "early.json"));
  ASSERT_EQ(early.exit_code, 0) << early.output;
  EXPECT_NE(early.output.find("note: the dye released over [0.2, 0.5] is compared with elements[1]'s sketch, drawn "
                              "for [0.2, 0.8]"),
            std::string::npos)
      << early.output;
  const std::pair<std::string, std::string> bad[] = {
      {" --element 0", "--element 0: the scene has no streakline element at that index"},
      {" --element 7", "--element 7: the scene has no streakline element at that index"},
      {"", "--seed is required (or --element, a streakline element of the scene)"},
  };
  for (const auto& [args, message] : bad) {
    const auto b = run_tvf("streaklines " + quoted(dir / "scene.json") + args + " -o " + quoted(dir / "bad.json"));
    EXPECT_NE(b.exit_code, 0) << args;
    EXPECT_EQ(count_lines(b.output), 1) << args << ": " << b.output;
    EXPECT_NE(b.output.find(message), std::string::npos) << args << ": " << b.output;
  }
  EXPECT_FALSE(fs::exists(dir / "bad.json"));
}

TEST(CliLcs, TextureAnimationInjectsDye) {
  // `tvf render texture --streakline X,Y`: the streakline since the first picture drawn in
  // red over the gray texture (gray has red = green); without it no pixel is red.
  TempDir dir;
  write_field(dir / "rot", GridSpec{17, 17, {-1, -1}, {1, 1}}, TimeSampling{0, 2, 9},
              [](const Vec3& x, double) { return Vec3(-x.y(), x.x(), 0); });
  auto reds = [](const Image& img) {
    int n = 0;
    for (const std::uint32_t c : img.pixels) n += static_cast<int>((c >> 16) & 0xFF) > static_cast<int>((c >> 8) & 0xFF) + 80;
    return n;
  };
  const auto r = run_tvf("render texture " + quoted(dir / "rot") + " --streakline 0.5,0 --range 8:8 -s 128 -q -o " +
                         quoted(dir / "dye"));
  ASSERT_EQ(r.exit_code, 0) << r.output;
  EXPECT_GT(reds(read_png((dir / "dye" / "frame_00008.png").string())), 50);
  const auto plain = run_tvf("render texture " + quoted(dir / "rot") + " --range 8:8 -s 128 -q -o " + quoted(dir / "plain"));
  ASSERT_EQ(plain.exit_code, 0) << plain.output;
  EXPECT_EQ(reds(read_png((dir / "plain" / "frame_00008.png").string())), 0);
  const auto bad = run_tvf("render texture " + quoted(dir / "rot") + " --streakline 0.5 -q -o " + quoted(dir / "bad"));
  EXPECT_NE(bad.exit_code, 0);
  EXPECT_EQ(count_lines(bad.output), 1) << bad.output;
  EXPECT_NE(bad.output.find("--streakline 0.5: expected X,Y"), std::string::npos) << bad.output;
  EXPECT_FALSE(fs::exists(dir / "bad"));
}

TEST(CliLcs, TextureAnimationCarriesATimeline) {
  // `tvf render texture --timeline X0,Y0,X1,Y1`: the segment at the first picture, carried
  // by the rotation (−y, x), is the segment turned by t: at t = 2 every light-blue pixel
  // (the gray texture has red = green = blue) lies on the segment turned by 2 radians.
  TempDir dir;
  write_field(dir / "rot", GridSpec{17, 17, {-1, -1}, {1, 1}}, TimeSampling{0, 2, 9},
              [](const Vec3& x, double) { return Vec3(-x.y(), x.x(), 0); });
  const auto r = run_tvf("render texture " + quoted(dir / "rot") + " --timeline -0.5,0,0.5,0 --range 8:8 -s 128 -q -o " +
                         quoted(dir / "line"));
  ASSERT_EQ(r.exit_code, 0) << r.output;
  const Image img = read_png((dir / "line" / "frame_00008.png").string());
  const Vec2 along(std::cos(2.0), std::sin(2.0));
  int blue = 0;
  double farthest = 0;
  for (int row = 0; row < img.height; ++row)
    for (int col = 0; col < img.width; ++col) {
      const std::uint32_t c = img.pixels[static_cast<size_t>(row) * img.width + col];
      const int red = (c >> 16) & 0xFF, green = (c >> 8) & 0xFF, b = c & 0xFF;
      if (b < red + 100 || green < red + 60) continue;
      ++blue;
      // Pixel centres in the domain [−1, 1]², y up.
      const Vec2 x(-1 + 2 * (col + 0.5) / img.width, 1 - 2 * (row + 0.5) / img.height);
      const double s = std::clamp(x.dot(along), -0.5, 0.5);
      farthest = std::max(farthest, (x - s * along).norm());
    }
  EXPECT_GT(blue, 40);
  EXPECT_LT(farthest, 0.05);
  // Both renderers take it; a malformed or misplaced one is one sentence.
  const auto leaves = run_tvf("render particles " + quoted(dir / "rot") + " --timeline -0.5,0,0.5,0 --frames 3 -s 128 -q -o " +
                              quoted(dir / "leaves"));
  EXPECT_EQ(leaves.exit_code, 0) << leaves.output;
  EXPECT_TRUE(fs::exists(dir / "leaves" / "frame_00002.png"));
  const std::pair<std::string, std::string> bad[] = {
      {"--timeline 0,0,0.5", "--timeline 0,0,0.5: expected X0,Y0,X1,Y1 (two points of the planar domain)"},
      {"--timeline 0,0,x,1", "--timeline 0,0,x,1: expected X0,Y0,X1,Y1"},
      {"--timeline 0,0,5,0", "the timeline's last point (5, 0) is outside the domain"},
      {"--timeline 0.2,0.2,0.2,0.2", "are one point of the domain"},
  };
  for (const auto& [option, message] : bad) {
    const auto out = run_tvf("render texture " + quoted(dir / "rot") + " " + option + " -q -o " + quoted(dir / "bad"));
    EXPECT_NE(out.exit_code, 0) << option;
    EXPECT_EQ(count_lines(out.output), 1) << out.output;
    EXPECT_NE(out.output.find(message), std::string::npos) << out.output;
    EXPECT_FALSE(fs::exists(dir / "bad")) << option;
  }
}

TEST(CliLcs, RenderersWarnOfATimelineTornApart) {
  // The saddle V = (27x, −27y): a timeline across its stable separatrix x = 0 is torn apart
  // at t = 1 (Dye.RecordsWhereATimelineWasNotResolved). Both renderers draw it and say once
  // which line, at how many pictures and why (stderr, even with -q); one that does not cross
  // the separatrix says nothing.
  TempDir dir;
  write_field(dir / "saddle", GridSpec{21, 21, {-1, -1}, {1, 1}}, TimeSampling{0, 1, 11},
              [](const Vec3& x, double) { return Vec3(27 * x.x(), -27 * x.y(), 0); });
  for (const char* renderer : {"texture", "particles"}) {
    const auto torn = run_tvf(std::string("render ") + renderer + " " + quoted(dir / "saddle") +
                              " --timeline=-0.3,0.6,0.5,0.6 -s 64 -q -o " + quoted(dir / (std::string(renderer) + "_torn")));
    ASSERT_EQ(torn.exit_code, 0) << torn.output;
    EXPECT_EQ(count_lines(torn.output), 1) << torn.output;
    EXPECT_NE(torn.output.find("warning: --timeline -0.3,0.6,0.5,0.6 is not resolved at 1 of 11 pictures, from t = 1: "
                               "at t = 1 neighbours are up to"),
              std::string::npos)
        << renderer << ": " << torn.output;
    EXPECT_NE(torn.output.find("the flow tears it apart"), std::string::npos) << torn.output;
    const auto whole = run_tvf(std::string("render ") + renderer + " " + quoted(dir / "saddle") +
                               " --timeline 0.2,0.5,0.6,0.5 -s 64 -q -o " + quoted(dir / (std::string(renderer) + "_whole")));
    ASSERT_EQ(whole.exit_code, 0) << whole.output;
    EXPECT_EQ(whole.output, "") << renderer;
  }
}

TEST(CliLcs, BadOptionsAreOneSentenceAndLeaveNothing) {
  TempDir dir;
  write_field(dir / "f", GridSpec{9, 9, {-1, -1}, {1, 1}}, TimeSampling{0, 1, 5},
              [](const Vec3& x, double) { return Vec3(-x.y(), x.x(), 0); });
  const std::string in = quoted(dir / "f");
  // A field far too fast for its time range (a billion edge lengths a frame): refused,
  // naming the input, not walked round the domain.
  write_field(dir / "fast", GridSpec{9, 9, {-1, -1}, {1, 1}}, TimeSampling{0, 1, 5},
              [](const Vec3& x, double) -> Vec3 { return 1e9 * Vec3(-x.y(), x.x(), 0); });
  const std::string fast = quoted(dir / "fast");
  const std::pair<std::string, std::string> cases[] = {
      {"streaklines " + fast + " --seed 0.5 0 -o " + quoted(dir / "out.json"),
       (dir / "fast").string() + ": the field's speed"},
      {"ftle " + fast + " --horizon 0.5 -o " + quoted(dir / "out"), "too fast for its time range"},
      {"timelines " + fast + " --line 0 0 0.5 0 -o " + quoted(dir / "out.json"), "too fast for its time range"},
      {"ftle " + in + " --horizon 0 -o " + quoted(dir / "out"), "--horizon 0: must be a positive time"},
      {"ftle " + in + " --horizon -2 -o " + quoted(dir / "out"), "--horizon -2: must be a positive time"},
      {"ftle " + quoted(dir / "nothing") + " --horizon 1 -o " + quoted(dir / "out"), "no such file or folder"},
      {"streaklines " + in + " --seed 3 0 -o " + quoted(dir / "out.json"), "seed (3, 0) is outside the domain"},
      {"streaklines " + in + " --seed 0 0 --from 0.8 --to 0.2 -o " + quoted(dir / "out.json"),
       "--from 0.8 is after --to 0.2"},
      {"streaklines " + in + " --seed 0 0 --to 1.5 -o " + quoted(dir / "out.json"),
       "--to 1.5 is outside the field's time range [0, 1]"},
      {"streaklines " + in + " --seed 0 0 --release-spacing -1 -o " + quoted(dir / "out.json"),
       "--release-spacing -1: must be a positive time"},
      // 0 given is no one's spacing or step (left out, the option takes its default).
      {"streaklines " + in + " --seed 0 0 --release-spacing 0 -o " + quoted(dir / "out.json"),
       "--release-spacing 0: must be a positive time"},
      {"ftle " + in + " --horizon 0.5 --dt 0 -o " + quoted(dir / "out"), "--dt 0: must be a positive time"},
      // What would exhaust memory or never end: refused at once, naming the value.
      {"streaklines " + in + " --seed 0 0 --release-spacing 1e-9 -o " + quoted(dir / "out.json"),
       "release spacing 1e-09 would release 1e+09 particles over [0, 1], more than 1e+06"},
      {"ftle " + in + " --horizon 0.5 --dt 1e-12 -o " + quoted(dir / "out"),
       "flow map time step 1e-12 would take 1e+12 RK4 steps"},
      {"timelines " + in + " --line 0 0 0.5 0 --dt 1e-12 -o " + quoted(dir / "out.json"),
       "flow map time step 1e-12 would take 1e+12 RK4 steps"},
      {"timelines " + in + " --line 0 0 0.5 0 --count 2000000000 -o " + quoted(dir / "out.json"),
       "--count 2000000000: a timeline has 2 to 20000 particles"},
      {"timelines " + in + " --line 0 0 5 0 -o " + quoted(dir / "out.json"), "is outside the domain"},
      {"timelines " + in + " --line 0.2 0.2 0.2 0.2 -o " + quoted(dir / "out.json"),
       "the timeline's ends (0.2, 0.2) and (0.2, 0.2) are one point of the domain: give two different points"},
      {"streaklines " + in + " --seed 0 0 --max-gap 0 -o " + quoted(dir / "out.json"),
       "--max-gap 0: must be a positive distance"},
      {"timelines " + in + " --line 0 0 0.5 0 --max-gap inf -o " + quoted(dir / "out.json"),
       "--max-gap inf: must be a positive distance"},
      // A Z off the plane (z = 0) is a mistake, not a point to project: refused, not traced
      // from (0.5, 0) (nor called outside the domain for a huge Z).
      {"streaklines " + in + " --seed 0.5 0 1 -o " + quoted(dir / "out.json"),
       "--seed: Z = 1 is off the planar domain, which lies at z = 0: give X Y"},
      {"streaklines " + in + " --seed 0.5 0 1e8 -o " + quoted(dir / "out.json"), "--seed: Z = 100000000 is off"},
      {"timelines " + in + " --line 0 0 0 0.5 0 0.25 -o " + quoted(dir / "out.json"), "--line: Z = 0.25 is off"},
      {"render texture " + in + " --streakline 0.5,0,4 -o " + quoted(dir / "out"),
       "--streakline 0.5,0,4: Z = 4 is off the planar domain"},
      // The surface pictures' camera.
      {"timelines " + in + " --line 0 0 0.5 0 --view 0,0,0 -o " + quoted(dir / "out.json"),
       "--view 0,0,0: must be a direction, three finite numbers not all zero"},
      {"ftle " + in + " --horizon 0.5 --up 1,nan,0 -o " + quoted(dir / "out"), "--up 1,nan,0: must be a direction"},
      {"ftle " + in + " --horizon 1e-300 -o " + quoted(dir / "out"), "give a horizon of at least"},
      {"timelines " + in + " --line 0 0 0.5 0 --from -1 -o " + quoted(dir / "out.json"),
       "--from -1 is outside the field's time range"},
      // Outputs refused before the work: a folder given as the file, a file in the way.
      {"streaklines " + in + " --seed 0.5 0 -o " + in, (dir / "f").string() + ": is a folder; give the name"},
      {"timelines " + in + " --line 0 0 0.5 0 -o " + quoted(dir / "f" / "field.tvff" / "out.json"),
       "field.tvff is not a folder"},
  };
  for (const auto& [args, message] : cases) {
    const auto r = run_tvf(args);
    EXPECT_NE(r.exit_code, 0) << args;
    EXPECT_EQ(count_lines(r.output), 1) << args << ": " << r.output;
    EXPECT_NE(r.output.find(message), std::string::npos) << args << ": " << r.output;
  }
  EXPECT_FALSE(fs::exists(dir / "out"));
  EXPECT_FALSE(fs::exists(dir / "out.json"));
  EXPECT_FALSE(fs::exists(dir / "out.png"));
}

}  // namespace
}  // namespace tvf
