#include "tvf/core/atomic_output.h"

#include "tvf/core/error.h"

#include <algorithm>
#include <array>
#include <atomic>
#include <cerrno>
#include <climits>
#include <csignal>
#include <cstring>
#include <fstream>
#include <set>
#include <system_error>

#include <fcntl.h>
#include <sys/syscall.h>
#include <sys/types.h>
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

// --- Staging folders the signal handlers remove -----------------------------------------

struct StageSlot {
  std::atomic<bool> claimed{false};  // taken by an OutputStage
  std::atomic<bool> ready{false};    // path is complete: the handler may use it
  char path[PATH_MAX] = {};
};
std::array<StageSlot, 64> g_stages;
static_assert(std::atomic<bool>::is_always_lock_free);

int register_stage(const fs::path& stage) {
  const std::string p = fs::absolute(stage).string();
  if (p.size() >= PATH_MAX) return -1;
  for (size_t i = 0; i < g_stages.size(); ++i) {
    bool expected = false;
    if (!g_stages[i].claimed.compare_exchange_strong(expected, true)) continue;
    std::memcpy(g_stages[i].path, p.c_str(), p.size() + 1);
    g_stages[i].ready.store(true, std::memory_order_release);
    return static_cast<int>(i);
  }
  return -1;  // more than 64 at once: these are cleaned on the next start instead
}

void unregister_stage(int slot) {
  if (slot < 0) return;
  g_stages[static_cast<size_t>(slot)].ready.store(false, std::memory_order_release);
  g_stages[static_cast<size_t>(slot)].claimed.store(false, std::memory_order_release);
}

// Removes a staging folder and the files in it with system calls that are safe in a
// signal handler (open, getdents64, unlinkat, close, rmdir; no allocation).
void remove_stage_raw(const char* path) {
  const int fd = ::open(path, O_RDONLY | O_DIRECTORY | O_CLOEXEC);
  if (fd < 0) return;
  // struct linux_dirent64: d_ino (8 bytes), d_off (8), d_reclen (2), d_type (1), d_name.
  constexpr long kReclen = 16, kName = 19;
  alignas(8) char buffer[4096];
  for (int pass = 0; pass < 2; ++pass) {
    ::lseek(fd, 0, SEEK_SET);
    for (;;) {
      const long n = ::syscall(SYS_getdents64, fd, buffer, sizeof(buffer));
      if (n <= 0) break;
      for (long at = 0; at < n;) {
        unsigned short reclen = 0;
        std::memcpy(&reclen, buffer + at + kReclen, sizeof(reclen));
        const char* name = buffer + at + kName;
        at += reclen;
        if (reclen == 0) break;
        if (std::strcmp(name, ".") == 0 || std::strcmp(name, "..") == 0) continue;
        if (::unlinkat(fd, name, 0) != 0) ::unlinkat(fd, name, AT_REMOVEDIR);
      }
    }
  }
  ::close(fd);
  ::rmdir(path);
}

extern "C" void tvf_remove_stages_on_signal(int signal_number) {
  for (StageSlot& slot : g_stages)
    if (slot.ready.load(std::memory_order_acquire)) remove_stage_raw(slot.path);
  // End the process as the signal would have.
  ::signal(signal_number, SIG_DFL);
  ::raise(signal_number);
}

// The pid in a staging folder's name ".tvf-stage-PID-N", or -1.
long stage_owner(const std::string& name) {
  static const std::string prefix = ".tvf-stage-";
  if (name.compare(0, prefix.size(), prefix) != 0) return -1;
  const std::string rest = name.substr(prefix.size());
  const auto dash = rest.find('-');
  if (dash == 0 || dash == std::string::npos) return -1;
  long pid = 0;
  for (size_t i = 0; i < dash; ++i) {
    if (rest[i] < '0' || rest[i] > '9' || pid > 100'000'000) return -1;
    pid = pid * 10 + (rest[i] - '0');
  }
  return pid;
}

// Removes the staging folders in `dir` whose process is gone (killed, or the machine lost
// power); those of live processes (a concurrent run) stay.
void remove_dead_stages(const fs::path& dir) {
  std::error_code ec;
  for (fs::directory_iterator it(dir, ec), end; !ec && it != end; it.increment(ec)) {
    const long pid = stage_owner(it->path().filename().string());
    if (pid <= 0 || pid == static_cast<long>(::getpid())) continue;
    if (::kill(static_cast<pid_t>(pid), 0) == 0 || errno != ESRCH) continue;
    std::error_code ignored;
    fs::remove_all(it->path(), ignored);
  }
}

}  // namespace

void sync_path(const fs::path& path) {
  const int fd = ::open(path.c_str(), O_RDONLY | O_CLOEXEC);
  if (fd < 0) fail(path, "cannot open it to flush it to the disk", std::error_code(errno, std::generic_category()));
  const int rc = ::fsync(fd);
  const int error = errno;
  ::close(fd);
  // Some file systems cannot fsync a folder (EINVAL): nothing more can be done there.
  if (rc != 0 && error != EINVAL && error != EROFS)
    fail(path, "cannot flush it to the disk", std::error_code(error, std::generic_category()));
}

void check_output_complete(const fs::path& dir) {
  std::error_code ec;
  if (fs::exists(dir / kCommitMarker, ec))
    throw_input_error(dir.string(), "",
                      fmt::format("the folder holds an interrupted output ({} is there: a run stopped while moving "
                                  "its files into place, so they may come from two runs); run tvf generate again",
                                  kCommitMarker));
}

void install_output_cleanup_on_signals() {
  struct sigaction action {};
  action.sa_handler = tvf_remove_stages_on_signal;
  sigemptyset(&action.sa_mask);
  action.sa_flags = SA_RESETHAND;
  sigaction(SIGINT, &action, nullptr);
  sigaction(SIGTERM, &action, nullptr);
}

fs::path temporary_sibling(const fs::path& path) {
  // Appended piece by piece: GCC 12 warns falsely (-Wrestrict) about "." + std::string.
  std::string name(1, '.');
  name += path.filename().string();
  name += ".tmp-";
  name += unique_suffix();
  return path.parent_path() / name;
}

void check_output_file(const fs::path& file) {
  std::error_code ec;
  if (file.empty()) throw_input_error("", "", "the output file is an empty path");
  if (fs::is_directory(file, ec)) fail(file, "is a folder; give the name of the file to write", {});
  // The nearest part of the folder's path that exists must be a folder.
  for (fs::path p = file.parent_path(); !p.empty(); p = p.parent_path()) {
    const fs::file_status st = fs::status(p, ec);
    if (fs::exists(st)) {
      if (!fs::is_directory(st)) fail(file, fmt::format("cannot be written: {} is not a folder", p.string()), {});
      break;
    }
    if (p == p.parent_path()) break;
  }
}

void create_output_folder_for(const fs::path& file) {
  const fs::path parent = file.parent_path();
  std::error_code ec;
  if (parent.empty() || fs::is_directory(parent, ec)) return;
  fs::create_directories(parent, ec);
  if (ec) fail(parent, "cannot create the output folder", ec);
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
    // Durable before it is visible, and the rename durable once we return.
    sync_path(tmp);
    fs::rename(tmp, path, ec);
    if (ec) fail(path, "cannot move the finished file into place", ec);
    const fs::path parent = path.parent_path().empty() ? fs::path(".") : path.parent_path();
    sync_path(parent);
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
  if (target_.empty())
    throw_input_error("", "", "the output folder is an empty path; give a folder (\".\" for the current one)");
  if (fs::exists(target_, ec)) {
    if (!fs::is_directory(target_, ec)) fail(target_, "exists and is not a folder", {});
  } else {
    created_target_ = fs::create_directories(target_, ec);
    if (ec) fail(target_, "cannot create the output folder", ec);
  }
  remove_dead_stages(target_);
  stage_ = target_ / (".tvf-stage-" + unique_suffix());
  if (!fs::create_directory(stage_, ec) || ec) {
    const fs::path stage = stage_;
    if (created_target_) fs::remove(target_, ec);
    fail(stage, "cannot create a staging folder", ec);
  }
  slot_ = register_stage(stage_);
}

OutputStage::~OutputStage() {
  unregister_stage(slot_);
  if (committed_) return;
  std::error_code ec;
  fs::remove_all(stage_, ec);
  // fs::remove only removes an empty folder: a target that received files stays.
  if (created_target_ && fs::is_empty(target_, ec) && !ec) fs::remove(target_, ec);
}

std::vector<fs::path> OutputStage::commit(const std::function<bool(const std::string&)>& owned) {
  TVF_CHECK(!committed_, "OutputStage::commit called twice for {}", target_.string());
  std::error_code ec;
  std::vector<fs::path> staged;
  for (fs::directory_iterator it(stage_, ec), end; !ec && it != end; it.increment(ec))
    staged.push_back(it->path());
  if (ec) fail(stage_, "cannot list the staging folder", ec);
  std::sort(staged.begin(), staged.end());
  std::set<std::string> names;
  for (const fs::path& from : staged) names.insert(from.filename().string());

  // 1. Every new file on the disk before any old one is touched.
  for (const fs::path& from : staged) sync_path(from);
  sync_path(stage_);

  // 2. The marker: from here until it is removed, readers refuse the folder.
  const fs::path marker = target_ / kCommitMarker;
  {
    std::ofstream out(marker, std::ios::binary | std::ios::trunc);
    out << "a tvf run is moving its files into this folder\n";
    out.close();
    if (!out) fail(marker, "cannot write the commit marker", {});
  }
  sync_path(marker);
  sync_path(target_);

  // 3. The files of the previous run that this one does not write.
  if (owned) {
    std::vector<fs::path> stale;
    for (fs::directory_iterator it(target_, ec), end; !ec && it != end; it.increment(ec)) {
      const std::string name = it->path().filename().string();
      if (!names.count(name) && owned(name) && !it->is_directory(ec)) stale.push_back(it->path());
    }
    for (const fs::path& old : stale) fs::remove(old, ec);
  }

  // 4. The new files.
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

  // 5. The marker goes: the folder is whole again.
  fs::remove(marker, ec);
  if (ec) fail(marker, "cannot remove the commit marker", ec);
  sync_path(target_);
  committed_ = true;
  return written;
}

bool is_numbered_name(std::string_view name, std::string_view prefix, std::string_view suffix) {
  if (name.size() <= prefix.size() + suffix.size() || !name.starts_with(prefix) || !name.ends_with(suffix))
    return false;
  for (size_t k = prefix.size(); k < name.size() - suffix.size(); ++k)
    if (name[k] < '0' || name[k] > '9') return false;
  return true;
}

}  // namespace tvf
