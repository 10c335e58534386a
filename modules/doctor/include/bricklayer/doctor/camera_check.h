// The camera: present, delivering the size the calibration (or the profile) wants at the wanted rate,
// and its automatic exposure, white balance, gain and focus lockable (and locked by bricklayer-camera).
// Video files and image folders (the camera module's --video / --images) are checked the same way,
// without the controls.
#pragma once

#include <string>
#include <vector>

#include "bricklayer/frames/v4l2_device.h"
#include "bricklayer/doctor/check.h"
#include "bricklayer/doctor/host_plan.h"

namespace bricklayer::doctor {

struct CameraCheckOptions {
  double measure_s = 1.5;       // how long a live camera's frame rate is measured
  double wanted_fps = 30;       // when the profile gives no --fps
  std::string save_frame;       // write the first frame here (to see that the view covers the board)
};

std::vector<CheckResult> check_camera(const HostPlan& plan, const CameraCheckOptions& options);

// The processes other than this one that hold `path` open ("bricklayer-camera (pid 123)"), from
// /proc/*/fd: a camera in use cannot be opened for capture a second time.
std::vector<std::string> processes_using(const std::string& path);

// One line per automatic mode. camera_in_use: a capture is running (bricklayer-camera), so an
// automatic mode found on was not locked by it.
std::vector<CheckResult> check_automatic_controls(frames::ControlDevice& device, bool camera_in_use);

}  // namespace bricklayer::doctor
