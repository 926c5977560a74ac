// `tvf render texture INPUT -o OUT…` as a user meets it: PNG frames and MP4 from a scene or
// a generated folder, surfaces from a camera, a clear sentence for bad options, and no partial output.
#include "support/test_paths.h"
#include "tvf/render/image.h"

#include <gtest/gtest.h>

#include <filesystem>
#include <string>

namespace tvf {
namespace {

namespace fs = std::filesystem;
using test::count_lines;
using test::run_tvf;
using test::quoted;
using test::TempDir;

constexpr const char* kSmallScene = R"({"tvf": 1,
  "domain": {"grid": {"size": [17, 17], "min": [-1, -1], "max": [1, 1]}},
  "time": {"frames": 6, "range": [0, 1]},
  "elements": [{"kind": "singular", "type": "ccw_center", "path": [[-0.3, 0, 0], [0.3, 0, 1]]},
               {"kind": "singular", "type": "source", "path": [[0.5, 0.5, 0]]}]})";

int count_pngs(const fs::path& dir) {
  int n = 0;
  for (const auto& e : fs::directory_iterator(dir)) n += e.path().extension() == ".png";
  return n;
}

TEST(CliRender, TextureFramesFromASceneAndAFolder) {
  TempDir dir;
  test::write_text(dir / "scene.json", kSmallScene);
  const auto r = run_tvf("render texture " + quoted(dir / "scene.json") + " -o " + quoted(dir / "frames") +
                         " --size 64 --overlay singularities");
  ASSERT_EQ(r.exit_code, 0) << r.output;
  EXPECT_EQ(count_lines(r.output), 1) << r.output;  // the summary; no progress in a pipe
  EXPECT_NE(r.output.find("rendered 6 frames of 64×64"), std::string::npos) << r.output;
  EXPECT_EQ(count_pngs(dir / "frames"), 6);

  ASSERT_EQ(run_tvf("generate " + quoted(dir / "scene.json") + " -o " + quoted(dir / "gen") + " -q --no-vtk").exit_code, 0);
  const auto q = run_tvf("render texture " + quoted(dir / "gen") + " -o " + quoted(dir / "f2") +
                         " --size 32 --frames 11 --range 2:5 -q");
  ASSERT_EQ(q.exit_code, 0) << q.output;
  EXPECT_EQ(q.output, "");
  EXPECT_EQ(count_pngs(dir / "f2"), 4);
  EXPECT_TRUE(fs::exists(dir / "f2" / "frame_00002.png"));
  EXPECT_TRUE(fs::exists(dir / "f2" / "frame_00005.png"));
}

TEST(CliRender, Mp4DecodesWithTheRightFrameCount) {
  if (test::run_command("command -v ffprobe >/dev/null 2>&1").exit_code != 0)
    GTEST_SKIP() << "ffprobe not installed (Debian package ffmpeg)";
  TempDir dir;
  test::write_text(dir / "scene.json", kSmallScene);
  const auto r = run_tvf("render texture " + quoted(dir / "scene.json") + " -o " + quoted(dir / "a.mp4") +
                         " -o " + quoted(dir / "frames") + " --size 48 --frames 9 --fps 10 -q");
  ASSERT_EQ(r.exit_code, 0) << r.output;
  const auto p = test::run_command("ffprobe -v error -count_frames -select_streams v:0 -show_entries "
                                   "stream=nb_read_frames -of csv=p=0 " + quoted(dir / "a.mp4"));
  ASSERT_EQ(p.exit_code, 0) << p.output;
  EXPECT_EQ(std::stoi(p.output), 9);
  EXPECT_EQ(count_pngs(dir / "frames"), 9);
}

TEST(CliRender, SurfaceTextureFromACamera) {
  TempDir dir;
  test::write_text(dir / "sphere.json", R"({"tvf": 1, "domain": {"sphere": {"subdivisions": 2}},
    "time": {"frames": 3}, "elements": [{"kind": "singular", "type": "source", "path": [[0, 0, 1, 0]]}]})");
  const auto s = run_tvf("render texture " + quoted(dir / "sphere.json") + " -o " + quoted(dir / "out") +
                         " --size 64 --view 0,-1,1 --overlay singularities paths");
  ASSERT_EQ(s.exit_code, 0) << s.output;
  EXPECT_NE(s.output.find("rendered 3 frames of 64×64"), std::string::npos) << s.output;
  EXPECT_EQ(count_pngs(dir / "out"), 3);
  // A camera looking along its up direction still has an up; a zero view is an error.
  EXPECT_EQ(run_tvf("render texture " + quoted(dir / "sphere.json") + " -o " + quoted(dir / "o2") +
                    " --size 32 --view 0,0,1 -q").exit_code, 0);
  const auto z = run_tvf("render texture " + quoted(dir / "sphere.json") + " -o " + quoted(dir / "o3") +
                         " --size 32 --view 0,0,0 -q");
  EXPECT_NE(z.exit_code, 0);
  EXPECT_EQ(count_lines(z.output), 1) << z.output;
  EXPECT_NE(z.output.find("view"), std::string::npos) << z.output;
  EXPECT_FALSE(fs::exists(dir / "o3"));
  // Leaves are carried on the surface too, seen from the same camera options.
  const auto q = run_tvf("render particles " + quoted(dir / "sphere.json") + " -o " + quoted(dir / "leaves") +
                         " --size 64 --count 50 --view 0,-1,1 -q");
  ASSERT_EQ(q.exit_code, 0) << q.output;
  EXPECT_EQ(count_pngs(dir / "leaves"), 3);
  // The other kinds still draw planar domains only, and say so in one sentence.
  const auto p = run_tvf("render grass " + quoted(dir / "sphere.json") + " -o " + quoted(dir / "p"));
  EXPECT_NE(p.exit_code, 0);
  EXPECT_EQ(count_lines(p.output), 1) << p.output;
  EXPECT_NE(p.output.find("sphere.json"), std::string::npos) << p.output;
  EXPECT_NE(p.output.find("planar domains only"), std::string::npos) << p.output;
}

TEST(CliRender, DyeInParticlesAndSurfaceTextures) {
  // --streakline injects dye: in the particle renderer (planar and surface) and in the
  // surface texture; each seed's colour (red, then blue) shows in the last picture.
  TempDir dir;
  test::write_text(dir / "scene.json", kSmallScene);
  test::write_text(dir / "sphere.json", R"({"tvf": 1, "domain": {"sphere": {"subdivisions": 2}},
    "time": {"frames": 3}, "elements": [{"kind": "singular", "type": "ccw_center", "path": [[0, 0, 1, 0]]}]})");
  auto count = [](const fs::path& png, bool want_blue) {
    const Image img = read_png(png.string());
    int n = 0;
    for (const std::uint32_t c : img.pixels) {
      const int r = static_cast<int>((c >> 16) & 0xFF), g = static_cast<int>((c >> 8) & 0xFF),
                b = static_cast<int>(c & 0xFF);
      n += want_blue ? b > r + 80 && b > g + 40 : r > g + 80 && r > b + 80;
    }
    return n;
  };
  const auto p = run_tvf("render particles " + quoted(dir / "scene.json") + " -o " + quoted(dir / "leaves") +
                         " --streakline 0.3,0.2 --streakline -0.5,-0.5,0 --count 1 --particle-size 1 --size 96 -q");
  ASSERT_EQ(p.exit_code, 0) << p.output;
  EXPECT_GT(count(dir / "leaves" / "frame_00005.png", false), 20);
  EXPECT_GT(count(dir / "leaves" / "frame_00005.png", true), 20);
  const auto s = run_tvf("render texture " + quoted(dir / "sphere.json") + " -o " + quoted(dir / "tex") +
                         " --streakline 0.6,0,0.8 --size 64 --view 0.3,0.3,1 -q");
  ASSERT_EQ(s.exit_code, 0) << s.output;
  EXPECT_GT(count(dir / "tex" / "frame_00002.png", false), 10);
  const auto q = run_tvf("render particles " + quoted(dir / "sphere.json") + " -o " + quoted(dir / "sleaves") +
                         " --streakline 0.6,0,0.8 --count 1 --size 64 --view 0.3,0.3,1 -q");
  ASSERT_EQ(q.exit_code, 0) << q.output;
  EXPECT_GT(count(dir / "sleaves" / "frame_00002.png", false), 10);
  // Bad seeds: one sentence, nothing written.
  const std::pair<std::string, std::string> cases[] = {
      {"particles " + quoted(dir / "scene.json") + " --streakline 3,0", "the dye seed (3, 0) is outside the domain"},
      {"particles " + quoted(dir / "scene.json") + " --streakline 0.3", "--streakline 0.3: expected X,Y"},
      {"texture " + quoted(dir / "scene.json") + " --streakline 0,-1.5", "the dye seed (0, -1.5) is outside the domain"},
      {"texture " + quoted(dir / "sphere.json") + " --streakline 0,0", "--streakline 0,0: expected X,Y,Z"},
      {"texture " + quoted(dir / "sphere.json") + " --streakline 0,0,3", "the dye seed (0, 0, 3) is 2"},
      {"particles " + quoted(dir / "sphere.json") + " --streakline 0,0,-3", "from the surface, farther than"},
  };
  for (const auto& [args, message] : cases) {
    const auto r = run_tvf("render " + args + " -q --size 32 -o " + quoted(dir / "bad"));
    EXPECT_NE(r.exit_code, 0) << args;
    EXPECT_EQ(count_lines(r.output), 1) << args << ": " << r.output;
    EXPECT_NE(r.output.find(message), std::string::npos) << args << ": " << r.output;
    EXPECT_FALSE(fs::exists(dir / "bad")) << args;
  }
}

TEST(CliRender, BadOptionsAreOneSentenceAndLeaveNothing) {
  TempDir dir;

  test::write_text(dir / "scene.json", kSmallScene);
  for (const std::string bad : {"--range 3", "--range 4:9", "--size 5", "--alpha 2", "--fps 0"}) {
    const auto r = run_tvf("render texture " + quoted(dir / "scene.json") + " -o " + quoted(dir / "out") + " " + bad);
    EXPECT_NE(r.exit_code, 0) << bad;
    EXPECT_EQ(count_lines(r.output), 1) << bad << ": " << r.output;
  }
  const auto m = run_tvf("render texture " + quoted(dir / "missing") + " -o " + quoted(dir / "out"));
  EXPECT_NE(m.exit_code, 0);
  EXPECT_NE(m.output.find("no such file"), std::string::npos) << m.output;
  // Nothing but the inputs is left.
  int entries = 0;
  for (const auto& e : fs::directory_iterator(dir.path())) {
    entries += 1;
    EXPECT_NE(e.path().filename(), "out");
  }
  EXPECT_EQ(entries, 1);
}

}  // namespace
}  // namespace tvf
