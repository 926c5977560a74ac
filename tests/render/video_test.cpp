// MP4 through ffmpeg: the file decodes with ffprobe and has every frame.
#include "tvf/render/video.h"

#include "support/test_paths.h"
#include "tvf/core/error.h"
#include "tvf/mesh/grid.h"
#include "tvf/render/texture_animation.h"

#include <gtest/gtest.h>

#include <filesystem>

namespace tvf {
namespace {

namespace fs = std::filesystem;

bool have_ffprobe() { return test::run_command("command -v ffprobe >/dev/null 2>&1").exit_code == 0; }

// Frames ffprobe decodes from `file`, or -1.
int decoded_frames(const fs::path& file) {
  const auto r = test::run_command("ffprobe -v error -count_frames -select_streams v:0 -show_entries "
                                   "stream=nb_read_frames -of csv=p=0 '" + file.string() + "'");
  if (r.exit_code != 0) return -1;
  try {
    return std::stoi(r.output);
  } catch (...) {
    return -1;
  }
}

TEST(Video, DecodesWithTheRightFrameCount) {
  if (!ffmpeg_available() || !have_ffprobe()) GTEST_SKIP() << "ffmpeg/ffprobe not installed (Debian package ffmpeg)";
  test::TempDir dir;
  const fs::path out = dir / "v.mp4";
  {
    VideoWriter w(out.string(), 33, 20, VideoOptions{12, 23});  // odd width: padded
    for (int k = 0; k < 17; ++k) {
      Image img(33, 20);
      for (int y = 0; y < 20; ++y)
        for (int x = 0; x < 33; ++x) img.at(x, y) = gray(static_cast<std::uint8_t>((x * 7 + y * 3 + k * 11) & 255));
      w.add(img);
    }
    EXPECT_FALSE(fs::exists(out));  // not before finish()
    w.finish();
  }
  EXPECT_EQ(decoded_frames(out), 17);
  std::vector<std::string> names;
  for (const auto& e : fs::directory_iterator(dir.path())) names.push_back(e.path().filename().string());
  EXPECT_EQ(names, std::vector<std::string>{"v.mp4"});  // no temporary or log left
}

TEST(Video, GrayFramesGoInOneByteAPixel) {
  if (!ffmpeg_available() || !have_ffprobe()) GTEST_SKIP() << "ffmpeg/ffprobe not installed (Debian package ffmpeg)";
  test::TempDir dir;
  const fs::path out = dir / "g.mp4";
  VideoOptions o;
  o.gray = true;
  o.preset = "superfast";
  {
    VideoWriter w(out.string(), 33, 20, o);  // odd width: padded
    for (int k = 0; k < 9; ++k) {
      Image img(33, 20);
      for (int y = 0; y < 20; ++y)
        for (int x = 0; x < 33; ++x) img.at(x, y) = gray(static_cast<std::uint8_t>((x * 7 + y * 3 + k * 11) & 255));
      w.add(img);
    }
    w.finish();
  }
  EXPECT_EQ(decoded_frames(out), 9);
  // A coloured pixel in a gray video is a bug of the caller: refused, nothing left behind.
  {
    VideoWriter w((dir / "c.mp4").string(), 16, 16, o);
    Image img(16, 16);
    img.at(3, 4) = rgb(200, 10, 10);
    EXPECT_THROW(w.add(img), InternalError);
  }
  EXPECT_FALSE(fs::exists(dir / "c.mp4"));
}

TEST(Video, AbandonedWriterLeavesNothing) {
  if (!ffmpeg_available()) GTEST_SKIP() << "ffmpeg not installed (Debian package ffmpeg)";
  test::TempDir dir;
  {
    VideoWriter w((dir / "v.mp4").string(), 16, 16);
    w.add(Image(16, 16));
  }
  EXPECT_TRUE(fs::is_empty(dir.path()));
}

TEST(Video, TextureAnimationVideoHasEveryFrame) {
  if (!ffmpeg_available() || !have_ffprobe()) GTEST_SKIP() << "ffmpeg/ffprobe not installed (Debian package ffmpeg)";
  const Mesh grid = make_grid(GridSpec{9, 9, {-1, -1}, {1, 1}});
  const TangentBundle bundle(grid);
  Field field(TimeSampling{0, 1, 5}, grid.num_vertices());
  for (auto& z : field.data()) z = cplx(1, 0.5);
  test::TempDir dir;
  TextureAnimationOptions o;
  o.texture.size = 64;
  o.frames = 12;
  o.video = (dir / "a.mp4").string();
  o.frames_dir = (dir / "frames").string();
  const auto r = write_texture_animation(bundle, field, o);
  EXPECT_EQ(r.frames, 12);
  EXPECT_EQ(decoded_frames(dir / "a.mp4"), 12);
  int pngs = 0;
  for (const auto& e : fs::directory_iterator(dir / "frames")) pngs += e.path().extension() == ".png";
  EXPECT_EQ(pngs, 12);
}

}  // namespace
}  // namespace tvf
