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
#include <chrono>
#include <iostream>

#include <opencv2/imgcodecs.hpp>

#include "bricklayer/frames/camera_controls.h"
#include "bricklayer/frames/frame_source.h"
#include "bricklayer/common/channels.h"
#include "bricklayer/common/flags.h"
#include "bricklayer/common/lcm_url.h"
#include "bricklayer/common/log.h"
#include "bricklayer/common/module.h"
#include "bricklayer/image_t.hpp"

namespace {

using namespace bricklayer;

class CameraProcess {
 public:
  CameraProcess(const std::string& url, std::unique_ptr<frames::FrameSource> source, std::string format, int quality)
      : module_("camera", url),
        source_(std::move(source)),
        format_(std::move(format)),
        quality_(quality),
        image_channel_(channel(kImageChannel)) {
    log::info("publishing ", source_->describe(), " on ", image_channel_, " as ", format_);
  }

  void ReportControlWarnings(int warnings) {
    module_.set_value("control_warnings", warnings);
    if (warnings > 0) module_.set_status("camera controls: " + std::to_string(warnings) + " warnings (see the log)");
  }

  int Run() {
    started_ = std::chrono::steady_clock::now();
    return module_.run([this] { Tick(); }, 1);
  }

 private:
  void Tick() {
    if (!source_->live()) {
      auto due = started_ + std::chrono::microseconds(static_cast<int64_t>(1e6 * frame_number_ / source_->rate()));
      if (std::chrono::steady_clock::now() < due) return;
    }
    cv::Mat frame;
    const bool got = source_->next(frame);
    module_.counters().errors += source_->unreadable() - unreadable_seen_;  // skipped frames are errors
    unreadable_seen_ = source_->unreadable();
    if (!got) {
      log::info(source_->describe(), ": no more frames after ", frame_number_);
      Module::request_stop();
      return;
    }
    image_t im{};
    im.utime = wall_utime();
    im.frame_number = frame_number_++;
    im.width = frame.cols;
    im.height = frame.rows;
    im.source = source_->describe();
    bool ok = format_ == "png" ? cv::imencode(".png", frame, im.data)
                               : cv::imencode(".jpg", frame, im.data, {cv::IMWRITE_JPEG_QUALITY, quality_});
    if (!ok) {
      ++module_.counters().errors;
      log::warn("could not encode frame ", im.frame_number);
      return;
    }
    im.format = format_ == "png" ? int32_t{image_t::FORMAT_PNG} : int32_t{image_t::FORMAT_JPEG};
    im.size = static_cast<int32_t>(im.data.size());
    module_.publish(image_channel_, im);
    double seconds = std::chrono::duration<double>(std::chrono::steady_clock::now() - started_).count();
    if (seconds > 0) module_.set_value("fps", frame_number_ / seconds);
  }

  Module module_;  // owns the LCM handle
  std::unique_ptr<frames::FrameSource> source_;
  int64_t unreadable_seen_ = 0;
  std::string format_;
  int quality_;
  std::string image_channel_;
  int64_t frame_number_ = 0;
  std::chrono::steady_clock::time_point started_;
};

// Sets the camera's controls; returns how many warnings it logged. Controls left unset are locked at
// what the automatic modes chose after `settle_s` seconds of frames (they adjust only while streaming).
int SetCameraControls(frames::FrameSource& source, const std::string& device, const frames::CameraControls& controls,
                      double settle_s) {
  if (!controls.all_values() && settle_s > 0) {
    log::info("letting the automatic modes settle for ", settle_s, " s before locking them");
    const auto end = std::chrono::steady_clock::now() + std::chrono::duration<double>(settle_s);
    cv::Mat frame;
    while (std::chrono::steady_clock::now() < end && !Module::stop_requested() && source.next(frame)) {
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
  std::unique_ptr<frames::FrameSource> source;
  int control_warnings = 0;
  if (!flags.get("video").empty()) {
    source = frames::open_video(flags.get("video"), fps, flags.get_bool("loop"));
  } else if (!flags.get("images").empty()) {
    source = frames::open_folder(flags.get("images"), fps, flags.get_bool("loop"));
  } else {
    source = frames::open_camera(device, width, height);
    control_warnings = SetCameraControls(*source, device, controls, settle_s);
  }
  CameraProcess process(url, std::move(source), format, quality);
  process.ReportControlWarnings(control_warnings);
  return process.Run();
}

}  // namespace

int main(int argc, char** argv) { return bricklayer::run_main("bricklayer-camera", &Main, argc, argv); }
