#include "bricklayer/doctor/host_plan.h"

#include <filesystem>

#include "bricklayer/common/flags.h"

namespace bricklayer::doctor {
namespace {

namespace fs = std::filesystem;

const launcher::ModuleSpec* find_program(const launcher::Profile& p, const std::string& program) {
  for (const auto& m : p.modules)
    if (!m.command.empty() && fs::path(m.command[0]).filename() == program) return &m;
  return nullptr;
}

int int_value(const std::vector<std::string>& command, const std::string& name, int fallback) {
  std::optional<std::string> v = flag_value(command, name);
  if (!v) return fallback;
  try {
    size_t used = 0;
    int n = std::stoi(*v, &used);
    if (used == v->size()) return n;
  } catch (const std::exception&) {
  }
  throw FlagError("the profile gives " + name + " '" + *v + "', not an integer");
}

std::string absolute(const std::string& root, const std::string& path) {
  if (path.empty() || fs::path(path).is_absolute()) return path;
  return (fs::path(root) / path).lexically_normal().string();
}

}  // namespace

std::optional<std::string> flag_value(const std::vector<std::string>& command, const std::string& name) {
  for (size_t i = 1; i < command.size(); ++i) {
    const std::string& a = command[i];
    if (a == name) return i + 1 < command.size() ? command[i + 1] : std::string();
    if (a.rfind(name + "=", 0) == 0) return a.substr(name.size() + 1);
  }
  return std::nullopt;
}

bool has_flag(const std::vector<std::string>& command, const std::string& name) {
  for (size_t i = 1; i < command.size(); ++i)
    if (command[i] == name || command[i].rfind(name + "=", 0) == 0) return true;
  return false;
}

HostPlan plan_host(const launcher::Profile& profile, const std::string& root, const std::string& lcm_url) {
  HostPlan plan;
  plan.profile = profile.name;
  plan.root = root;
  plan.lcm_url = lcm_url;
  plan.logger = profile.logger;

  const bool has_vision = find_program(profile, "bricklayer-vision") != nullptr;
  const bool has_prediction = find_program(profile, "bricklayer-prediction") != nullptr;
  const bool has_projection = find_program(profile, "bricklayer-projection") != nullptr;
  plan.two_hosts = (has_vision || has_prediction || has_projection) && !(has_vision && has_prediction && has_projection);

  if (const auto* m = find_program(profile, "bricklayer-projection")) {
    plan.projection = true;
    // The command the exhibit runs with a screen decides what the screen must be.
    const auto& cmd = m->command_with_display.empty() ? m->command : m->command_with_display;
    if (has_flag(cmd, "--headless")) {
      plan.display = DisplayNeed::kNone;
    } else if (has_flag(cmd, "--window")) {
      plan.display = DisplayNeed::kOptional;
    } else {
      plan.display = DisplayNeed::kFullscreen;
      plan.display_index = int_value(cmd, "--display", 0);
    }
    plan.projector_width = int_value(cmd, "--width", plan.projector_width);
    plan.projector_height = int_value(cmd, "--height", plan.projector_height);
    plan.audio = !has_flag(cmd, "--mute");
    plan.font = absolute(root, flag_value(cmd, "--font").value_or("/usr/share/fonts/truetype/dejavu/DejaVuSans-Bold.ttf"));
  }

  if (const auto* m = find_program(profile, "bricklayer-camera")) {
    const auto& cmd = m->command;
    if (auto v = flag_value(cmd, "--video"); v && !v->empty()) {
      plan.camera = HostPlan::CameraKind::kVideo;
      plan.camera_source = absolute(root, *v);
    } else if (auto f = flag_value(cmd, "--images"); f && !f->empty()) {
      plan.camera = HostPlan::CameraKind::kImages;
      plan.camera_source = absolute(root, *f);
    } else {
      plan.camera = HostPlan::CameraKind::kDevice;
      const std::string device = flag_value(cmd, "--device").value_or("");
      plan.camera_source = device.empty() ? std::string("0") : device;
    }
    plan.camera_width = int_value(cmd, "--width", plan.camera_width);
    plan.camera_height = int_value(cmd, "--height", plan.camera_height);
    if (auto fps = flag_value(cmd, "--fps")) {
      try {
        plan.camera_fps = std::stod(*fps);
      } catch (const std::exception&) {
        throw FlagError("the profile gives --fps '" + *fps + "', not a number");
      }
    }
    plan.controls = frames::parse_controls([&](const std::string& name) { return flag_value(cmd, "--" + name).value_or(""); });
  } else if (find_program(profile, "bricklayer-simcam")) {
    plan.camera = HostPlan::CameraKind::kSimulated;
  }

  if (const auto* m = find_program(profile, "bricklayer-calibrate")) {
    plan.calibration_file = absolute(root, flag_value(m->command, "--output").value_or("calibration.json"));
  } else if (const auto* v = find_program(profile, "bricklayer-vision"); v && has_flag(v->command, "--require-calibration")) {
    plan.calibration_file = absolute(root, "calibration.json");
  }
  return plan;
}

}  // namespace bricklayer::doctor
