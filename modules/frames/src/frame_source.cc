#include "bricklayer/frames/frame_source.h"

#include <algorithm>
#include <set>
#include <stdexcept>

#include <opencv2/imgcodecs.hpp>
#include <opencv2/videoio.hpp>

#include "bricklayer/common/log.h"

namespace bricklayer::frames {
namespace fs = std::filesystem;

namespace {

class CameraSource final : public FrameSource {
 public:
  CameraSource(const std::string& device, int width, int height) : device_(device) {
    bool numeric = !device.empty() && std::all_of(device.begin(), device.end(), ::isdigit);
    bool opened = numeric ? cap_.open(std::stoi(device), cv::CAP_V4L2) : cap_.open(device, cv::CAP_V4L2);
    if (!opened || !cap_.isOpened())
      throw std::runtime_error("cannot open camera '" + device + "' (is it connected? ls /dev/video*)");
    // The driver queues ~4 frames by default: a stale frame is worse than a dropped one here.
    try_set(cv::CAP_PROP_BUFFERSIZE, 1, "a one-frame buffer");
    if (width > 0) try_set(cv::CAP_PROP_FRAME_WIDTH, width, "the frame width");
    if (height > 0) try_set(cv::CAP_PROP_FRAME_HEIGHT, height, "the frame height");
    // Exposure, gain, white balance and focus are set and locked through the V4L2 controls
    // themselves (camera_controls.h), not OpenCV's CAP_PROP values, which skip what they cannot map.
    fps_ = cap_.get(cv::CAP_PROP_FPS);
    if (!(fps_ > 0)) fps_ = 30.0;
  }
  bool next(cv::Mat& frame) override { return cap_.read(frame) && !frame.empty(); }
  double rate() const override { return fps_; }
  bool live() const override { return true; }
  std::string describe() const override { return "camera " + device_; }

 private:
  void try_set(int property, double value, const char* what) {
    if (!cap_.set(property, value)) log::warn("camera ", device_, ": the driver did not accept ", what);
  }
  std::string device_;
  cv::VideoCapture cap_;
  double fps_ = 30.0;
};

class VideoSource final : public FrameSource {
 public:
  VideoSource(const std::string& path, double fps, bool loop) : path_(path), loop_(loop) {
    // A missing file is said plainly, before any backend tries it (GStreamer's attempt prints three
    // lines of its own and leaves allocations behind).
    std::error_code ec;
    if (!fs::is_regular_file(path, ec)) throw std::runtime_error("video file '" + path + "' does not exist");
    // FFmpeg first: it reads every container the exhibit records and decodes the same frames on every
    // machine, so a replayed video gives the same pixels; any other backend only if FFmpeg cannot.
    bool opened = cap_.open(path, cv::CAP_FFMPEG) && cap_.isOpened();
    if (!opened) opened = cap_.open(path) && cap_.isOpened();
    if (!opened) throw std::runtime_error("cannot open video file '" + path + "'");
    fps_ = fps > 0 ? fps : cap_.get(cv::CAP_PROP_FPS);
    if (!(fps_ > 0)) fps_ = 30.0;
  }
  bool next(cv::Mat& frame) override {
    if (cap_.read(frame) && !frame.empty()) return true;
    if (!loop_) {
      finished_ = true;
      return false;
    }
    cap_.set(cv::CAP_PROP_POS_FRAMES, 0);
    return cap_.read(frame) && !frame.empty();
  }
  double rate() const override { return fps_; }
  bool live() const override { return false; }
  bool finished() const override { return finished_; }
  std::string describe() const override { return "video " + path_; }

 private:
  std::string path_;
  bool loop_;
  bool finished_ = false;
  cv::VideoCapture cap_;
  double fps_ = 30.0;
};

class FolderSource final : public FrameSource {
 public:
  FolderSource(const std::string& dir, double fps, bool loop)
      : dir_(dir), files_(list_image_files(dir)), fps_(fps > 0 ? fps : 30.0), loop_(loop) {
    if (files_.empty()) throw std::runtime_error("folder '" + dir + "' holds no image (png, jpg, bmp, tif)");
  }
  bool next(cv::Mat& frame) override {
    // Skip unreadable files, but give up after one pass without a readable image.
    for (size_t tries = 0; tries < files_.size(); ++tries) {
      if (index_ >= files_.size()) {
        if (!loop_) {
          finished_ = true;
          return false;
        }
        index_ = 0;
      }
      const fs::path& file = files_[index_++];
      frame = cv::imread(file.string(), cv::IMREAD_COLOR);
      if (!frame.empty()) return true;
      ++unreadable_;
      // Once per file: a looping folder would otherwise say it again at every pass (30 lines a second).
      if (warned_.insert(file).second)
        log::warn("skipping unreadable image ", file.string(), " (counted at every pass; said once)");
    }
    return false;
  }
  double rate() const override { return fps_; }
  bool live() const override { return false; }
  std::string describe() const override { return "folder " + dir_ + " (" + std::to_string(files_.size()) + " images)"; }
  int64_t unreadable() const override { return unreadable_; }
  bool finished() const override { return finished_; }

 private:
  bool finished_ = false;
  std::string dir_;
  std::vector<fs::path> files_;
  double fps_;
  bool loop_;
  size_t index_ = 0;
  int64_t unreadable_ = 0;
  std::set<fs::path> warned_;
};

}  // namespace

std::vector<fs::path> list_image_files(const std::string& dir) {
  std::error_code ec;
  if (!fs::is_directory(dir, ec)) throw std::runtime_error("'" + dir + "' is not a folder");
  std::vector<fs::path> files;
  for (const auto& entry : fs::directory_iterator(dir, ec)) {
    if (!entry.is_regular_file()) continue;
    std::string ext = entry.path().extension().string();
    std::transform(ext.begin(), ext.end(), ext.begin(), ::tolower);
    if (ext == ".png" || ext == ".jpg" || ext == ".jpeg" || ext == ".bmp" || ext == ".tif" || ext == ".tiff")
      files.push_back(entry.path());
  }
  std::sort(files.begin(), files.end());
  return files;
}

std::unique_ptr<FrameSource> open_camera(const std::string& device, int width, int height) {
  return std::make_unique<CameraSource>(device, width, height);
}
std::unique_ptr<FrameSource> open_video(const std::string& path, double fps, bool loop) {
  return std::make_unique<VideoSource>(path, fps, loop);
}
std::unique_ptr<FrameSource> open_folder(const std::string& dir, double fps, bool loop) {
  return std::make_unique<FolderSource>(dir, fps, loop);
}

}  // namespace bricklayer::frames
