// `tvf export DIR --vdb` (apps/tvf/export_command.cpp; DESIGN §12 "Export"): OpenVDB's writer
// is the module libtvf_vdb.so (src/vdb/vdb_module.h), opened by the export alone; tvf itself
// does not link OpenVDB (ctest cli_loads_no_petsc_or_openvdb).
#include "support/test_paths.h"

#include <gtest/gtest.h>

#include <filesystem>
#include <fstream>
#include <string>

namespace tvf {
namespace {

namespace fs = std::filesystem;
using test::quoted;
using test::run_tvf;
using test::TempDir;

#ifdef TVF_TEST_VDB

// One VDB file per frame, each an OpenVDB file (its magic number, the grid "v"). (Python's
// test reads the vectors back with OpenVDB's own reader where python3-openvdb is installed.)
TEST(CliExport, VdbWritesOneOpenVdbFilePerFrame) {
  TempDir dir;
  test::write_text(dir / "scene.json", R"({"tvf": 1,
    "domain": {"grid": {"size": [9, 7], "min": [-1, -1], "max": [1, 0.5]}}, "time": {"frames": 3},
    "elements": [{"kind": "singular", "type": "source", "path": [[0, 0, 0]]}]})");
  const auto gen = run_tvf("generate " + quoted(dir / "scene.json") + " -o " + quoted(dir / "out") + " -q --no-vtk");
  ASSERT_EQ(gen.exit_code, 0) << gen.output;
  const auto r = run_tvf("export " + quoted(dir / "out") + " --vdb -o " + quoted(dir / "vdb") + " -q");
  ASSERT_EQ(r.exit_code, 0) << r.output;
  for (int j = 0; j < 3; ++j) {
    const fs::path file = dir / "vdb" / ("velocity_000" + std::to_string(j) + ".vdb");
    ASSERT_TRUE(fs::exists(file)) << file;
    std::string bytes(static_cast<size_t>(fs::file_size(file)), '\0');
    std::ifstream(file, std::ios::binary).read(bytes.data(), static_cast<std::streamsize>(bytes.size()));
    ASSERT_GE(bytes.size(), 8u) << file;
    EXPECT_EQ(bytes.substr(0, 4), " BDV") << file;  // OpenVDB's magic number 0x56444220, little-endian
    EXPECT_NE(bytes.find("Tree_vec3s_5_4_3"), std::string::npos) << file;
  }
  EXPECT_FALSE(fs::exists(dir / "vdb" / "velocity_0003.vdb"));
}

#else

TEST(CliExport, VdbNotBuilt) { GTEST_SKIP() << "this build has no OpenVDB (libopenvdb-dev)"; }

#endif

}  // namespace
}  // namespace tvf
