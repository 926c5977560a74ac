#pragma once
// MP4 video through ffmpeg (Debian package `ffmpeg`), run as a subprocess that reads raw
// RGB frames on its standard input and encodes H.264 (yuv420p, so every player opens it;
// odd sizes are padded by one pixel). The file is written under a temporary name and
// renamed when ffmpeg has finished successfully; a writer destroyed before finish()
// stops ffmpeg and removes the temporary file, leaving no partial video.
#include "tvf/render/image.h"

#include <string>
#include <vector>

namespace tvf {

struct VideoOptions {
  double fps = 25.0;
  int crf = 18;  // H.264 quality: 0 lossless … 51 worst; 18 looks lossless
  // x264's preset: veryfast halves the encoder's CPU time of its fast preset at the same
  // file size (docs/benchmarks.md, "Texture animation").
  std::string preset = "veryfast";
  // Every frame is gray (red = green = blue in every pixel): the frames go to ffmpeg as
  // one byte a pixel (a third of the pipe, no RGB → YUV conversion). The video is the
  // same yuv420p. add() throws tvf::Error on a frame with a coloured pixel.
  bool gray = false;
};

// True when an `ffmpeg` executable is on the PATH.
bool ffmpeg_available();

class VideoWriter {
public:
  // Starts ffmpeg. Throws tvf::Error naming `path` when ffmpeg is missing or cannot start.
  VideoWriter(std::string path, int width, int height, const VideoOptions& options = {});
  ~VideoWriter();
  VideoWriter(const VideoWriter&) = delete;
  VideoWriter& operator=(const VideoWriter&) = delete;

  // Appends one frame (width × height). Throws tvf::Error when ffmpeg has failed.
  void add(const Image& frame);
  // Waits for ffmpeg and moves the video into place. Throws tvf::Error with ffmpeg's last
  // message when encoding failed.
  void finish();
  int frames() const { return frames_; }

private:
  void abort();
  std::string path_, tmp_, log_;
  int width_, height_;
  int pipe_ = -1;
  int pid_ = -1;
  int frames_ = 0;
  bool gray_ = false;
  std::vector<unsigned char> buffer_;  // one frame as ffmpeg reads it
};

}  // namespace tvf
