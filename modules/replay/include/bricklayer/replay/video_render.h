// A recorded moment as a video anyone can open: the camera frame and what the projector showed side by
// side, with the time of day, the score, the verdict and the round, written by OpenCV's VideoWriter
// (MPEG-4 part 2 in an .mp4, or MJPEG in an .avi).
//
// The projector side is the projector_state_t image projection published (what it showed, at the
// resolution it recorded), not a redraw. Pace: the video runs at 30 frames a second of log time divided
// by speed; a moment without a new camera frame (frames thinned by the logger's policy) repeats the last
// picture, so the video's clock stays the log's.
#pragma once

#include <cstdint>
#include <memory>
#include <optional>
#include <string>

#include <opencv2/core.hpp>

#include "bricklayer/prediction_t.hpp"
#include "bricklayer/round_t.hpp"
#include "bricklayer/runtime/log_file.h"

namespace cv {
class VideoWriter;
}

namespace bricklayer::replay {

struct VideoOptions {
  std::string path;    // .mp4 (MPEG-4) or .avi (MJPEG)
  double speed = 1.0;  // 1 = recorded pace, 4 = four times faster
  double fps = 30.0;   // video frames per second
};

struct VideoSummary {
  int64_t video_frames = 0;   // frames written
  int64_t camera_frames = 0;  // camera frames drawn
  int64_t bad_frames = 0;     // camera or projector images that did not decode (drawn as a notice)
  double duration_s = 0;      // of the video
};

class VideoRenderer {
 public:
  static constexpr int kSideWidth = 640, kSideHeight = 480, kStripHeight = 64;

  // Throws std::invalid_argument for bad options; the file is opened at the first camera frame.
  explicit VideoRenderer(VideoOptions options);
  ~VideoRenderer();

  // Every event of the range, in order: camera frames are drawn, predictions, rounds and projector
  // images update what is drawn beside them.
  void observe(const runtime::LogEvent& e);
  // Writes the last picture up to the last event's time and closes the file. Throws std::runtime_error
  // when no writer could be opened (no camera frame in the range, or an unknown container).
  VideoSummary finish();

  // The picture for a camera frame at utime (exposed for tests).
  cv::Mat compose(const cv::Mat& camera, int64_t utime) const;

 private:
  int64_t index_of(int64_t utime) const;
  // Writes the current picture until the video holds `index` frames.
  void write_before(int64_t index);

  VideoOptions options_;
  std::unique_ptr<cv::VideoWriter> writer_;
  cv::Mat picture_, projector_;
  std::optional<prediction_t> prediction_;
  std::optional<round_t> round_;
  int64_t first_utime_ = -1, last_utime_ = -1;
  VideoSummary summary_;
};

}  // namespace bricklayer::replay
