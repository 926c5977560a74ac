#include "support/test_paths.h"

#include <array>
#include <atomic>
#include <cstdio>
#include <algorithm>
#include <fstream>
#include <random>
#include <sstream>
#include <sys/wait.h>
#include <unistd.h>

namespace tvf::test {

TempDir::TempDir() {
  static std::atomic<int> counter{0};
  path_ = std::filesystem::temp_directory_path() /
          ("tvf-test-" + std::to_string(::getpid()) + "-" + std::to_string(counter++));
  std::filesystem::remove_all(path_);
  std::filesystem::create_directories(path_);
}

TempDir::~TempDir() {
  std::error_code ec;
  std::filesystem::remove_all(path_, ec);
}

CommandResult run_command(const std::string& command_line) {
  CommandResult r;
  const std::string cmd = command_line + " 2>&1";
  FILE* pipe = ::popen(cmd.c_str(), "r");
  if (!pipe) return r;
  std::array<char, 4096> buf{};
  size_t n = 0;
  while ((n = std::fread(buf.data(), 1, buf.size(), pipe)) > 0) r.output.append(buf.data(), n);
  const int status = ::pclose(pipe);
  r.exit_code = WIFEXITED(status) ? WEXITSTATUS(status) : -1;
  return r;
}

CommandResult run_tvf(const std::string& arguments) {
  return run_command(std::string("'") + TVF_CLI_PATH + "' " + arguments);
}

std::string quoted(const std::filesystem::path& path) {
  // Built by appending: "'" + std::string trips GCC 12's -Wrestrict (a false positive).
  std::string s(1, '\'');
  s += path.string();
  s += '\'';
  return s;
}

std::string source_dir() { return TVF_SOURCE_DIR; }
std::string cli_path() { return TVF_CLI_PATH; }
std::string test_data_dir() { return TVF_TEST_DATA_DIR; }
std::string python() { return TVF_PYTHON; }

void write_text(const std::filesystem::path& path, const std::string& text) {
  std::ofstream out(path, std::ios::binary);
  out << text;
}

std::vector<std::string> listing(const std::filesystem::path& dir) {
  std::vector<std::string> names;
  for (const auto& e : std::filesystem::directory_iterator(dir)) names.push_back(e.path().filename().string());
  std::sort(names.begin(), names.end());
  return names;
}

std::string read_text(const std::filesystem::path& path) {
  std::ifstream in(path, std::ios::binary);
  std::stringstream ss;
  ss << in.rdbuf();
  return ss.str();
}

std::optional<std::filesystem::path> cgal_mesh(const TempDir& dir, const std::string& name) {
  const std::string member = "data/meshes/" + name + ".off";
  if (!std::filesystem::exists(kCgalArchive)) return std::nullopt;
  const CommandResult r = run_command("tar -xzf " + quoted(kCgalArchive) + " -C " + quoted(dir.path()) + " " + member);
  if (r.exit_code != 0) return std::nullopt;
  return dir / member;
}

}  // namespace tvf::test
