// Exemplars: procedural ones tile and have their stripes along x; PNG and JPEG files load
// alike; bad files are one clear error naming the file.
#include "tvf/synth/exemplar.h"

#include "support/test_paths.h"
#include "synth_test_support.h"
#include "tvf/render/image.h"
#include "tvf/render/video.h"

#include <gtest/gtest.h>

#include <numbers>

namespace tvf {
namespace {

TEST(Exemplar, ProceduralStripesRunAlongXAndTile) {
  const Exemplar e = make_procedural_exemplar(ProceduralExemplar::stripes, 64, 3);
  ASSERT_EQ(e.channels, 3);
  EXPECT_TRUE(e.tileable);
  double coherence = 0;
  const auto l = test::luminance(e.pixels, 3);
  const double angle = test::stripe_angle(l, 64, 0, 0, 64, 64, coherence);
  EXPECT_LT(test::line_angle_difference(angle, 0.0), 0.2) << angle;
  EXPECT_GT(coherence, 0.6);
  // Tileable: the jump across the wrap is no larger than between neighbouring rows.
  double wrap = 0, inner = 0;
  for (int x = 0; x < 64; ++x) {
    wrap += std::abs(l[static_cast<size_t>(63 * 64 + x)] - l[static_cast<size_t>(x)]);
    inner += std::abs(l[static_cast<size_t>(31 * 64 + x)] - l[static_cast<size_t>(32 * 64 + x)]);
  }
  EXPECT_LT(wrap, 2.5 * inner + 1.0);
}

TEST(Exemplar, HeightExemplarsHaveOneChannelInRange) {
  for (auto kind : {ProceduralExemplar::ridges, ProceduralExemplar::dunes}) {
    const Exemplar e = make_procedural_exemplar(kind, 48);
    EXPECT_EQ(e.channels, 1);
    const auto [lo, hi] = std::minmax_element(e.pixels.begin(), e.pixels.end());
    EXPECT_GE(*lo, 0.f);
    EXPECT_LE(*hi, 1.f);
    EXPECT_GT(*hi - *lo, 0.5f);  // real relief
  }
}

TEST(Exemplar, DownsampleHalvesAndAverages) {
  Exemplar e(4, 2, 1);
  for (int x = 0; x < 4; ++x) e.at(x, 0, 0) = static_cast<float>(x), e.at(x, 1, 0) = static_cast<float>(x + 4);
  const Exemplar d = downsample(e);
  ASSERT_EQ(d.width, 2);
  ASSERT_EQ(d.height, 1);
  EXPECT_FLOAT_EQ(d.at(0, 0, 0), (0 + 1 + 4 + 5) / 4.f);
  EXPECT_FLOAT_EQ(d.at(1, 0, 0), (2 + 3 + 6 + 7) / 4.f);
}

TEST(Exemplar, PngAndJpegLoadAlike) {
  test::TempDir dir;
  const Exemplar e = make_procedural_exemplar(ProceduralExemplar::pebbles, 64);
  write_png((dir / "a.png").string(), exemplar_to_image(e));
  const Exemplar png = load_exemplar((dir / "a.png").string());
  ASSERT_EQ(png.width, 64);
  for (size_t i = 0; i < e.pixels.size(); ++i) ASSERT_NEAR(png.pixels[i], e.pixels[i], 0.5 / 255 + 1e-6);
  if (!ffmpeg_available()) GTEST_SKIP() << "ffmpeg makes the JPEG";
  const auto r = test::run_command("ffmpeg -loglevel error -y -i " + test::quoted(dir / "a.png") + " -q:v 2 " +
                                   test::quoted(dir / "a.jpg"));
  ASSERT_EQ(r.exit_code, 0) << r.output;
  const Exemplar jpg = load_exemplar((dir / "a.jpg").string());
  ASSERT_EQ(jpg.width, 64);
  ASSERT_EQ(jpg.height, 64);
  double mean_error = 0;
  for (size_t i = 0; i < e.pixels.size(); ++i) mean_error += std::abs(jpg.pixels[i] - e.pixels[i]);
  EXPECT_LT(mean_error / static_cast<double>(e.pixels.size()), 0.03);  // lossy, but the same picture
  const Exemplar gray = load_exemplar((dir / "a.jpg").string(), 1);
  EXPECT_EQ(gray.channels, 1);
}

TEST(Exemplar, BadFilesAreOneClearError) {
  test::TempDir dir;
  test::write_text(dir / "not.png", "hello");
  EXPECT_NE(test::error_of([&] { load_exemplar((dir / "not.png").string()); }).find("not.png: not a PNG or JPEG"),
            std::string::npos);
  EXPECT_NE(test::error_of([&] { load_exemplar((dir / "missing.png").string()); }).find("missing.png"), std::string::npos);
  write_png((dir / "tiny.png").string(), Image(4, 4));
  EXPECT_NE(test::error_of([&] { load_exemplar((dir / "tiny.png").string()); }).find("at least 8×8"), std::string::npos);
  EXPECT_NE(test::error_of([] { parse_procedural_exemplar("plaid"); }).find("stripes, pebbles, ridges or dunes"),
            std::string::npos);
}

}  // namespace
}  // namespace tvf
