#pragma once
// Where the pictures of an animation go: a folder of PNG frames (frame_00000.png …) that
// appears complete or not at all, and/or an MP4 (video.h). Shared by every `tvf render`
// kind (texture, painterly, crowd, particles).
#include "tvf/render/image.h"
#include "tvf/render/video.h"

#include <filesystem>
#include <functional>
#include <memory>
#include <string>
#include <vector>

namespace tvf {

// A folder that appears complete or not at all: frames go into a hidden sibling, which
// replaces the target folder on commit(); destroyed uncommitted, it is removed. An
// existing target may hold nothing but frame_*.png files (it is replaced as a whole).
class StagedFolder {
public:
  explicit StagedFolder(const std::filesystem::path& target);
  ~StagedFolder();
  StagedFolder(const StagedFolder&) = delete;
  StagedFolder& operator=(const StagedFolder&) = delete;
  const std::filesystem::path& stage() const { return stage_; }
  void commit();

private:
  std::filesystem::path target_, stage_;
  bool committed_ = false;
};

// PNG frames and/or MP4, frames given in order. Nothing appears unless finish() is called.
class FrameOutput {
public:
  // A frame as it is handed on in order: its number (k of add_in_order; 0, 1, … for add)
  // and the picture (e.g. kept in memory by the Python module's render_texture).
  using Sink = std::function<void(int k, const Image& frame)>;
  // frames_dir or video may be empty (not both, unless a sink takes the frames). Throws
  // tvf::Error naming the output. The video is encoded with video_options (its fps
  // replaced by fps).
  FrameOutput(const std::string& frames_dir, const std::string& video, int width, int height, double fps,
              Sink sink = {}, VideoOptions video_options = {});
  void add(const Image& frame);
  // Frames first … last: make(k) runs in order (one at a time, on whichever thread the
  // pipeline picks), the PNGs (frame_<k>.png) are encoded in parallel while the next
  // frames are made, and the video is fed in order; done(n) after each frame written.
  void add_in_order(int first, int last, const std::function<Image(int)>& make,
                    const std::function<void(int)>& done = {});
  // Finishes the video and moves the frames into place; returns what was written.
  std::vector<std::string> finish();
  int frames() const { return count_; }

private:
  std::string frames_dir_, video_;
  int width_, height_;
  std::unique_ptr<StagedFolder> folder_;
  std::unique_ptr<VideoWriter> writer_;
  Sink sink_;
  int count_ = 0;
};

}  // namespace tvf
