#pragma once
// Paths and processes for tests: a fresh temporary folder per test, and running the
// tvf CLI or Debian's python3 with captured output.
#include "tvf/core/error.h"

#include <gtest/gtest.h>

#include <filesystem>
#include <optional>
#include <string>
#include <vector>

namespace tvf::test {

// A new empty folder under the system temp dir, removed by the destructor.
class TempDir {
public:
  TempDir();
  ~TempDir();
  TempDir(const TempDir&) = delete;
  TempDir& operator=(const TempDir&) = delete;
  const std::filesystem::path& path() const { return path_; }
  std::filesystem::path operator/(const std::string& name) const { return path_ / name; }

private:
  std::filesystem::path path_;
};

struct CommandResult {
  int exit_code = -1;
  std::string output;  // stdout and stderr together
};
// Runs a shell command line, capturing output.
CommandResult run_command(const std::string& command_line);
// Runs the tvf CLI built with the tests with the given arguments (shell-quoted by caller).
CommandResult run_tvf(const std::string& arguments);
// A path in single quotes, for command lines (test paths have no quotes of their own).
std::string quoted(const std::filesystem::path& path);

std::string source_dir();
std::string cli_path();  // the tvf program this build made
std::string test_data_dir();
std::string python();  // Debian's python3 with numpy and vtk, or "" when not found

// Runs `fn` and returns the message of the tvf::Error it throws (fails the test when it
// throws nothing).
template <class Fn>
std::string error_of(Fn&& fn) {
  try {
    fn();
  } catch (const Error& e) {
    return e.what();
  }
  ADD_FAILURE() << "expected tvf::Error";
  return {};
}

// Number of '\n' in a command's output (one-sentence errors are one line).
inline int count_lines(const std::string& s) {
  int n = 0;
  for (char c : s) n += c == '\n';
  return n;
}

// libcgal-demo's data archive (Debian), whose sample meshes the tests use as real inputs.
inline constexpr const char* kCgalArchive = "/usr/share/doc/libcgal-dev/data.tar.gz";
// Extracts the archive's data/meshes/NAME.off into `dir` and returns its path; nullopt when
// the archive is missing or has no such mesh (the test then skips, naming kCgalArchive).
std::optional<std::filesystem::path> cgal_mesh(const TempDir& dir, const std::string& name);

// Writes text to a file (test fixtures).
void write_text(const std::filesystem::path& path, const std::string& text);
std::string read_text(const std::filesystem::path& path);
// The names of the files in a folder, sorted.
std::vector<std::string> listing(const std::filesystem::path& dir);

}  // namespace tvf::test
