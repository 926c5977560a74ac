// `tvf render painterly | crowd | particles | grass` as a user meets them: frames, video and CSV
// from a scene, one clear sentence for a bad input, and no partial output.
#include "support/test_paths.h"

#include "tvf/render/image.h"

#include <gtest/gtest.h>

#include <algorithm>
#include <filesystem>
#include <fstream>
#include <string>

namespace tvf {
namespace {

namespace fs = std::filesystem;
using test::count_lines;
using test::run_tvf;
using test::quoted;
using test::TempDir;

constexpr const char* kScene = R"({"tvf": 1,
  "domain": {"grid": {"size": [17, 17], "min": [-1, -1], "max": [1, 1]}},
  "time": {"frames": 5, "range": [0, 1]},
  "elements": [{"kind": "singular", "type": "ccw_center", "path": [[-0.3, 0, 0], [0.3, 0, 1]]}]})";

int count_pngs(const fs::path& dir) {
  int n = 0;
  for (const auto& e : fs::directory_iterator(dir)) n += e.path().extension() == ".png";
  return n;
}

TEST(CliRenderApps, PainterlyFramesFromAPictureAndAMask) {
  TempDir dir;
  test::write_text(dir / "scene.json", kScene);
  Image picture(64, 48), mask(64, 48);
  for (int y = 0; y < 48; ++y)
    for (int x = 0; x < 64; ++x) {
      picture.at(x, y) = rgb(static_cast<std::uint8_t>(4 * x), static_cast<std::uint8_t>(5 * y), 128);
      mask.at(x, y) = y > 24 ? 0x00FFFFFFu : 0u;
    }
  write_png((dir / "picture.png").string(), picture);
  write_png((dir / "mask.png").string(), mask);
  const auto r = run_tvf("render painterly " + quoted(dir / "scene.json") + " --image " + quoted(dir / "picture.png") +
                         " --mask " + quoted(dir / "mask.png") + " -o " + quoted(dir / "frames") +
                         " --stroke-width 3 --stroke-length 8 --density 1.5");
  ASSERT_EQ(r.exit_code, 0) << r.output;
  EXPECT_NE(r.output.find("rendered 5 painterly frames of 64×48"), std::string::npos) << r.output;
  EXPECT_EQ(count_pngs(dir / "frames"), 5);
  const Image f = read_png((dir / "frames" / "frame_00004.png").string());
  EXPECT_EQ(f.width, 64);
  EXPECT_EQ(f.height, 48);

  // A missing picture: one sentence naming it, nothing written.
  const auto m = run_tvf("render painterly " + quoted(dir / "scene.json") + " --image " + quoted(dir / "nope.png") +
                         " -o " + quoted(dir / "out"));
  EXPECT_NE(m.exit_code, 0);
  EXPECT_EQ(count_lines(m.output), 1) << m.output;
  EXPECT_NE(m.output.find("nope.png"), std::string::npos) << m.output;
  EXPECT_FALSE(fs::exists(dir / "out"));
  const auto d = run_tvf("render painterly " + quoted(dir / "scene.json") + " --image " + quoted(dir / "picture.png") +
                         " -o " + quoted(dir / "out") + " --density 0");
  EXPECT_NE(d.exit_code, 0);
  EXPECT_NE(d.output.find("density"), std::string::npos) << d.output;
  EXPECT_FALSE(fs::exists(dir / "out"));
}

TEST(CliRenderApps, CrowdTrajectoriesAsCsvAndFrames) {
  TempDir dir;
  test::write_text(dir / "scene.json", kScene);
  test::write_text(dir / "crowd.json", R"({"agents": 6, "speed": 4, "weights": {"goal": 1, "field": 0},
    "start": [{"rectangle": {"min": [-0.9, -0.2], "max": [-0.7, 0.2]}}],
    "goals": [{"circle": {"center": [0.8, 0], "radius": 0.15}}],
    "obstacles": [{"circle": {"center": [0, 0], "radius": 0.3}}]})");
  const auto r = run_tvf("render crowd " + quoted(dir / "scene.json") + " --crowd " + quoted(dir / "crowd.json") +
                         " -o " + quoted(dir / "frames") + " -o " + quoted(dir / "paths.csv") + " --size 100 --frames 30");
  ASSERT_EQ(r.exit_code, 0) << r.output;
  EXPECT_NE(r.output.find("6 of 6 agents reached a goal"), std::string::npos) << r.output;
  EXPECT_EQ(count_pngs(dir / "frames"), 30);
  std::ifstream csv(dir / "paths.csv");
  std::string header;
  std::getline(csv, header);
  EXPECT_EQ(header, "agent,frame,t,x,y,arrived");
  int rows = 0;
  for (std::string line; std::getline(csv, line);) ++rows;
  EXPECT_EQ(rows, 6 * 30);

  test::write_text(dir / "bad.json", R"({"agents": 6, "start": [], "goals": [{"circle": {"center": [0, 0]}}]})");
  const auto b = run_tvf("render crowd " + quoted(dir / "scene.json") + " --crowd " + quoted(dir / "bad.json") +
                         " -o " + quoted(dir / "out.csv"));
  EXPECT_NE(b.exit_code, 0);
  EXPECT_EQ(count_lines(b.output), 1) << b.output;
  EXPECT_NE(b.output.find("bad.json: goals[0].circle"), std::string::npos) << b.output;
  EXPECT_FALSE(fs::exists(dir / "out.csv"));
}

TEST(CliRenderApps, ParticlesVideoDecodes) {
  if (test::run_command("command -v ffprobe >/dev/null 2>&1").exit_code != 0)
    GTEST_SKIP() << "ffprobe not installed (Debian package ffmpeg)";
  TempDir dir;
  test::write_text(dir / "scene.json", kScene);
  const auto r = run_tvf("render particles " + quoted(dir / "scene.json") + " -o " + quoted(dir / "leaves.mp4") +
                         " --count 200 --size 96 --frames 7 --spin 30 -q");
  ASSERT_EQ(r.exit_code, 0) << r.output;
  EXPECT_EQ(r.output, "");
  const auto p = test::run_command("ffprobe -v error -count_frames -select_streams v:0 -show_entries "
                                   "stream=nb_read_frames -of csv=p=0 " + quoted(dir / "leaves.mp4"));
  ASSERT_EQ(p.exit_code, 0) << p.output;
  EXPECT_EQ(std::stoi(p.output), 7);
  const auto c = run_tvf("render particles " + quoted(dir / "scene.json") + " -o " + quoted(dir / "x.mp4") + " --count 0");
  EXPECT_NE(c.exit_code, 0);
  EXPECT_NE(c.output.find("count"), std::string::npos) << c.output;
  EXPECT_FALSE(fs::exists(dir / "x.mp4"));
}

TEST(CliRenderApps, GrassFramesAndOneSentenceForBadOptions) {
  TempDir dir;
  test::write_text(dir / "scene.json", kScene);
  const auto r = run_tvf("render grass " + quoted(dir / "scene.json") + " -o " + quoted(dir / "frames") +
                         " --count 300 --segments 3 --size 120 --frames 3");
  ASSERT_EQ(r.exit_code, 0) << r.output;
  EXPECT_NE(r.output.find("rendered 3 grass frames"), std::string::npos) << r.output;
  EXPECT_EQ(count_pngs(dir / "frames"), 3);
  const Image frame = read_png((dir / "frames" / "frame_00002.png").string());
  EXPECT_EQ(std::max(frame.width, frame.height), 120);
  for (const std::string bad : {"--segments 0", "--length 2", "--bend -5", "--wind-speed -1", "--elevation 5"}) {
    const auto c = run_tvf("render grass " + quoted(dir / "scene.json") + " -o " + quoted(dir / "bad") + " " + bad);
    EXPECT_NE(c.exit_code, 0) << bad;
    EXPECT_NE(c.output.find("grass option"), std::string::npos) << bad << ": " << c.output;
    EXPECT_EQ(count_lines(c.output), 1) << c.output;
    EXPECT_FALSE(fs::exists(dir / "bad")) << bad;
  }
}

}  // namespace
}  // namespace tvf

namespace tvf {
namespace {

namespace fs = std::filesystem;
using test::count_lines;
using test::quoted;
using test::run_tvf;
using test::TempDir;

// Issue 16: `--frames 0` rendered the field's frames, `-o out.avi` (or `-o c.txt` for a
// crowd) quietly became a folder of PNGs, and a CSV-only crowd reported "frames of 0×0
// pixels". Each is refused in one sentence with nothing written, or does what was asked.
TEST(CliRenderApps, OutputsAndFrameCountsAreWhatWasAsked) {
  TempDir dir;
  test::write_text(dir / "scene.json", kScene);
  test::write_text(dir / "crowd.json", R"({"agents": 4, "speed": 4, "weights": {"goal": 1, "field": 0},
    "start": [{"rectangle": {"min": [-0.9, -0.2], "max": [-0.7, 0.2]}}],
    "goals": [{"circle": {"center": [0.8, 0], "radius": 0.15}}]})");
  const std::string scene = quoted(dir / "scene.json"), crowd = " --crowd " + quoted(dir / "crowd.json");
  struct Case {
    std::string args, says, output;
  };
  const Case cases[] = {
      {"particles " + scene + " -o " + quoted(dir / "a") + " --frames 0", "--frames 0: must be at least 1", "a"},
      {"texture " + scene + " -o " + quoted(dir / "b") + " --frames 0", "--frames 0: must be at least 1", "b"},
      {"painterly " + scene + " -o " + quoted(dir / "c") + " --image x.png --frames -3", "--frames -3", "c"},
      {"particles " + scene + " -o " + quoted(dir / "out.avi"), "cannot write .avi output", "out.avi"},
      {"texture " + scene + " -o " + quoted(dir / "out.gif"), "cannot write .gif output", "out.gif"},
      {"crowd " + scene + crowd + " -o " + quoted(dir / "c.txt"), "cannot write .txt output", "c.txt"},
      {"particles " + scene + " -o " + quoted(dir / "d") + " --time-scale 0", "--time-scale 0", "d"},
      {"grass " + scene + " -o " + quoted(dir / "e") + " --fps 0", "--fps 0", "e"},
  };
  for (const Case& c : cases) {
    const auto r = run_tvf("render " + c.args);
    EXPECT_NE(r.exit_code, 0) << c.args;
    EXPECT_EQ(count_lines(r.output), 1) << c.args << ": " << r.output;
    EXPECT_NE(r.output.find(c.says), std::string::npos) << c.args << ": " << r.output;
    EXPECT_FALSE(fs::exists(dir / c.output)) << c.args;
  }
  // --frames 3 gives three pictures.
  auto r = run_tvf("render particles " + scene + " -o " + quoted(dir / "three") + " --frames 3 --count 20 --size 64");
  ASSERT_EQ(r.exit_code, 0) << r.output;
  int pngs = 0;
  for (const auto& e : fs::directory_iterator(dir / "three")) pngs += e.path().extension() == ".png";
  EXPECT_EQ(pngs, 3);
  // A crowd with trajectories only says what it wrote, not pictures of 0×0 pixels.
  r = run_tvf("render crowd " + scene + crowd + " -o " + quoted(dir / "paths.csv") + " --frames 10");
  ASSERT_EQ(r.exit_code, 0) << r.output;
  EXPECT_EQ(r.output.find("0×0"), std::string::npos) << r.output;
  EXPECT_NE(r.output.find("simulated 10 crowd frames"), std::string::npos) << r.output;
  EXPECT_TRUE(fs::exists(dir / "paths.csv"));
  // The same on a surface: the trajectories with z, and the same report.
  test::write_text(dir / "sphere.json", R"({"tvf": 1, "domain": {"sphere": {"subdivisions": 3, "radius": 1}},
    "time": {"frames": 4}, "generator": "basis", "elements": [{"kind": "singular", "type": "ccw_center",
    "path": [[0, 0, 1, 0]]}]})");
  test::write_text(dir / "ball.json", R"({"agents": 3, "speed": 6, "weights": {"goal": 1, "field": 0},
    "start": [{"ball": {"center": [0, 0, -1], "radius": 0.3}}], "goals": [{"ball": {"center": [0, 0, 1], "radius": 0.3}}]})");
  r = run_tvf("render crowd " + quoted(dir / "sphere.json") + " --crowd " + quoted(dir / "ball.json") + " -o " +
              quoted(dir / "surface.csv") + " --frames 5");
  ASSERT_EQ(r.exit_code, 0) << r.output;
  EXPECT_EQ(r.output.find("0×0"), std::string::npos) << r.output;
  EXPECT_NE(r.output.find("simulated 5 crowd frames"), std::string::npos) << r.output;
  const std::string csv = test::read_text(dir / "surface.csv");
  EXPECT_EQ(csv.rfind("agent,frame,t,x,y,z,arrived\n", 0), 0u) << csv.substr(0, 80);
  EXPECT_EQ(count_lines(csv), 1 + 3 * 5) << csv;
}

}  // namespace
}  // namespace tvf
