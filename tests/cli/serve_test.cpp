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

TEST(CliServe, StopsCleanlyOnSigtermWithTheDesignSaved) {
  test::TempDir dir;
  const auto work = dir / "work";
  const auto log = dir / "log.txt";
  // Start it, wait for its address, send SIGTERM, and report its exit status.
  const std::string script = test::quoted(test::cli_path()) + " serve --dir " + quoted(work) + " --port 0 > " + quoted(log) +
                             " 2>&1 & pid=$!; for i in $(seq 300); do grep -q 'open http' " + quoted(log) +
                             " && break; sleep 0.1; done; kill -TERM $pid; wait $pid; echo exit=$?";
  const auto r = test::run_command(script);
  EXPECT_NE(r.output.find("exit=0"), std::string::npos) << r.output << test::read_text(log);
  const std::string out = test::read_text(log);
  EXPECT_NE(out.find("open http://127.0.0.1:"), std::string::npos) << out;
  EXPECT_NE(out.find("stopped; the design is in"), std::string::npos) << out;
  EXPECT_TRUE(std::filesystem::exists(work / "scene.json"));
}

}  // namespace
}  // namespace tvf
