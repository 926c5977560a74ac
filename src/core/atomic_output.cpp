#include "tvf/core/atomic_output.h"

#include "tvf/core/error.h"

#include <algorithm>
#include <atomic>
#include <fstream>
#include <system_error>
#include <unistd.h>

namespace tvf {

namespace fs = std::filesystem;

namespace {

// One counter for every temporary name this process makes, so names made by concurrent
// threads never collide.
std::string unique_suffix() {
  static std::atomic<unsigned long long> counter{0};
  return std::to_string(::getpid()) + "-" + std::to_string(counter++);
}

[[noreturn]] void fail(const fs::path& path, const std::string& what, const std::error_code& ec) {
  throw_input_error(path.string(), "", ec ? what + " (" + ec.message() + ")" : what);
}

}  // namespace

fs::path temporary_sibling(const fs::path& path) {
  // Appended piece by piece: GCC 12 warns falsely (-Wrestrict) about "." + std::string.
  std::string name(1, '.');
  name += path.filename().string();
  name += ".tmp-";
  name += unique_suffix();
  return path.parent_path() / name;
}

void write_file_atomically(const fs::path& path, const std::function<void(std::ostream&)>& writer) {
  const fs::path tmp = temporary_sibling(path);
  std::error_code ec;
  try {
    {
      std::ofstream out(tmp, std::ios::binary | std::ios::trunc);
      if (!out) fail(path, "cannot open a temporary file next to it for writing", {});
      writer(out);
      out.close();
      if (!out) fail(path, "cannot write the file", {});
    }
    fs::rename(tmp, path, ec);
    if (ec) fail(path, "cannot move the finished file into place", ec);
  } catch (...) {
    fs::remove(tmp, ec);
    throw;
  }
}

void write_file_atomically(const fs::path& path, const std::string& bytes) {
  write_file_atomically(path, [&](std::ostream& out) {
    out.write(bytes.data(), static_cast<std::streamsize>(bytes.size()));
  });
}

OutputStage::OutputStage(const fs::path& target_dir) : target_(target_dir) {
  std::error_code ec;
  if (target_.empty()) target_ = ".";
  if (fs::exists(target_, ec)) {
    if (!fs::is_directory(target_, ec)) fail(target_, "exists and is not a folder", {});
  } else {
    created_target_ = fs::create_directories(target_, ec);
    if (ec) fail(target_, "cannot create the output folder", ec);
  }
  stage_ = target_ / (".tvf-stage-" + unique_suffix());
  if (!fs::create_directory(stage_, ec) || ec) {
    const fs::path stage = stage_;
    if (created_target_) fs::remove(target_, ec);
    fail(stage, "cannot create a staging folder", ec);
  }
}

OutputStage::~OutputStage() {
  if (committed_) return;
  std::error_code ec;
  fs::remove_all(stage_, ec);
  // fs::remove only removes an empty folder: a target that received files stays.
  if (created_target_ && fs::is_empty(target_, ec) && !ec) fs::remove(target_, ec);
}

std::vector<fs::path> OutputStage::commit() {
  TVF_CHECK(!committed_, "OutputStage::commit called twice for {}", target_.string());
  std::error_code ec;
  std::vector<fs::path> staged;
  for (fs::directory_iterator it(stage_, ec), end; !ec && it != end; it.increment(ec))
    staged.push_back(it->path());
  if (ec) fail(stage_, "cannot list the staging folder", ec);
  std::sort(staged.begin(), staged.end());

  std::vector<fs::path> written;
  written.reserve(staged.size());
  for (const fs::path& from : staged) {
    const fs::path to = target_ / from.filename();
    fs::rename(from, to, ec);
    if (ec) fail(to, "cannot move the finished file into place", ec);
    written.push_back(to);
  }
  fs::remove(stage_, ec);
  if (ec) fail(stage_, "cannot remove the staging folder", ec);
  committed_ = true;
  return written;
}

}  // namespace tvf
