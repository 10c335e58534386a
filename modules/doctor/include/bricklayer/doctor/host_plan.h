// What a launch profile asks of this host, read from its modules' commands with the flags their
// programs take (bricklayer-projection's --display, bricklayer-camera's --device and controls,
// bricklayer-calibrate's --output, ...), so every check knows what to look for.
#pragma once

#include <cstdint>
#include <optional>
#include <string>
#include <vector>

#include "bricklayer/frames/camera_controls.h"
#include "bricklayer/launcher/profile.h"

namespace bricklayer::doctor {

enum class DisplayNeed { kNone, kOptional, kFullscreen };  // headless only / a window / a projector screen

struct HostPlan {
  std::string profile;
  std::string root;  // the project root: the profile's relative paths start there
  std::string lcm_url;
  bool two_hosts = false;  // the profile runs only part of the chain (camera-host, projector-host)

  // bricklayer-projection
  bool projection = false;
  DisplayNeed display = DisplayNeed::kNone;
  int display_index = 0;
  int projector_width = 1024, projector_height = 768;
  bool audio = false;  // projection without --mute
  std::string font;

  // bricklayer-camera (or simcam)
  enum class CameraKind { kNone, kSimulated, kDevice, kVideo, kImages } camera = CameraKind::kNone;
  std::string camera_source;  // device, video file or folder (absolute)
  int camera_width = 640, camera_height = 480;  // 0 = the driver's
  double camera_fps = 0;                        // --fps (files); 0 = the source's own
  frames::CameraControls controls;

  // bricklayer-calibrate --serve / vision --require-calibration
  std::string calibration_file;  // absolute; empty when the profile uses none

  std::optional<launcher::LoggerSpec> logger;
};

// The value of --name in a command ("--name value" or "--name=value"), or nullopt.
std::optional<std::string> flag_value(const std::vector<std::string>& command, const std::string& name);
bool has_flag(const std::vector<std::string>& command, const std::string& name);

// Throws FlagError for a value a program would refuse (a non-numeric --display).
HostPlan plan_host(const launcher::Profile& profile, const std::string& root, const std::string& lcm_url);

}  // namespace bricklayer::doctor
