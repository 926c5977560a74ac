// `tvf render synth|terrain INPUT …` as a user meets it: PNG frames, an MP4 with every
// frame, per-frame meshes (OBJ/PLY, planar and surface), and for bad input one sentence
// naming the file or the flag, a non-zero exit, and nothing left behind.
#include "support/test_paths.h"

#include <gtest/gtest.h>

#include <filesystem>
#include <fstream>
#include <set>
#include <string>

namespace tvf {
namespace {

namespace fs = std::filesystem;
using test::count_lines;
using test::quoted;
using test::run_tvf;
using test::TempDir;

constexpr const char* kSmallScene = R"({"tvf": 1,
  "domain": {"grid": {"size": [17, 17], "min": [-1, -1], "max": [1, 1]}},
  "time": {"frames": 5, "range": [0, 1]},
  "elements": [{"kind": "singular", "type": "ccw_center", "path": [[-0.3, 0, 0], [0.3, 0, 1]]},
               {"kind": "singular", "type": "source", "path": [[0.5, 0.5, 0]]}]})";

constexpr const char* kSphereScene = R"({"tvf": 1, "domain": {"sphere": {"subdivisions": 2}},
  "time": {"frames": 3}, "elements": [{"kind": "singular", "type": "ccw_center", "path": [[0, 0, 1, 0]]}]})";

// Small and quick: a 32-pixel procedural exemplar, two levels, 48-pixel pictures.
const std::string kQuick = " --exemplar-size 32 --levels 2 --frame-levels 1 --first-iterations 2 --iterations 1 -s 48 -q";

int count_files(const fs::path& dir, const std::string& extension) {
  int n = 0;
  for (const auto& e : fs::directory_iterator(dir)) n += e.path().extension() == extension;
  return n;
}

bool have_ffprobe() { return test::run_command("command -v ffprobe >/dev/null 2>&1").exit_code == 0; }

int mp4_frames(const fs::path& file) {
  const auto p = test::run_command("ffprobe -v error -count_frames -select_streams v:0 -show_entries "
                                   "stream=nb_read_frames -of csv=p=0 " + quoted(file));
  return p.exit_code == 0 ? std::stoi(p.output) : -1;
}

// The PNG's width and height from its IHDR chunk.
std::pair<int, int> png_size(const fs::path& file) {
  std::ifstream in(file, std::ios::binary);
  unsigned char h[24] = {};
  in.read(reinterpret_cast<char*>(h), 24);
  auto be = [&](int o) { return (h[o] << 24) | (h[o + 1] << 16) | (h[o + 2] << 8) | h[o + 3]; };
  return {be(16), be(20)};
}

TEST(CliSynth, PlanarFramesAndVideo) {
  TempDir dir;
  test::write_text(dir / "scene.json", kSmallScene);
  const auto r = run_tvf("render synth " + quoted(dir / "scene.json") + " --exemplar stripes -o " +
                         quoted(dir / "frames") + " -o " + quoted(dir / "a.mp4") + " --frames 7" + kQuick);
  ASSERT_EQ(r.exit_code, 0) << r.output;
  EXPECT_EQ(r.output, "");  // -q
  EXPECT_EQ(count_files(dir / "frames", ".png"), 7);
  EXPECT_EQ(png_size(dir / "frames" / "frame_00006.png"), std::make_pair(48, 48));
  if (have_ffprobe()) {
    EXPECT_EQ(mp4_frames(dir / "a.mp4"), 7);
  }
  // Without -q: one summary line (no progress bar in a pipe).
  const auto s = run_tvf("render synth " + quoted(dir / "scene.json") + " --exemplar pebbles -o " +
                         quoted(dir / "f2") + " --exemplar-size 32 --levels 2 -s 32 --frames 2");
  ASSERT_EQ(s.exit_code, 0) << s.output;
  EXPECT_EQ(count_lines(s.output), 1) << s.output;
  EXPECT_NE(s.output.find("synthesized 2 frames"), std::string::npos) << s.output;
}

TEST(CliSynth, TerrainPicturesAndMeshesFromAGeneratedFolder) {
  TempDir dir;
  test::write_text(dir / "scene.json", kSmallScene);
  ASSERT_EQ(run_tvf("generate " + quoted(dir / "scene.json") + " -o " + quoted(dir / "gen") + " -q --no-vtk").exit_code, 0);
  const auto r = run_tvf("render terrain " + quoted(dir / "gen") + " --exemplar dunes -o " + quoted(dir / "t.mp4") +
                         " --meshes " + quoted(dir / "obj") + " --mesh-resolution 20" + kQuick);
  ASSERT_EQ(r.exit_code, 0) << r.output;
  EXPECT_EQ(count_files(dir / "obj", ".obj"), 5);  // the field's 5 frames
  if (have_ffprobe()) {
    EXPECT_EQ(mp4_frames(dir / "t.mp4"), 5);
  }
  // A 20-vertex-wide grid over the square domain: 400 vertices.
  const std::string obj = test::read_text(dir / "obj" / "frame_00004.obj");
  int vertices = 0;
  for (size_t at = obj.find("\nv "); at != std::string::npos; at = obj.find("\nv ", at + 1)) ++vertices;
  vertices += obj.rfind("v ", 0) == 0;
  EXPECT_EQ(vertices, 400);

  const auto p = run_tvf("render terrain " + quoted(dir / "gen") + " --exemplar ridges --meshes " +
                         quoted(dir / "ply") + " --mesh-format ply --mesh-resolution 12 --frames 2" + kQuick);
  ASSERT_EQ(p.exit_code, 0) << p.output;
  EXPECT_EQ(count_files(dir / "ply", ".ply"), 2);
  EXPECT_EQ(test::read_text(dir / "ply" / "frame_00001.ply").rfind("ply\n", 0), 0u);
}

TEST(CliSynth, SurfaceMeshesWithVertexColours) {
  TempDir dir;
  test::write_text(dir / "sphere.json", kSphereScene);
  const auto r = run_tvf("render synth " + quoted(dir / "sphere.json") + " --exemplar pebbles --meshes " +
                         quoted(dir / "m") + kQuick);
  ASSERT_EQ(r.exit_code, 0) << r.output;
  EXPECT_EQ(count_files(dir / "m", ".ply"), 3);
  const std::string ply = test::read_text(dir / "m" / "frame_00002.ply");
  // The icosphere of 2 subdivisions (162 vertices) at the automatic density, 8 per edge
  // (the cap): 162 + 480·7 + 320·21 samples.
  EXPECT_NE(ply.find("element vertex 10242"), std::string::npos);
  const auto one = run_tvf("render synth " + quoted(dir / "sphere.json") + " --exemplar pebbles --density 1 --meshes " +
                           quoted(dir / "m1") + kQuick);
  ASSERT_EQ(one.exit_code, 0) << one.output;
  EXPECT_NE(test::read_text(dir / "m1" / "frame_00002.ply").find("element vertex 162"), std::string::npos);
  const auto bad = run_tvf("render synth " + quoted(dir / "sphere.json") + " --exemplar pebbles --density 9 --meshes " +
                           quoted(dir / "m9") + kQuick);
  EXPECT_NE(bad.exit_code, 0);
  EXPECT_NE(bad.output.find("--density: 9 is outside [0, 8]"), std::string::npos) << bad.output;
  EXPECT_FALSE(fs::exists(dir / "m9"));
  EXPECT_NE(ply.find("property uchar red"), std::string::npos);
  const auto t = run_tvf("render terrain " + quoted(dir / "sphere.json") + " --exemplar ridges --meshes " +
                         quoted(dir / "t") + " --mesh-format ply" + kQuick);
  ASSERT_EQ(t.exit_code, 0) << t.output;
  EXPECT_EQ(count_files(dir / "t", ".ply"), 3);
  // Pictures of the surface through the offscreen mesh renderer: PNG frames and an MP4.
  const auto p = run_tvf("render synth " + quoted(dir / "sphere.json") + " --exemplar pebbles -o " +
                         quoted(dir / "frames") + " -o " + quoted(dir / "sphere.mp4") + kQuick);
  ASSERT_EQ(p.exit_code, 0) << p.output;
  EXPECT_EQ(count_files(dir / "frames", ".png"), 3);
  EXPECT_TRUE(fs::is_regular_file(dir / "sphere.mp4"));
}

std::set<std::string> entries(const fs::path& dir) {
  std::set<std::string> names;
  for (const auto& e : fs::recursive_directory_iterator(dir)) names.insert(e.path().lexically_relative(dir).string());
  return names;
}

// One line, non-zero exit, the given words in it, and nothing new in the folder (no
// output, no temporary or staging file).
void expect_clean_failure(const TempDir& dir, const std::string& command, const std::string& words) {
  const auto before = entries(dir.path());
  const auto r = run_tvf(command);
  EXPECT_NE(r.exit_code, 0) << command;
  EXPECT_EQ(count_lines(r.output), 1) << command << ": " << r.output;
  EXPECT_NE(r.output.find(words), std::string::npos) << command << ": " << r.output;
  EXPECT_EQ(entries(dir.path()), before) << command;
}

TEST(CliSynth, BadInputIsOneSentenceAndLeavesNothing) {
  TempDir dir;
  test::write_text(dir / "scene.json", kSmallScene);
  test::write_text(dir / "sphere.json", kSphereScene);
  test::write_text(dir / "not_a_picture.png", "hello");
  // A PNG signature and a header cut short.
  test::write_text(dir / "cut.png", std::string("\x89PNG\r\n\x1a\n\0\0\0\x0dIHDR\0\0", 18));
  const std::string scene = quoted(dir / "scene.json");
  const std::string outputs = " -o " + quoted(dir / "out") + " -o " + quoted(dir / "out.mp4");
  const std::string synth = "render synth " + scene + outputs;
  expect_clean_failure(dir, synth + " --exemplar " + quoted(dir / "missing.png"), "missing.png");
  expect_clean_failure(dir, synth + " --exemplar " + quoted(dir / "not_a_picture.png"), "not_a_picture.png");
  expect_clean_failure(dir, synth + " --exemplar " + quoted(dir / "cut.png"), "cut.png");
  expect_clean_failure(dir, synth + " --exemplar marble", "--exemplar marble");
  expect_clean_failure(dir, synth + " --exemplar dunes", "colour");
  expect_clean_failure(dir, "render terrain " + scene + outputs + " --exemplar stripes", "height");
  expect_clean_failure(dir, "render synth " + quoted(dir / "nothing.json") + outputs + " --exemplar stripes", "nothing.json");
  expect_clean_failure(dir, "render synth " + quoted(dir / "sphere.json") + outputs + " --exemplar stripes --view 0,0,0",
                       "viewing direction");
  // Out-of-range sizes and values name the flag.
  for (const auto& [bad, flag] : std::initializer_list<std::pair<std::string, std::string>>{
           {"-s 8", "--size"}, {"-s 100000", "--size"}, {"--levels 0", "--levels"}, {"--levels 9", "--levels"},
           {"--frame-levels 4", "--frame-levels"}, {"--neighbourhood 4", "--neighbourhood"},
           {"--stride 9", "--stride"}, {"--iterations 0", "--iterations"}, {"--first-iterations 1000", "--first-iterations"},
           {"--temporal-weight nan", "--temporal-weight"}, {"--temporal-weight -1", "--temporal-weight"},
           {"--speed -2", "--speed"}, {"--frames -3", "--frames"}, {"--exemplar-size 4", "exemplar size"},
           {"--exemplar-size 100000", "exemplar size"}, {"--fps 0", "fps"}})
    expect_clean_failure(dir, synth + " --exemplar stripes " + bad, flag);
  const std::string terrain = "render terrain " + scene + " --exemplar dunes --meshes " + quoted(dir / "meshes") +
                              " -o " + quoted(dir / "out");
  expect_clean_failure(dir, terrain + " --height-scale -3", "--height-scale");
  expect_clean_failure(dir, terrain + " --height-scale 50", "--height-scale");
  expect_clean_failure(dir, terrain + " --mesh-resolution 1", "--mesh-resolution");
  expect_clean_failure(dir, terrain + " --relief -1", "--relief");
  expect_clean_failure(dir, "render terrain " + quoted(dir / "sphere.json") + " --exemplar ridges --meshes " +
                                quoted(dir / "meshes") + " --height-scale 2", "--height-scale");
  expect_clean_failure(dir, "render synth " + scene + " --exemplar stripes", "-o");
  expect_clean_failure(dir, synth + " --exemplar stripes --meshes " + quoted(dir / "meshes"), "--meshes");
}

TEST(CliSynth, UnknownOptionValuesAreRefused) {
  TempDir dir;
  test::write_text(dir / "scene.json", kSmallScene);
  const std::string terrain = "render terrain " + quoted(dir / "scene.json") + " --exemplar dunes --meshes " + quoted(dir / "out");
  for (const std::string bad : {"--mesh-format stl", "--levels many", "--size 1.5x"}) {
    const auto r = run_tvf(terrain + " " + bad);
    EXPECT_NE(r.exit_code, 0) << bad;
    EXPECT_NE(r.output.find(bad.substr(0, bad.find(' '))), std::string::npos) << bad << ": " << r.output;
    EXPECT_FALSE(fs::exists(dir / "out")) << bad;
  }
}

}  // namespace
}  // namespace tvf
