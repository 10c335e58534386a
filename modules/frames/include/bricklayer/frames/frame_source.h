// Where camera frames come from: a V4L2 camera, a video file or a folder of images.
// One interface so bricklayer-camera can publish any of them the same way.
#pragma once

#include <cstdint>
#include <filesystem>
#include <memory>
#include <string>
#include <vector>

#include <opencv2/core.hpp>

namespace bricklayer::frames {

class FrameSource {
 public:
  virtual ~FrameSource() = default;
  // The next frame (BGR); false when the source is exhausted or has failed (finished() tells which).
  virtual bool next(cv::Mat& frame) = 0;
  // True once a file source without loop has delivered its last frame: its end, not a failure. After a
  // false next() that is not the end (a camera unplugged, a folder emptied), the source is gone and a
  // publisher opens it again when it is back.
  virtual bool finished() const { return false; }
  // Frames per second the source delivers on its own (a camera) or should be paced at (files), > 0.
  virtual double rate() const = 0;
  // True for a live camera: it paces itself, so the publisher must not sleep between frames.
  virtual bool live() const = 0;
  virtual std::string describe() const = 0;
  // Frames the source could not read and skipped (a corrupt image in a folder), so far: the caller counts
  // them as errors (a skipped frame must not vanish silently).
  virtual int64_t unreadable() const { return 0; }
};

// A V4L2 camera: "0" or "/dev/video0". Keeps a one-frame driver buffer (only the newest frame).
// Its exposure, gain, white balance and focus are camera_controls.h's business.
// Throws std::runtime_error when the device cannot be opened.
std::unique_ptr<FrameSource> open_camera(const std::string& device, int width, int height);

// A video file, paced at fps (0: the file's own rate, else 30). Throws when it cannot be opened.
std::unique_ptr<FrameSource> open_video(const std::string& path, double fps, bool loop);

// The images of a folder in name order (png, jpg, jpeg, bmp, tif, tiff), paced at fps. An unreadable
// image is skipped with a warning and counted in unreadable(). Throws when the folder is missing or holds no image.
std::unique_ptr<FrameSource> open_folder(const std::string& dir, double fps, bool loop);

// The image files of dir in name order.
std::vector<std::filesystem::path> list_image_files(const std::string& dir);

}  // namespace bricklayer::frames
