#pragma once
// Outputs appear complete or not at all: files are written under a temporary name and
// renamed into place when complete (DESIGN §11, engineering standards). The promise, as
// docs/file_formats.md ("Atomic outputs") states it:
//  - a single file (write_file_atomically) is the old file or the new one, never a mix,
//    and once the call returns it survives a power loss (the file and its folder are
//    fsynced);
//  - a folder of outputs (OutputStage) is committed as a whole: while its files are being
//    moved into place the folder holds the marker kCommitMarker, written (and fsynced)
//    before the first file moves and removed after the last; readers (tvf's own, through
//    check_output_complete) refuse a folder that holds it. The files of the previous run
//    that this run does not write (those its `owned` names) are removed in the same window.
//    Staging folders of runs that died (SIGKILL, power loss) are removed by the next
//    OutputStage in the same folder; SIGINT and SIGTERM remove them at once
//    (install_output_cleanup_on_signals).
#include <filesystem>
#include <functional>
#include <ostream>
#include <string>
#include <string_view>
#include <vector>

namespace tvf {

// The marker present in an output folder while a commit is under way (or was interrupted).
inline constexpr const char* kCommitMarker = ".tvf-committing";

// Throws tvf::Error naming `dir` when it holds kCommitMarker: an interrupted run left a
// mix of two runs' files there.
void check_output_complete(const std::filesystem::path& dir);

// Installs SIGINT and SIGTERM handlers that remove the staging folders of every live
// OutputStage (with async-signal-safe system calls only), then end the process as the
// signal would have. For the command line; a program that handles the signals itself
// (tvf serve) does not call it.
void install_output_cleanup_on_signals();

// Flushes a file or folder to the disk (fsync). Throws tvf::Error naming it on failure.
void sync_path(const std::filesystem::path& path);

// Path of a temporary sibling of `path` (same folder, so rename() is atomic).
std::filesystem::path temporary_sibling(const std::filesystem::path& path);

// An output file's path checked before the work that makes it: throws tvf::Error naming it
// when it is a folder, or when a part of its folder's path is a file, so a command refuses
// at once instead of after its work. A folder that is missing is fine (see below).
void check_output_file(const std::filesystem::path& file);

// Creates the folder an output file goes into when it is missing (as the commands' output
// folders are created); throws tvf::Error naming it when it cannot.
void create_output_folder_for(const std::filesystem::path& file);

// Writes `bytes` to `path` atomically. Throws tvf::Error naming `path` on failure.
void write_file_atomically(const std::filesystem::path& path, const std::string& bytes);

// Streams a file to `path` atomically: `writer` fills a binary stream opened on a
// temporary sibling, which is renamed into place once the stream is closed without
// error. If `writer` throws or the stream fails, the temporary file is removed and the
// target is left as it was. Throws tvf::Error naming `path` on failure.
void write_file_atomically(const std::filesystem::path& path,
                           const std::function<void(std::ostream&)>& writer);

// Whether `name` is `prefix`, one or more digits, then `suffix` (field_0042.vtu): the names
// an OutputStage::commit's `owned` claims for numbered outputs of an earlier run.
bool is_numbered_name(std::string_view name, std::string_view prefix, std::string_view suffix);

// A staging folder inside `target_dir`: files are written into stage(), and commit()
// moves them all into target_dir (see the promise above). Destroyed uncommitted, it removes
// the staging folder and everything in it, so a failed run leaves no partial output.
// Creating one removes the staging folders that dead processes left in target_dir.
class OutputStage {
public:
  explicit OutputStage(const std::filesystem::path& target_dir);
  ~OutputStage();
  OutputStage(const OutputStage&) = delete;
  OutputStage& operator=(const OutputStage&) = delete;

  const std::filesystem::path& stage() const { return stage_; }
  std::filesystem::path file(const std::string& name) const { return stage_ / name; }
  // Moves every staged file into the target folder (replacing files of the same name)
  // and returns their final paths. Files of the target that this commit does not write
  // and that `owned` claims (outputs of an earlier run, like field_0099.vtu when this run
  // has fewer frames) are removed in the same commit; all other files stay.
  std::vector<std::filesystem::path> commit(const std::function<bool(const std::string&)>& owned = {});

private:
  std::filesystem::path target_;
  std::filesystem::path stage_;
  bool created_target_ = false;
  bool committed_ = false;
  int slot_ = -1;  // in the table the signal handlers clean
};

}  // namespace tvf
