// DESIGN §12 "MPI": `mpirun -n 2 tvf generate SCENE -o DIR` writes the one process's
// outputs (the field equal to the solver's tolerance) and its report names the ranks.
// Built with TVF_MPI only (tests/CMakeLists.txt defines TVF_MPIRUN).
#include "support/test_paths.h"
#include "tvf/field/field_io.h"
#include "tvf/field/npy.h"

#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <filesystem>
#include <string>

namespace tvf {
namespace {

#ifdef TVF_MPIRUN

// The largest |z| and the largest difference between two generated folders' fields.
std::pair<double, double> field_difference(const std::filesystem::path& a, const std::filesystem::path& b) {
  const FieldFile fa = load_field_file((a / "field.tvff").string());
  const FieldFile fb = load_field_file((b / "field.tvff").string());
  EXPECT_EQ(fa.field.data().size(), fb.field.data().size());
  double largest = 0, difference = 0;
  for (size_t k = 0; k < std::min(fa.field.data().size(), fb.field.data().size()); ++k) {
    largest = std::max(largest, std::abs(fa.field.data()[k]));
    difference = std::max(difference, std::abs(fa.field.data()[k] - fb.field.data()[k]));
  }
  return {largest, difference};
}

void expect_same_outputs_on_two_ranks(const std::string& scene_text, const char* method = "PETSc CG") {
  test::TempDir dir;
  test::write_text(dir / "scene.json", scene_text);
  const std::string cli = test::quoted(test::cli_path());
  const auto scene = test::quoted(dir / "scene.json");
  const auto one = test::run_command(cli + " generate " + scene + " -o " + test::quoted(dir / "one"));
  ASSERT_EQ(one.exit_code, 0) << one.output;
  EXPECT_EQ(one.output.find("ranks"), std::string::npos) << one.output;
  const auto two = test::run_command(std::string(TVF_MPIRUN) + " " + cli + " generate " + scene + " -o " +
                                     test::quoted(dir / "two"));
  ASSERT_EQ(two.exit_code, 0) << two.output;
  EXPECT_NE(two.output.find(method), std::string::npos) << two.output;
  EXPECT_NE(two.output.find("2 ranks"), std::string::npos) << two.output;
  // Rank 0 alone reports and writes.
  size_t reports = 0;
  for (size_t at = two.output.find("generated "); at != std::string::npos; at = two.output.find("generated ", at + 1))
    ++reports;
  EXPECT_EQ(reports, 1u) << two.output;
  // The same files.
  for (const char* f : {"field.npy", "field.tvff", "field.pvd", "vertices.npy", "times.npy", "scene.json"}) {
    EXPECT_TRUE(std::filesystem::exists(dir / "one" / f)) << f;
    EXPECT_TRUE(std::filesystem::exists(dir / "two" / f)) << f;
  }
  const auto [largest, difference] = field_difference(dir / "one", dir / "two");
  EXPECT_GT(largest, 0.1);
  EXPECT_LE(difference, 1e-8 * largest) << "largest " << largest;
  // What rank 0 wrote from the gathered field is one process's: field.npy's vectors to the
  // same tolerance, the mesh and times byte for byte, and field.tvff byte for byte up to
  // its values (header, scene, mesh).
  const NpyArray a = read_npy((dir / "one" / "field.npy").string());
  const NpyArray b = read_npy((dir / "two" / "field.npy").string());
  EXPECT_EQ(a.shape, b.shape);
  ASSERT_EQ(a.values.size(), b.values.size());
  double npy_largest = 0, npy_difference = 0;
  for (size_t k = 0; k < a.values.size(); ++k) {
    npy_largest = std::max(npy_largest, std::abs(a.values[k]));
    npy_difference = std::max(npy_difference, std::abs(a.values[k] - b.values[k]));
  }
  EXPECT_GT(npy_largest, 1e-3);  // world vectors, scaled with the mesh
  EXPECT_LE(npy_difference, 1e-6 * npy_largest) << "largest " << npy_largest;  // 32-bit floats
  for (const char* f : {"vertices.npy", "faces.npy", "times.npy", "scene.json"})
    EXPECT_EQ(test::read_text(dir / "one" / f), test::read_text(dir / "two" / f)) << f;
  const std::string ta = test::read_text(dir / "one" / "field.tvff");
  const std::string tb = test::read_text(dir / "two" / "field.tvff");
  ASSERT_EQ(ta.size(), tb.size());
  const FieldFile ff = load_field_file((dir / "one" / "field.tvff").string());
  const size_t values = static_cast<size_t>(ff.field.frames()) * static_cast<size_t>(ff.field.num_vertices()) * 16;
  ASSERT_GT(ta.size(), values);
  EXPECT_EQ(ta.substr(0, ta.size() - values), tb.substr(0, tb.size() - values));
}

TEST(CliMpi, GridWithAMovingElementIsTheSameOnTwoRanks) {
  expect_same_outputs_on_two_ranks(R"({"tvf": 1,
    "domain": {"grid": {"size": [41, 41], "min": [-1, -1], "max": [1, 1]}},
    "time": {"frames": 24, "range": [0, 1]},
    "generator": "spacetime",
    "elements": [{"kind": "singular", "type": "ccw_center", "path": [[-0.7, -0.6, 0], [0.7, 0.6, 1]]}],
    "keyframes": [{"t": 0, "elements": [{"kind": "singular", "type": "source", "at": [0, 0.5]}]}]})");
}

TEST(CliMpi, SphereWithAMovingVortexIsTheSameOnTwoRanks) {
  expect_same_outputs_on_two_ranks(R"({"tvf": 1,
    "domain": {"sphere": {"subdivisions": 3, "radius": 1}},
    "time": {"frames": 20, "range": [0, 1]},
    "generator": "spacetime",
    "falloff": 20,
    "elements": [{"kind": "singular", "type": "ccw_center",
                  "path": [[1, 0, 0, 0], [0, 1, 0, 0.5], [-1, 0, 0, 1]]},
                 {"kind": "singular", "type": "source", "path": [[0, 0, 1, 0]]}]})");
}

TEST(CliMpi, ProjectedGridIsTheSameOnTwoRanks) {
  // The field is rank 0's alone after the solve: the projection runs there.
  expect_same_outputs_on_two_ranks(R"({"tvf": 1,
    "domain": {"grid": {"size": [31, 31], "min": [-1, -1], "max": [1, 1]}},
    "time": {"frames": 10, "range": [0, 1]},
    "generator": "spacetime",
    "incompressible": true,
    "elements": [{"kind": "singular", "type": "ccw_center", "path": [[-0.6, -0.5, 0], [0.6, 0.5, 1]]}],
    "keyframes": [{"t": 0, "elements": [{"kind": "singular", "type": "ccw_center", "at": [0, 0.5]}]}]})");
}

TEST(CliMpi, ConstrainedFramesAreSharedByTwoRanks) {
  // The per-frame generator: frame j on rank j mod 2, then every frame to rank 0.
  expect_same_outputs_on_two_ranks(R"({"tvf": 1,
    "domain": {"grid": {"size": [41, 41], "min": [-1, -1], "max": [1, 1]}},
    "time": {"frames": 12, "range": [0, 1]},
    "generator": "constrained",
    "elements": [{"kind": "singular", "type": "ccw_center", "path": [[-0.7, -0.6, 0], [0.7, 0.6, 1]]},
                 {"kind": "singular", "type": "source", "path": [[0, 0.5, 0]]}]})",
                                   "frames shared by 2 ranks");
}

size_t occurrences(const std::string& text, const std::string& what) {
  size_t count = 0;
  for (size_t at = text.find(what); at != std::string::npos; at = text.find(what, at + 1)) ++count;
  return count;
}

// An input error is every rank's (each reads the same scene): rank 0 alone prints it, every
// rank exits non-zero, and nothing is written.
TEST(CliMpi, AnInputErrorIsPrintedOnceAndFailsTheRun) {
  test::TempDir dir;
  test::write_text(dir / "scene.json", R"({"tvf": 1,
    "domain": {"grid": {"size": [21, 21], "min": [-1, -1], "max": [1, 1]}},
    "time": {"frames": 8, "range": [0, 1]},
    "generator": "spacetime",
    "solver": {"tolerance": -1}})");
  const std::string cli = test::quoted(test::cli_path());
  const auto one = test::run_command(cli + " generate " + test::quoted(dir / "scene.json") + " -o " +
                                     test::quoted(dir / "one"));
  ASSERT_NE(one.exit_code, 0) << one.output;
  ASSERT_EQ(occurrences(one.output, "tvf: error:"), 1u) << one.output;
  const auto two = test::run_command(std::string(TVF_MPIRUN) + " " + cli + " generate " +
                                     test::quoted(dir / "scene.json") + " -o " + test::quoted(dir / "two"));
  EXPECT_NE(two.exit_code, 0) << two.output;
  EXPECT_EQ(occurrences(two.output, "tvf: error:"), 1u) << two.output;
  EXPECT_EQ(occurrences(two.output, "solver.tolerance"), 1u) << two.output;
  EXPECT_FALSE(std::filesystem::exists(dir / "two")) << two.output;
  // A command-line error likewise.
  const auto bad = test::run_command(std::string(TVF_MPIRUN) + " " + cli + " generate " +
                                     test::quoted(dir / "scene.json"));
  EXPECT_NE(bad.exit_code, 0) << bad.output;
  EXPECT_EQ(occurrences(bad.output, "--output is required"), 1u) << bad.output;
}

// tvf links neither PETSc nor MPI: launched by mpirun it runs tvf-mpi beside it in its place
// (apps/tvf/mpi_exec.h). A tvf without that program says so in one sentence (here an MPI
// launcher's environment variable, without mpirun, on a copy of tvf in a folder of its own).
TEST(CliMpi, MissingMpiProgramIsOneSentence) {
  test::TempDir dir;
  std::filesystem::copy_file(test::cli_path(), dir / "tvf");
  const auto run = test::run_command("OMPI_COMM_WORLD_SIZE=1 " + test::quoted(dir / "tvf") + " --help");
  EXPECT_EQ(run.exit_code, 1) << run.output;
  EXPECT_EQ(occurrences(run.output, "tvf: error: launched by mpirun, but "), 1u) << run.output;
  EXPECT_NE(run.output.find((dir / "tvf-mpi").string()), std::string::npos) << run.output;
  EXPECT_EQ(run.output.find("Usage"), std::string::npos) << run.output;
}

#else

TEST(CliMpi, NotBuilt) { GTEST_SKIP() << "this build has no distributed solve (TVF_MPI off)"; }

#endif

}  // namespace
}  // namespace tvf
