// The calibration check on real files written by the calibration library: present and fresh, missing,
// corrupt, stale, made for another projector size.
#include <catch2/catch.hpp>

#include <filesystem>

#include "bricklayer/board/calibration_file.h"
#include "bricklayer/doctor/calibration_check.h"
#include "doctor_test_util.h"

using namespace bricklayer;
using doctor::Severity;
namespace fs = std::filesystem;

TEST_CASE("calibration: fresh ok, missing and corrupt fail, old warns, another projector size fails") {
  auto dir = test::temp_dir("calibration");
  doctor::HostPlan plan;
  plan.profile = "t";
  plan.projection = true;
  plan.calibration_file = (dir / "calibration.json").string();
  const int64_t now = 1'800'000'000'000'000;
  const int64_t day = 86'400'000'000;

  auto missing = doctor::check_calibration(plan, now, 30);
  CHECK(missing.severity == Severity::kFailed);
  CHECK(missing.detail.find("does not exist: vision publishes no stacks") != std::string::npos);
  CHECK(missing.fix.find("bricklayer-calibrate --output " + plan.calibration_file) != std::string::npos);

  calibration_t cal = board::default_calibration();
  cal.utime = now - 2 * day;
  board::save_calibration(plan.calibration_file, cal);
  auto fresh = doctor::check_calibration(plan, now, 30);
  INFO(fresh.detail);
  CHECK(fresh.severity == Severity::kOk);
  CHECK(fresh.detail.find("camera 640x480, projector 1024x768") != std::string::npos);
  CHECK(fresh.detail.find("made 2.0 days ago") != std::string::npos);

  auto old = doctor::check_calibration(plan, now + 40 * day, 30);
  CHECK(old.severity == Severity::kWarning);
  CHECK(old.fix.find("--self-check") != std::string::npos);

  auto future = doctor::check_calibration(plan, now - 5 * day, 30);
  CHECK(future.severity == Severity::kWarning);
  CHECK(future.detail.find("in the future") != std::string::npos);

  plan.projector_width = 1280;
  plan.projector_height = 800;
  auto other = doctor::check_calibration(plan, now, 30);
  CHECK(other.severity == Severity::kFailed);
  CHECK(other.detail.find("projection draws 1280x800") != std::string::npos);

  test::write_file(plan.calibration_file, "{\"format\": \"bricklayer-calibration\"");
  CHECK(doctor::check_calibration(plan, now, 30).severity == Severity::kFailed);

  plan.calibration_file.clear();
  CHECK(doctor::check_calibration(plan, now, 30).severity == Severity::kOk);
  fs::remove_all(dir);
}
