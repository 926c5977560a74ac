// The fuzz targets' inputs replayed in the ordinary build (docs/architecture.md,
// "Fuzzing"): every seed of fuzz/corpus/<target>/ and every input that ever crashed a
// target, kept in fuzz/crashers/<target>/, must end cleanly (loaded, or refused with a
// tvf::Error). A crash, a sanitizer report (in the sanitize build) or an internal error
// fails the test, naming the file.
#include "support/test_paths.h"
#include "targets.h"

#include <gtest/gtest.h>

#include <algorithm>
#include <exception>
#include <filesystem>
#include <functional>
#include <string>
#include <vector>

namespace tvf {
namespace {

namespace fs = std::filesystem;

struct Target {
  const char* name;
  std::function<void(std::string_view)> run;
};

const Target kTargets[] = {{"scene", fuzz::scene},       {"mesh_obj", fuzz::mesh_obj}, {"mesh_ply", fuzz::mesh_ply},
                           {"mesh_off", fuzz::mesh_off}, {"field", fuzz::field},       {"session", fuzz::session}};

std::vector<fs::path> inputs(const std::string& kind, const std::string& target) {
  std::vector<fs::path> files;
  const fs::path dir = fs::path(test::source_dir()) / "fuzz" / kind / target;
  if (fs::is_directory(dir))
    for (const auto& e : fs::directory_iterator(dir))
      if (e.is_regular_file() && e.path().filename().string()[0] != '.') files.push_back(e.path());
  std::sort(files.begin(), files.end());
  return files;
}

void replay(const std::string& kind, size_t minimum) {
  size_t count = 0;
  for (const Target& t : kTargets) {
    for (const fs::path& file : inputs(kind, t.name)) {
      SCOPED_TRACE(file.string());
      const std::string bytes = test::read_text(file);
      try {
        t.run(bytes);
      } catch (const std::exception& e) {
        ADD_FAILURE() << file << ": " << e.what();
      }
      ++count;
    }
  }
  EXPECT_GE(count, minimum);
}

TEST(FuzzReplay, EverySeedEndsCleanly) { replay("corpus", 20); }

TEST(FuzzReplay, EveryInputThatEverCrashedEndsCleanly) { replay("crashers", 0); }

}  // namespace
}  // namespace tvf
