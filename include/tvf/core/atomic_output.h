#pragma once
// Outputs appear complete or not at all: files are written under a temporary name and
// renamed into place when complete (DESIGN §11, engineering standards).
#include <filesystem>
#include <functional>
#include <ostream>
#include <string>
#include <vector>

namespace tvf {

// Path of a temporary sibling of `path` (same folder, so rename() is atomic).
std::filesystem::path temporary_sibling(const std::filesystem::path& path);

// Writes `bytes` to `path` atomically. Throws tvf::Error naming `path` on failure.
void write_file_atomically(const std::filesystem::path& path, const std::string& bytes);

// Streams a file to `path` atomically: `writer` fills a binary stream opened on a
// temporary sibling, which is renamed into place once the stream is closed without
// error. If `writer` throws or the stream fails, the temporary file is removed and the
// target is left as it was. Throws tvf::Error naming `path` on failure.
void write_file_atomically(const std::filesystem::path& path,
                           const std::function<void(std::ostream&)>& writer);

// A staging folder inside `target_dir`: files are written into stage(), and commit()
// moves them all into target_dir. Destroyed uncommitted, it removes the staging folder
// and everything in it, so a failed run leaves no partial output.
class OutputStage {
public:
  explicit OutputStage(const std::filesystem::path& target_dir);
  ~OutputStage();
  OutputStage(const OutputStage&) = delete;
  OutputStage& operator=(const OutputStage&) = delete;

  const std::filesystem::path& stage() const { return stage_; }
  std::filesystem::path file(const std::string& name) const { return stage_ / name; }
  // Moves every staged file into the target folder (replacing files of the same name)
  // and returns their final paths.
  std::vector<std::filesystem::path> commit();

private:
  std::filesystem::path target_;
  std::filesystem::path stage_;
  bool created_target_ = false;
  bool committed_ = false;
};

}  // namespace tvf
