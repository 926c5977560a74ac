// `tvf serve` as a user meets it before the browser: bad arguments are one sentence, a
// non-zero exit, and leave the working folder untouched. (The server itself: tests/serve;
// the designer end to end: web/e2e, ctest `web_e2e`.)
#include "support/test_paths.h"

#include <gtest/gtest.h>

#include <filesystem>

namespace tvf {
namespace {

using test::quoted;
using test::run_tvf;

TEST(CliServe, BadArgumentsAreOneSentenceAndWriteNothing) {
  test::TempDir dir;
  const auto work = dir / "work";
  std::filesystem::create_directory(work);
  struct Case {
    std::string args, expected;
    bool one_line;  // tvf's own errors; CLI11's add "Run with --help ..."
  };
  const std::vector<Case> cases = {
      {"serve --dir " + quoted(work) + " --port 99999", "--port", false},
      {"serve " + quoted(dir / "missing.json"), "no such scene file", true},
      {"serve " + quoted(std::filesystem::path(test::source_dir()) / "examples/02_combined_elements/scene.json") + " --dir " + quoted(work),
       "must lie inside the working folder", true},
  };
  for (const Case& c : cases) {
    const auto r = run_tvf(c.args);
    EXPECT_NE(r.exit_code, 0) << c.args;
    EXPECT_NE(r.output.find(c.expected), std::string::npos) << c.args << "\n" << r.output;
    if (c.one_line) {
      EXPECT_EQ(test::count_lines(r.output), 1) << r.output;
    }
    EXPECT_TRUE(std::filesystem::is_empty(work)) << c.args;
  }
}

}  // namespace
}  // namespace tvf
