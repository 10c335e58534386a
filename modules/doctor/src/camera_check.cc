#include "bricklayer/doctor/camera_check.h"

#include <unistd.h>

#include <cctype>
#include <chrono>
#include <filesystem>
#include <fstream>
#include <cstdio>
#include <memory>

#include <opencv2/imgcodecs.hpp>

#include "bricklayer/board/calibration_file.h"
#include "bricklayer/frames/camera_controls.h"
#include "bricklayer/frames/frame_source.h"
#include "bricklayer/common/log.h"

namespace bricklayer::doctor {
namespace {

std::string size_text(int w, int h) { return std::to_string(w) + "x" + std::to_string(h); }

std::string fps_text(double fps) {
  char text[32];
  std::snprintf(text, sizeof(text), "%.1f frames/s", fps);
  return text;
}

// The size vision will be calibrated for: the calibration file's, else the profile's request.
struct WantedSize {
  int width = 0, height = 0;
  std::string from;  // "calibration.json" or "the profile"
};
WantedSize wanted_size(const HostPlan& plan) {
  if (!plan.calibration_file.empty()) {
    try {
      auto cal = board::load_calibration(plan.calibration_file);
      return {cal.camera_width, cal.camera_height, plan.calibration_file};
    } catch (const std::exception&) {
      // The calibration check reports a missing or bad file.
    }
  }
  if (plan.camera == HostPlan::CameraKind::kDevice && plan.camera_width > 0 && plan.camera_height > 0)
    return {plan.camera_width, plan.camera_height, "the profile's --width/--height"};
  return {};
}

}  // namespace

std::vector<std::string> processes_using(const std::string& path) {
  namespace fs = std::filesystem;
  std::error_code ec;
  const fs::path target = fs::weakly_canonical(path, ec);
  const std::string self = std::to_string(getpid());
  std::vector<std::string> out;
  for (const auto& proc : fs::directory_iterator("/proc", ec)) {
    const std::string pid = proc.path().filename().string();
    if (pid.empty() || !std::isdigit(static_cast<unsigned char>(pid[0])) || pid == self) continue;
    std::error_code fd_ec;
    for (const auto& fd : fs::directory_iterator(proc.path() / "fd", fd_ec)) {
      std::error_code link_ec;
      if (fs::read_symlink(fd.path(), link_ec) != target) continue;
      std::string comm;
      std::ifstream(proc.path() / "comm") >> comm;
      out.push_back(comm + " (pid " + pid + ")");
      break;
    }
  }
  return out;
}

std::vector<CheckResult> check_automatic_controls(frames::ControlDevice& device, bool camera_in_use) {
  std::vector<CheckResult> out;
  for (const frames::AutomaticState& s : frames::inspect_automatic(device)) {
    if (!s.present) {
      out.push_back(s.matters ? CheckResult::warning(s.name, s.detail, "a camera with manual exposure and white balance (docs/hardware.md)")
                              : CheckResult::ok(s.name, s.detail));
    } else if (!s.lockable) {
      out.push_back(CheckResult::warning(s.name, s.detail + ": vision sees the brightness change by itself",
                                         "a camera whose automatic modes can be switched off (docs/hardware.md)"));
    } else if (s.locked) {
      out.push_back(CheckResult::ok(s.name, "locked"));
    } else if (camera_in_use) {
      out.push_back(CheckResult::warning(s.name, "on while the camera is in use: whatever captures it did not lock it",
                                         "run the camera through bricklayer-camera (it locks it), or v4l2-ctl -d DEVICE --set-ctrl"));
    } else {
      out.push_back(CheckResult::ok(s.name, "on now; lockable (bricklayer-camera locks it when it starts)"));
    }
  }
  return out;
}

std::vector<CheckResult> check_camera(const HostPlan& plan, const CameraCheckOptions& options) {
  using Kind = HostPlan::CameraKind;
  std::vector<CheckResult> out;
  if (plan.camera == Kind::kNone) return {CheckResult::ok("camera", "profile " + plan.profile + " runs no camera")};
  if (plan.camera == Kind::kSimulated) return {CheckResult::ok("camera", "the simulated camera (bricklayer-simcam)")};

  const std::string what = plan.camera == Kind::kDevice ? "camera " + frames::v4l2_device_path(plan.camera_source)
                           : plan.camera == Kind::kVideo ? "video " + plan.camera_source
                                                         : "folder " + plan.camera_source;
  bool in_use = false;
  std::unique_ptr<frames::V4l2ControlDevice> controls;
  std::unique_ptr<frames::FrameSource> source;
  if (plan.camera == Kind::kDevice) {
    try {
      controls = std::make_unique<frames::V4l2ControlDevice>(plan.camera_source);
    } catch (const std::exception& e) {
      return {CheckResult::failed("camera", e.what(), "connect the camera; list cameras with: v4l2-ctl --list-devices (package v4l-utils)")};
    }
  }
  const std::vector<std::string> users =
      plan.camera == Kind::kDevice ? processes_using(frames::v4l2_device_path(plan.camera_source)) : std::vector<std::string>{};
  try {
    if (!users.empty()) {
      in_use = true;
      std::string list;
      for (const auto& u : users) list += (list.empty() ? "" : ", ") + u;
      out.push_back(CheckResult::warning("camera", controls->describe() + " present, in use by " + list + ": size and rate not measured",
                                         "stop the exhibit and run the doctor again for the size and rate"));
    } else if (plan.camera == Kind::kDevice) {
      source = frames::open_camera(plan.camera_source, plan.camera_width, plan.camera_height);
    } else if (plan.camera == Kind::kVideo) {
      source = frames::open_video(plan.camera_source, plan.camera_fps, false);
    } else {
      source = frames::open_folder(plan.camera_source, plan.camera_fps, false);
    }
  } catch (const std::exception& e) {
    if (plan.camera != Kind::kDevice) return {CheckResult::failed("camera", e.what(), "fix --video / --images of the camera module in the profile")};
    in_use = true;  // the node opened for its controls but not for capture: someone streams from it
    out.push_back(CheckResult::warning("camera", controls->describe() + " present but cannot capture (" + e.what() +
                                                     "): in use by bricklayer-camera? size and rate not measured",
                                       "stop the exhibit and run the doctor again for the size and rate"));
  }

  if (source) {
    const WantedSize wanted = wanted_size(plan);
    cv::Mat frame;
    int frames = 0;
    double rate = source->rate();
    const auto start = std::chrono::steady_clock::now();
    std::chrono::steady_clock::time_point first_counted, last;
    bool got = source->next(frame);
    const cv::Size size = got ? frame.size() : cv::Size();
    if (got && !options.save_frame.empty() && !cv::imwrite(options.save_frame, frame))
      log::warn("could not write ", options.save_frame);
    if (got && source->live()) {
      // Measured, after a few frames (the first ones come from the driver's start-up).
      cv::Mat f;
      int seen = 0;
      while (std::chrono::steady_clock::now() - start < std::chrono::duration<double>(options.measure_s + 1) && source->next(f)) {
        const auto now = std::chrono::steady_clock::now();
        if (++seen == 3) first_counted = now;
        if (seen > 3) {
          ++frames;
          last = now;
          if (now - first_counted > std::chrono::duration<double>(options.measure_s)) break;
        }
      }
      rate = frames > 0 ? frames / std::chrono::duration<double>(last - first_counted).count() : 0;
    }
    const std::string source_text = source->describe() + (controls ? " (" + controls->card() + ")" : "");
    if (!got) {
      out.push_back(CheckResult::failed("camera", source_text + " delivered no frame", "check the cable and v4l2-ctl --list-formats-ext"));
    } else if (wanted.width > 0 && (size.width != wanted.width || size.height != wanted.height)) {
      const bool calibrated = wanted.from == plan.calibration_file;
      const std::string detail = source_text + " gives " + size_text(size.width, size.height) + ", " + wanted.from + " wants " +
                                 size_text(wanted.width, wanted.height);
      if (calibrated)
        out.push_back(CheckResult::failed("camera", detail + ": vision would measure in the wrong frame",
                                          "set the camera module's --width/--height to the calibrated size, or recalibrate"));
      else
        out.push_back(CheckResult::warning("camera", detail + ": the driver chose another size",
                                           "a size the camera offers: v4l2-ctl -d DEVICE --list-formats-ext"));
    } else {
      out.push_back(CheckResult::ok("camera", source_text + ", " + size_text(size.width, size.height) +
                                                  (wanted.width > 0 ? " as " + wanted.from + " wants" : "")));
    }
    if (got) {
      const double want_fps = plan.camera_fps > 0 ? plan.camera_fps : options.wanted_fps;
      const std::string how = source->live() ? "measured " : "paced at ";
      if (rate < 0.9 * want_fps)
        out.push_back(CheckResult::warning("camera rate", how + fps_text(rate) + ", below the wanted " + fps_text(want_fps) +
                                                              ": predictions lag the players",
                                           source->live() ? "more light or a shorter --exposure (long exposures lower the rate), "
                                                            "a USB port of its own"
                                                          : "a source of at least " + fps_text(want_fps) + " or --fps"));
      else
        out.push_back(CheckResult::ok("camera rate", how + fps_text(rate)));
    }
  }
  if (controls) {
    source.reset();  // our own capture must not count as "in use"
    for (auto& r : check_automatic_controls(*controls, in_use)) out.push_back(std::move(r));
  } else {
    out.push_back(CheckResult::ok("camera controls", "a " + std::string(plan.camera == Kind::kVideo ? "video file" : "folder of images") +
                                                         ": no exposure or white balance to lock"));
  }
  return out;
}

}  // namespace bricklayer::doctor
