#include "tvf/render/plots.h"

#include "support/test_paths.h"
#include "tvf/core/error.h"
#include "tvf/mesh/grid.h"

#include <gtest/gtest.h>

#include <filesystem>

namespace tvf {
namespace {

namespace fs = std::filesystem;

void expect_png_and_svg(const std::vector<std::string>& files) {
  ASSERT_EQ(files.size(), 2u);
  const std::string svg = test::read_text(files[0]);
  EXPECT_NE(svg.find("<svg"), std::string::npos);
  EXPECT_NE(svg.find("</svg>"), std::string::npos);
  const std::string png = test::read_text(files[1]);
  ASSERT_GT(png.size(), 100u);
  EXPECT_EQ(png.substr(1, 3), "PNG");
  EXPECT_EQ(png.substr(png.size() - 8, 4), "IEND");  // complete file
  for (const auto& e : fs::directory_iterator(fs::path(files[0]).parent_path()))
    EXPECT_EQ(e.path().filename().string().find(".tmp-"), std::string::npos) << e.path();
}

TEST(Plots, CoherencePlotIsACompleteSvgAndPng) {
  test::TempDir dir;
  std::vector<double> t, y;
  for (int i = 0; i < 50; ++i) t.push_back(i / 49.0), y.push_back(1 + std::sin(i * 0.2));
  expect_png_and_svg(write_coherence_plot((dir / "c").string(), t, y));
}

TEST(Plots, PathsPlotDrawsEveryPathAndBifurcation) {
  test::TempDir dir;
  const Mesh grid = make_grid(GridSpec{5, 5, {-1, -1}, {1, 1}});
  Topology topo;
  topo.times = {0, 0.5, 1};
  SingularityPath a;
  a.type = SingularityType::saddle;
  a.points = {{Vec3(-0.5, 0, 0), 0}, {Vec3(0, 0, 0), 0.5}};
  SingularityPath b = a;
  b.id = 1;
  b.type = SingularityType::source;
  b.points = {{Vec3(0.5, 0, 0), 0}, {Vec3(0, 0, 0), 0.5}};
  topo.paths = {a, b};
  Bifurcation bif;
  bif.t = 0.5;
  bif.position = Vec3(0, 0, 0);
  bif.kind = BifurcationKind::cancellation;
  bif.paths = {0, 1};
  topo.bifurcations = {bif};
  const auto files = write_paths_plot((dir / "p").string(), grid, topo);
  expect_png_and_svg(files);
  // The SVG carries the paper's colours: saddle blue and source green.
  const std::string svg = test::read_text(files[0]);
  EXPECT_NE(svg.find("stroke:rgb(10%,25%,90%)"), std::string::npos);
  EXPECT_NE(svg.find("stroke:rgb(10%,65%,20%)"), std::string::npos);
  // An empty analysis still draws the box.
  expect_png_and_svg(write_paths_plot((dir / "empty").string(), grid, Topology{}));
}

TEST(Plots, UnwritableFolderIsAnErrorNamingTheFile) {
  EXPECT_THROW(write_coherence_plot("/nonexistent-folder/c", {0, 1}, {1}), Error);
}

}  // namespace
}  // namespace tvf
