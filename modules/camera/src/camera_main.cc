// bricklayer-camera: camera frames onto the bus.
//
// Reads a V4L2 camera (--device 0 or /dev/video0), a video file (--video FILE) or a folder of
// images (--images DIR, name order) and publishes every frame, compressed.
// Subscribes: nothing.
// Publishes:  BL_IMAGE (image_t, JPEG or PNG) with a frame number counting from 0 and the capture
//             utime (wall clock when the frame was read); BL_HEARTBEAT once a second ("fps" value).
// A camera paces itself and its driver keeps one frame (only the newest); files are paced at --fps.
// A camera's exposure, gain, white balance and focus are set from the flags and their automatic modes
// locked (camera_controls.h); what the driver accepted is logged, and each control it lacks or
// refuses is a warning (heartbeat value "control_warnings"), never a failure.
// It never crash-loops on a missing source: a camera absent at boot or unplugged, a folder missing or
// emptied, a video file not there yet are waited for (reopened once a second) with the heartbeat's status
// saying what it waits for ("waiting for camera 0: cannot open ..."), and frames resume, numbered on,
// when the source is back. It runs on the runtime's LcmBus, so a bus outage is waited out too.
#include <chrono>
#include <filesystem>
#include <functional>
#include <iostream>

#include <opencv2/core/utils/logger.hpp>
#include <opencv2/imgcodecs.hpp>

#include "bricklayer/frames/camera_controls.h"
#include "bricklayer/frames/frame_source.h"
#include "bricklayer/common/channels.h"
#include "bricklayer/common/flags.h"
#include "bricklayer/common/lcm_url.h"
#include "bricklayer/common/log.h"
#include "bricklayer/image_t.hpp"
#include "bricklayer/runtime/lcm_bus.h"
#include "bricklayer/runtime/node.h"

namespace {

using namespace bricklayer;
using Opener = std::function<std::unique_ptr<frames::FrameSource>()>;

int64_t wall_utime() {
  return std::chrono::duration_cast<std::chrono::microseconds>(std::chrono::system_clock::now().time_since_epoch())
      .count();
}

class CameraNode final : public runtime::Node {
 public:
  // what: the source in words ("camera 0", "folder DIR"); open: opens it or throws std::runtime_error
  // saying why not; after_open: run on every source opened (a camera's controls), returns its warnings.
  CameraNode(runtime::Bus& bus, std::string what, Opener open, std::function<int(frames::FrameSource&)> after_open,
             std::string format, int quality, bool exit_when_missing)
      : Node("camera", bus),
        what_(std::move(what)),
        open_(std::move(open)),
        after_open_(std::move(after_open)),
        format_(std::move(format)),
        quality_(quality),
        exit_when_missing_(exit_when_missing),
        image_channel_(channel(kImageChannel)) {
    set_tick_ms(1000);
    set_value("waiting", 1);
  }
  // Set when the source could not be opened and --exit-when-missing asked to give up: the exit code.
  int exit_code() const { return exit_code_; }

 private:
  void tick() override {
    if (!source_ && !Open()) return;
    if (!source_->live()) {
      if (now() < next_due_) {
        wake_at(next_due_);
        return;
      }
    }
    cv::Mat frame;
    const bool got = source_->next(frame);
    const int64_t unreadable = source_->unreadable() - unreadable_seen_;  // skipped frames are errors
    unreadable_seen_ = source_->unreadable();
    if (unreadable > 0) own_counters().errors += unreadable;
    if (!got) {
      if (source_->finished()) {
        log::info(source_->describe(), ": no more frames after ", frame_number_);
        stop();
        return;
      }
      Lost("no frames from " + source_->describe());
      return;
    }
    Publish(frame);
    next_due_ = std::max(next_due_ + static_cast<int64_t>(1e6 / source_->rate()), now() - 1'000'000);
    wake_at(source_->live() ? now() : next_due_);
  }

  void before_heartbeat() override {
    const double seconds = static_cast<double>(now() - opened_utime_) / 1e6;
    if (source_ && seconds > 0) set_value("fps", static_cast<double>(frames_since_open_) / seconds);
    set_value("waiting", source_ ? 0 : 1);
    set_value("reopens", reopens_);
  }

  // Opens the source (at most once a second); false while it is not there.
  bool Open() {
    if (now() < next_open_) {
      wake_at(next_open_);
      return false;
    }
    next_open_ = now() + 1'000'000;
    // OpenCV says "can't open camera by index" at every attempt; once our own line has said it, the
    // retries run with OpenCV's warnings off (a line a second would fill a journal in a day).
    const auto opencv_level = cv::utils::logging::getLogLevel();
    if (!waiting_.empty()) cv::utils::logging::setLogLevel(cv::utils::logging::LOG_LEVEL_ERROR);
    try {
      source_ = open_();
      cv::utils::logging::setLogLevel(opencv_level);
    } catch (const std::exception& e) {
      cv::utils::logging::setLogLevel(opencv_level);
      const std::string why = "waiting for " + what_ + ": " + e.what();
      if (why != waiting_) log::warn(why, "; trying again every second");
      waiting_ = why;
      set_status(why);
      if (exit_when_missing_) {
        log::error(e.what());
        exit_code_ = 1;
        stop();
      }
      wake_at(next_open_);
      return false;
    }
    if (ever_opened_) ++reopens_;
    log::info(ever_opened_ ? "open again: " : "publishing ", source_->describe(), " on ", image_channel_, " as ", format_);
    ever_opened_ = true;
    waiting_.clear();
    unreadable_seen_ = 0;
    const int warnings = after_open_ ? after_open_(*source_) : 0;
    set_value("control_warnings", warnings);
    set_status(warnings > 0 ? "camera controls: " + std::to_string(warnings) + " warnings (see the log)" : "ok");
    opened_utime_ = now();
    frames_since_open_ = 0;
    next_due_ = now();
    return true;
  }

  void Lost(const std::string& why) {
    log::warn(why, " (", what_, " gone?); waiting for it to come back");
    source_.reset();
    waiting_ = "waiting for " + what_ + ": " + why;
    set_status(waiting_);
    next_open_ = now() + 1'000'000;
    wake_at(next_open_);
  }

  void Publish(const cv::Mat& frame) {
    image_t im{};
    im.utime = wall_utime();
    im.frame_number = frame_number_++;
    im.width = frame.cols;
    im.height = frame.rows;
    im.source = source_->describe();
    bool ok = format_ == "png" ? cv::imencode(".png", frame, im.data)
                               : cv::imencode(".jpg", frame, im.data, {cv::IMWRITE_JPEG_QUALITY, quality_});
    if (!ok) {
      error("unencodable frames", "could not encode frame " + std::to_string(im.frame_number));
      return;
    }
    im.format = format_ == "png" ? int32_t{image_t::FORMAT_PNG} : int32_t{image_t::FORMAT_JPEG};
    im.size = static_cast<int32_t>(im.data.size());
    publish(image_channel_, im);
    ++frames_since_open_;
  }

  std::string what_;
  Opener open_;
  std::function<int(frames::FrameSource&)> after_open_;
  std::unique_ptr<frames::FrameSource> source_;
  std::string format_;
  int quality_;
  bool exit_when_missing_;
  int exit_code_ = 0;
  std::string image_channel_;
  std::string waiting_;
  bool ever_opened_ = false;
  int reopens_ = 0;
  int64_t unreadable_seen_ = 0;
  int64_t frame_number_ = 0;
  int64_t frames_since_open_ = 0;
  int64_t next_open_ = 0;
  int64_t next_due_ = 0;
  int64_t opened_utime_ = 0;
};

// Sets the camera's controls; returns how many warnings it logged. Controls left unset are locked at
// what the automatic modes chose after `settle_s` seconds of frames (they adjust only while streaming).
int SetCameraControls(frames::FrameSource& source, const std::string& device, const frames::CameraControls& controls,
                      double settle_s) {
  if (!controls.all_values() && settle_s > 0) {
    log::info("letting the automatic modes settle for ", settle_s, " s before locking them");
    const auto end = std::chrono::steady_clock::now() + std::chrono::duration<double>(settle_s);
    cv::Mat frame;
    while (std::chrono::steady_clock::now() < end && !runtime::Node::stop_requested() && source.next(frame)) {
    }
  }
  try {
    frames::V4l2ControlDevice dev(device);
    int warnings = 0;
    for (const frames::ControlResult& r : frames::apply_controls(dev, controls)) {
      if (r.warning()) {
        ++warnings;
        log::warn("camera control ", r.describe());
      } else {
        log::info("camera control ", r.describe());
      }
    }
    return warnings;
  } catch (const std::exception& e) {
    log::warn("camera controls not set: ", e.what());
    return 1;
  }
}

int Main(int argc, char** argv) {
  Flags flags("bricklayer-camera", "Camera frames onto the bus: a V4L2 camera, a video file or a folder of images -> image_t on BL_IMAGE.");
  flags.add("device", "", "V4L2 camera: index (0) or path (/dev/video0)");
  flags.add("video", "", "a video file instead of a camera");
  flags.add("images", "", "a folder of images (name order) instead of a camera");
  flags.add("fps", "0", "pace for --video (0: the file's rate) and --images (0: 30)");
  flags.add_bool("loop", "--video / --images: start again at the end (else exit)");
  flags.add("width", "640", "camera frame width to request (0: the driver's)");
  flags.add("height", "480", "camera frame height to request (0: the driver's)");
  flags.add("format", "jpeg", "frame encoding: jpeg or png");
  flags.add("jpeg-quality", "90", "JPEG quality 1..100");
  frames::add_control_flags(flags);
  flags.add("settle-s", "2", "camera: seconds of frames before locking the automatic modes of controls left unset");
  flags.add_bool("list-controls", "print the camera's V4L2 controls (range, default, current value) and exit");
  flags.add_bool("exit-when-missing", "exit 1 when the source cannot be opened, instead of waiting for it (one-off runs)");
  flags.add_bool("check-config", "check the flags and the source's file or folder, start nothing (the launcher's profile check)");
  flags.add("lcm-url", "", "LCM URL (default: LCM_DEFAULT_URL, else host-only udpm ttl=0)");
  flags.add("log-level", "info", "debug, info, warn or error");
  if (!flags.parse(argc, argv)) return 0;
  log::set_level(log::parse_level(flags.get("log-level")));

  const int sources = !flags.get("device").empty() + !flags.get("video").empty() + !flags.get("images").empty();
  if (sources > 1) throw FlagError("give only one of --device, --video, --images");
  double fps = flags.get_double("fps");
  if (fps < 0 || fps > 240) throw FlagError("--fps must be between 0 and 240");
  std::string format = flags.get("format");
  if (format != "jpeg" && format != "png") throw FlagError("--format must be jpeg or png");
  int quality = static_cast<int>(flags.get_int("jpeg-quality"));
  if (quality < 1 || quality > 100) throw FlagError("--jpeg-quality must be 1..100");
  int width = static_cast<int>(flags.get_int("width")), height = static_cast<int>(flags.get_int("height"));
  if (width < 0 || height < 0 || width > 8192 || height > 8192) throw FlagError("--width/--height must be 0..8192");

  const frames::CameraControls controls = frames::parse_controls([&](const std::string& name) { return flags.get(name); });
  const double settle_s = flags.get_double("settle-s");
  if (settle_s < 0 || settle_s > 60) throw FlagError("--settle-s must be between 0 and 60");
  const std::string device = flags.get("device").empty() ? "0" : flags.get("device");
  if (flags.get_bool("list-controls")) {
    if (sources > 0 && flags.get("device").empty()) throw FlagError("--list-controls needs a camera (--device), not a file");
    frames::V4l2ControlDevice dev(device);
    std::cout << dev.describe() << "\n";
    for (const std::string& line : frames::describe_controls(dev)) std::cout << "  " << line << "\n";
    return 0;
  }

  std::string url = resolve_lcm_url(flags.get("lcm-url"));
  check_lcm_url(url);
  const bool loop = flags.get_bool("loop");
  std::string what;
  Opener open;
  std::function<int(frames::FrameSource&)> after_open;
  if (!flags.get("video").empty()) {
    const std::string path = flags.get("video");
    what = "video " + path;
    open = [path, fps, loop] { return frames::open_video(path, fps, loop); };
  } else if (!flags.get("images").empty()) {
    const std::string dir = flags.get("images");
    what = "folder " + dir;
    open = [dir, fps, loop] { return frames::open_folder(dir, fps, loop); };
  } else {
    what = "camera " + device;
    open = [device, width, height] { return frames::open_camera(device, width, height); };
    after_open = [device, controls, settle_s](frames::FrameSource& source) {
      return SetCameraControls(source, device, controls, settle_s);
    };
  }
  if (flags.get_bool("check-config")) {
    // A file source must be there; a camera may be plugged in after the start (it is waited for).
    std::error_code ec;
    const std::string path = !flags.get("video").empty() ? flags.get("video") : flags.get("images");
    if (!path.empty() && !std::filesystem::exists(path, ec)) {
      std::cerr << "bricklayer-camera: error: " << what << ": no such file or folder\n";
      std::cout << "missing files {\"source\": \"" << what << "\"}" << std::endl;
      return 2;
    }
    std::cout << "ok {\"source\": \"" << what << "\"}" << std::endl;
    return 0;
  }
  runtime::Node::install_signal_handlers();
  runtime::LcmBus bus(url, runtime::LcmBusOptions{channel(kHeartbeatChannel)});
  CameraNode node(bus, what, open, after_open, format, quality, flags.get_bool("exit-when-missing"));
  node.run();
  return node.exit_code();
}

}  // namespace

int main(int argc, char** argv) { return bricklayer::run_main("bricklayer-camera", &Main, argc, argv); }
