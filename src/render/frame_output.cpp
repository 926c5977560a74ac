#include "tvf/render/frame_output.h"

#include "tvf/core/atomic_output.h"
#include "tvf/core/error.h"

#include <fmt/format.h>
#include <tbb/parallel_pipeline.h>

#include <cmath>

namespace tvf {

namespace fs = std::filesystem;

// A folder that appears complete or not at all: frames go into a hidden sibling, which
// replaces the target folder on commit(); destroyed uncommitted, it is removed.
StagedFolder::StagedFolder(const fs::path& target) : target_(target) {
    if (!target_.has_filename()) target_ = target_.parent_path();  // "frames/" → "frames"
    std::error_code ec;
    if (target_.empty() || target_ == "." || target_ == "..")
      throw_input_error(target.string(), "", "give the frames a folder of their own (it is replaced as a whole)");
    if (fs::exists(target_, ec) && !fs::is_directory(target_, ec))
      throw_input_error(target_.string(), "", "exists and is not a folder");
    // The folder is replaced as a whole, so it may hold nothing but frames of an earlier run.
    if (fs::is_directory(target_, ec))
      for (const auto& e : fs::directory_iterator(target_, ec)) {
        const std::string name = e.path().filename().string();
        if (!(name.starts_with("frame_") && e.path().extension() == ".png"))
          throw_input_error(target_.string(), "",
                            fmt::format("holds {}, which is not a frame; give a new or empty folder for the frames", name));
      }
    if (!target_.parent_path().empty()) fs::create_directories(target_.parent_path(), ec);
    stage_ = temporary_sibling(target_);
    if (!fs::create_directory(stage_, ec) || ec)
      throw_input_error(target_.string(), "", fmt::format("cannot create the frames folder ({})", ec.message()));
  }
StagedFolder::~StagedFolder() {
    std::error_code ec;
    if (!committed_) fs::remove_all(stage_, ec);
  }
void StagedFolder::commit() {
    std::error_code ec;
    fs::path old;
    if (fs::exists(target_, ec)) {
      old = temporary_sibling(target_);
      fs::rename(target_, old, ec);
      if (ec) throw_input_error(target_.string(), "", fmt::format("cannot replace the folder ({})", ec.message()));
    }
    fs::rename(stage_, target_, ec);
    if (ec) {
      if (!old.empty()) fs::rename(old, target_, ec);
      throw_input_error(target_.string(), "", "cannot move the finished frames into place");
    }
    committed_ = true;
    if (!old.empty()) fs::remove_all(old, ec);
  }


FrameOutput::FrameOutput(const std::string& frames_dir, const std::string& video, int width, int height, double fps,
                         Sink sink, VideoOptions video_options)
    : frames_dir_(frames_dir), video_(video), width_(width), height_(height), sink_(std::move(sink)) {
  if (frames_dir.empty() && video.empty() && !sink_)
    throw Error("give a folder for the PNG frames or an MP4 file to write");
  if (!(std::isfinite(fps) && fps > 0 && fps <= 1000))
    throw Error(fmt::format("fps {} is outside (0, 1000]", fps));
  if (!frames_dir.empty()) folder_ = std::make_unique<StagedFolder>(frames_dir);
  if (!video.empty()) {
    const fs::path parent = fs::path(video).parent_path();
    std::error_code ec;
    if (!parent.empty()) fs::create_directories(parent, ec);
    video_options.fps = fps;
    writer_ = std::make_unique<VideoWriter>(video, width, height, video_options);
  }
}

void FrameOutput::add(const Image& frame) {
  if (frame.width != width_ || frame.height != height_)
    throw Error(fmt::format("frame of {}×{} pixels given to an output of {}×{}", frame.width, frame.height, width_, height_));
  if (folder_) write_png((folder_->stage() / fmt::format("frame_{:05d}.png", count_)).string(), frame);
  if (writer_) writer_->add(frame);
  if (sink_) sink_(count_, frame);
  ++count_;
}

void FrameOutput::add_in_order(int first, int last, const std::function<Image(int)>& make,
                               const std::function<void(int)>& done) {
  struct Item {
    int k;
    std::shared_ptr<Image> image;
  };
  int next = first, written = 0;
  tbb::parallel_pipeline(
      4,
      tbb::make_filter<void, Item>(tbb::filter_mode::serial_in_order,
                                   [&](tbb::flow_control& fc) -> Item {
                                     if (next > last) {
                                       fc.stop();
                                       return {};
                                     }
                                     const int k = next++;
                                     auto image = std::make_shared<Image>(make(k));
                                     if (image->width != width_ || image->height != height_)
                                       throw Error(fmt::format("frame of {}×{} pixels given to an output of {}×{}",
                                                               image->width, image->height, width_, height_));
                                     return {k, std::move(image)};
                                   }) &
          tbb::make_filter<Item, Item>(tbb::filter_mode::parallel,
                                       [&](Item item) {
                                         if (folder_)
                                           write_png((folder_->stage() / fmt::format("frame_{:05d}.png", item.k)).string(),
                                                     *item.image);
                                         return item;
                                       }) &
          tbb::make_filter<Item, void>(tbb::filter_mode::serial_in_order, [&](Item item) {
            if (writer_) writer_->add(*item.image);
            if (sink_) sink_(item.k, *item.image);
            ++count_;
            if (done) done(++written);
          }));
}

std::vector<std::string> FrameOutput::finish() {
  std::vector<std::string> files;
  if (writer_) {
    writer_->finish();
    files.push_back(video_);
  }
  if (folder_) {
    folder_->commit();
    files.push_back(frames_dir_);
  }
  return files;
}

}  // namespace tvf
