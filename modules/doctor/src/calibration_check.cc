#include "bricklayer/doctor/calibration_check.h"

#include <cstdio>
#include <filesystem>

#include "bricklayer/board/calibration_file.h"

namespace bricklayer::doctor {

CheckResult check_calibration(const HostPlan& plan, int64_t now_utime, double max_age_days) {
  const std::string name = "calibration";
  if (plan.calibration_file.empty()) return CheckResult::ok(name, "profile " + plan.profile + " uses none");
  const std::string calibrate = "with the exhibit running: build/bin/bricklayer-calibrate --output " + plan.calibration_file +
                                " (empty board), then the same with --scale-from-blocks (3+ blocks apart on the bottom row)";
  std::error_code ec;
  if (!std::filesystem::exists(plan.calibration_file, ec))
    return CheckResult::failed(name, plan.calibration_file + " does not exist: vision publishes no stacks without it", calibrate);
  bricklayer::calibration_t cal{};
  try {
    cal = board::load_calibration(plan.calibration_file);
  } catch (const std::exception& e) {
    return CheckResult::failed(name, e.what(), calibrate);
  }
  const std::string sizes = "camera " + std::to_string(cal.camera_width) + "x" + std::to_string(cal.camera_height) + ", projector " +
                            std::to_string(cal.projector_width) + "x" + std::to_string(cal.projector_height);
  if (plan.projection && (cal.projector_width != plan.projector_width || cal.projector_height != plan.projector_height))
    return CheckResult::failed(name, plan.calibration_file + " was made for " + sizes + ", projection draws " +
                                         std::to_string(plan.projector_width) + "x" + std::to_string(plan.projector_height),
                               "recalibrate, " + calibrate);
  const double age_days = (now_utime - cal.utime) / 86400e6;
  char age[64];
  std::snprintf(age, sizeof(age), "%.1f days", age_days);
  const std::string found = plan.calibration_file + " (" + sizes + ", mean error " +
                            std::to_string(cal.reprojection_error_mean_px).substr(0, 5) + " px)";
  if (age_days < -1)
    return CheckResult::warning(name, found + " is dated " + std::string(age + 1) + " in the future",
                                "set this host's clock (timedatectl set-ntp true)");
  if (age_days > max_age_days)
    return CheckResult::warning(name, found + " made " + age + " ago",
                                "check it: build/bin/bricklayer-calibrate --self-check --output " + plan.calibration_file +
                                    " (exit 3: it drifted, recalibrate)");
  return CheckResult::ok(name, found + ", made " + age + " ago");
}

}  // namespace bricklayer::doctor
