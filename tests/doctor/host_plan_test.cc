// What each shipped profile asks of its host, and the doctor's line format and exit code.
#include <catch2/catch.hpp>

#include "bricklayer/doctor/check.h"
#include "bricklayer/doctor/host_plan.h"
#include "doctor_test_util.h"

using namespace bricklayer;
using namespace bricklayer::doctor;

namespace {
HostPlan plan_of(const std::string& name) {
  return plan_host(launcher::load_profile(test::shipped_profile(name)), "/exhibit", "udpm://239.255.76.67:7667?ttl=0");
}
}  // namespace

TEST_CASE("all-in-one: the projector is display 1, the camera device 0 at 640x480, calibration.json served") {
  HostPlan p = plan_of("all-in-one");
  CHECK_FALSE(p.two_hosts);
  CHECK(p.projection);
  CHECK(p.display == DisplayNeed::kFullscreen);
  CHECK(p.display_index == 1);
  CHECK(p.projector_width == 1024);
  CHECK(p.audio);
  CHECK(p.font == "/usr/share/fonts/truetype/dejavu/DejaVuSans-Bold.ttf");
  CHECK(p.camera == HostPlan::CameraKind::kDevice);
  CHECK(p.camera_source == "0");
  CHECK(p.camera_width == 640);
  CHECK(p.camera_height == 480);
  CHECK(p.controls.power_line_hz == 50);
  CHECK_FALSE(p.controls.exposure);  // shipped empty: locked at what automatic exposure chose
  CHECK(p.calibration_file == "/exhibit/calibration.json");
  REQUIRE(p.logger);
  CHECK(p.logger->budget_mb == 20000);  // a day within a budget, the oldest deleted first
  CHECK(p.logger->min_free_mb == 2000);
}

TEST_CASE("camera-host and projector-host are each one of two hosts, the demo needs no hardware") {
  HostPlan cam = plan_of("camera-host");
  CHECK(cam.two_hosts);
  CHECK_FALSE(cam.projection);
  CHECK(cam.camera == HostPlan::CameraKind::kDevice);
  CHECK_FALSE(cam.logger);
  HostPlan proj = plan_of("projector-host");
  CHECK(proj.two_hosts);
  CHECK(proj.display == DisplayNeed::kFullscreen);
  CHECK(proj.display_index == 0);
  CHECK(proj.camera == HostPlan::CameraKind::kNone);
  CHECK(proj.calibration_file.empty());
  HostPlan demo = plan_of("demo");
  CHECK_FALSE(demo.two_hosts);
  CHECK(demo.display == DisplayNeed::kOptional);
  CHECK(demo.camera == HostPlan::CameraKind::kSimulated);
}

TEST_CASE("a profile's commands are read with their programs' flags") {
  launcher::Profile p = launcher::parse_profile(R"({"modules":[
      {"name":"projection","command":["bricklayer-projection","--headless","--mute","--font=fonts/x.ttf","--width","1280"]},
      {"name":"camera","command":["bricklayer-camera","--video","clips/a.avi","--fps","12.5","--exposure","156"]},
      {"name":"vision","command":["bricklayer-vision","--require-calibration"]}]})", "t");
  HostPlan h = plan_host(p, "/r", "udpm://239.255.76.67:7667?ttl=0");
  CHECK(h.display == DisplayNeed::kNone);
  CHECK_FALSE(h.audio);
  CHECK(h.font == "/r/fonts/x.ttf");
  CHECK(h.projector_width == 1280);
  CHECK(h.camera == HostPlan::CameraKind::kVideo);
  CHECK(h.camera_source == "/r/clips/a.avi");
  CHECK(h.camera_fps == 12.5);
  CHECK(h.controls.exposure == 156);
  CHECK(h.calibration_file == "/r/calibration.json");
  CHECK(h.two_hosts);  // vision and projection, no prediction

  CHECK(flag_value({"p", "--a", "1", "--b=2"}, "--b") == "2");
  CHECK(flag_value({"p", "--a", "1"}, "--a") == "1");
  CHECK_FALSE(flag_value({"p", "--ab", "1"}, "--a"));
  launcher::Profile bad = launcher::parse_profile(R"({"modules":[{"name":"c","command":["bricklayer-camera","--exposure","bright"]}]})", "t");
  CHECK_THROWS_AS(plan_host(bad, "/r", "x"), FlagError);
}

TEST_CASE("one line per check with its fix, failed decides the exit code") {
  std::vector<CheckResult> rs = {CheckResult::ok("fonts", "DejaVu"),
                                 CheckResult::warning("audio", "no device", "connect speakers")};
  CHECK(format_line(rs[1]) == "warning  audio                no device -- fix: connect speakers");
  CHECK(format_line(rs[0]) == "ok       fonts                DejaVu");
  CHECK(exit_code(rs) == 0);
  rs.push_back(CheckResult::failed("display", "none", "connect it"));
  CHECK(exit_code(rs) == 1);
  CHECK(summary(rs) == "1 ok, 1 warning, 1 failed");
}

TEST_CASE("bricklayer-doctor: a bad profile or flag is exit 2 with the reason") {
  auto r = test::run_doctor({"no-such-profile"});
  CHECK(r.code == 2);
  CHECK(r.out.find("cannot read profile") != std::string::npos);
  r = test::run_doctor({"demo", "--checks", "bus,teeth"});
  CHECK(r.code == 2);
  CHECK(r.out.find("unknown check 'teeth'") != std::string::npos);
  r = test::run_doctor({"demo", "--listen-s", "0"});
  CHECK(r.code == 2);
}
