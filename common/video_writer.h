#pragma once
/// MP4 videos from RGB frames, encoded by Debian's `ffmpeg` program (H.264, yuv420p, plays in
/// browsers and every player): frames go to it raw over a pipe. A separate program rather than
/// libavcodec: no codec API to follow across versions, and a crash in the encoder cannot take the
/// simulation with it. The file is written under a temporary name and renamed by Finish(), so a
/// video that exists is complete.

#include <string>

#include "common/rgb_image.h"

namespace graspbed::image {

/// Full path of program `name` found on PATH (or `name` itself when it contains a '/' and is
/// executable); "" when there is none.
std::string FindProgram(const std::string& name);

/// One video being encoded. Not copyable, not movable.
class VideoWriter {
 public:
  struct Options {
    std::string path;               ///< output .mp4
    int width_px = 640;             ///< frame width [px], even (H.264 in yuv420p needs even sizes)
    int height_px = 480;            ///< frame height [px], even
    double fps = 30.0;              ///< frames per second of the video [1/s], > 0
    std::string ffmpeg = "ffmpeg";  ///< the program: a name looked up on PATH, or a path
  };

  /// Starts ffmpeg. Throws std::invalid_argument for an odd or non-positive size or a bad frame rate,
  /// std::runtime_error when ffmpeg is not installed (saying which Debian package has it) or cannot
  /// be started.
  explicit VideoWriter(const Options& options);
  /// Stops an unfinished encoder and removes its temporary file.
  ~VideoWriter();
  VideoWriter(const VideoWriter&) = delete;
  VideoWriter& operator=(const VideoWriter&) = delete;

  /// Appends one frame of the size given at construction (blocks while ffmpeg catches up). Throws
  /// std::invalid_argument for another size, std::runtime_error when ffmpeg has failed (with its
  /// message).
  void Write(const RgbImage& frame);
  /// Ends the stream, waits for ffmpeg and renames the file into place. Throws std::runtime_error
  /// (with ffmpeg's message) when encoding failed; the temporary file is then removed.
  void Finish();
  int frames() const { return frames_; }

 private:
  void Stop();
  std::string ErrorText() const;

  Options options_;
  std::string temp_path_;
  std::string log_path_;  ///< ffmpeg's stderr
  int pipe_fd_ = -1;
  int pid_ = -1;
  int frames_ = 0;
};

/// A PNG of `count` frames evenly spaced through the video at `video_path` (of `video_frames`
/// frames), in rows of `columns` tiles, each scaled to `tile_width_px` wide (0: the frames' own size,
/// so their text stays as legible as in the video), made by ffmpeg (its select, scale and tile
/// filters). Written atomically. Throws std::invalid_argument for a bad count, column count or width,
/// std::runtime_error with ffmpeg's message.
void WriteVideoStrip(const std::string& video_path, int video_frames, int count, int columns,
                     int tile_width_px, const std::string& png_path, const std::string& ffmpeg = "ffmpeg");

}  // namespace graspbed::image
