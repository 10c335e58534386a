// camera_controls.h against a device that behaves like a V4L2 driver (fake_control_device.h: no
// camera exists on a CI machine), and V4l2ControlDevice against the real kernel where it can be
// reached without one (a missing node, a node that is not a V4L2 device).
#include <catch2/catch.hpp>

#include <linux/videodev2.h>

#include <algorithm>
#include <cstdio>
#include <map>
#include <string>

#include "bricklayer/frames/camera_controls.h"
#include "fake_control_device.h"

using namespace bricklayer;
using frames::ControlOutcome;
using frames::ControlResult;
using test::FakeControlDevice;

namespace {
std::map<std::string, ControlResult> by_name(const std::vector<ControlResult>& results) {
  std::map<std::string, ControlResult> out;
  for (const auto& r : results) out[r.name] = r;
  return out;
}
int warnings(const std::vector<ControlResult>& results) {
  return static_cast<int>(std::count_if(results.begin(), results.end(), [](const ControlResult& r) { return r.warning(); }));
}
}  // namespace

TEST_CASE("every automatic mode is locked before its manual value is set, and every value is read back") {
  FakeControlDevice dev = FakeControlDevice::uvc_webcam();
  frames::CameraControls want;
  want.exposure = 100;
  want.gain = 0;
  want.white_balance_k = 4600;
  want.focus = 40;
  want.power_line_hz = 50;
  auto results = frames::apply_controls(dev, want);
  for (const auto& r : results) INFO(r.describe());
  CHECK(warnings(results) == 0);
  auto r = by_name(results);
  CHECK(r["auto exposure"].outcome == ControlOutcome::kLocked);
  CHECK(r["auto white balance"].outcome == ControlOutcome::kLocked);
  CHECK(r["auto focus"].outcome == ControlOutcome::kLocked);
  CHECK(r["exposure priority"].outcome == ControlOutcome::kLocked);
  CHECK(r["auto gain"].outcome == ControlOutcome::kAbsent);  // UVC: gain follows auto exposure
  CHECK_FALSE(r["auto gain"].warning());
  CHECK(r["exposure"].outcome == ControlOutcome::kSet);
  CHECK(r["exposure"].accepted == 100);
  CHECK(r["white balance"].accepted == 4600);
  CHECK(r["focus"].accepted == 40);
  CHECK(r["power line"].outcome == ControlOutcome::kSet);
  // The device holds them (the manual ones were writable only because the automatic ones went first).
  CHECK(dev.value(V4L2_CID_EXPOSURE_AUTO) == V4L2_EXPOSURE_MANUAL);
  CHECK(dev.value(V4L2_CID_EXPOSURE_ABSOLUTE) == 100);
  CHECK(dev.value(V4L2_CID_GAIN) == 0);
  CHECK(dev.value(V4L2_CID_WHITE_BALANCE_TEMPERATURE) == 4600);
  CHECK(dev.value(V4L2_CID_FOCUS_ABSOLUTE) == 40);
  CHECK(dev.value(V4L2_CID_POWER_LINE_FREQUENCY) == V4L2_CID_POWER_LINE_FREQUENCY_50HZ);
  CHECK(dev.value(V4L2_CID_EXPOSURE_AUTO_PRIORITY) == 0);
}

TEST_CASE("values the driver clamps or rounds are reported as adjusted, with what it chose") {
  FakeControlDevice dev = FakeControlDevice::uvc_webcam();
  frames::CameraControls want;
  want.exposure = 5000;  // above 2047
  want.focus = 42;       // step 5
  auto r = by_name(frames::apply_controls(dev, want));
  CHECK(r["exposure"].outcome == ControlOutcome::kAdjusted);
  CHECK(r["exposure"].accepted == 2047);
  CHECK(r["exposure"].warning());
  CHECK(r["exposure"].describe().find("the driver chose 2047") != std::string::npos);
  CHECK(r["focus"].accepted == 40);
  CHECK(r["focus"].outcome == ControlOutcome::kAdjusted);
}

TEST_CASE("controls left unset are locked at the driver's current values") {
  FakeControlDevice dev = FakeControlDevice::uvc_webcam();
  auto results = frames::apply_controls(dev, {});
  auto r = by_name(results);
  CHECK(warnings(results) == 0);
  CHECK(r["exposure"].outcome == ControlOutcome::kKept);
  CHECK(r["exposure"].accepted == 250);
  CHECK(r["gain"].accepted == 64);
  CHECK(r["power line"].outcome == ControlOutcome::kKept);
  CHECK(dev.value(V4L2_CID_EXPOSURE_AUTO) == V4L2_EXPOSURE_MANUAL);
  CHECK(dev.value(V4L2_CID_AUTO_WHITE_BALANCE) == 0);
  CHECK(dev.value(V4L2_CID_FOCUS_AUTO) == 0);
  // Nothing but the automatic switches was written.
  for (const auto& [id, value] : dev.writes)
    CHECK((id == V4L2_CID_EXPOSURE_AUTO || id == V4L2_CID_AUTO_WHITE_BALANCE || id == V4L2_CID_FOCUS_AUTO ||
           id == V4L2_CID_EXPOSURE_AUTO_PRIORITY));
}

TEST_CASE("a control the driver lacks is a warning, not a failure, the rest is still set") {
  FakeControlDevice dev;
  dev.add_menu(V4L2_CID_EXPOSURE_AUTO, "Auto Exposure", {0, 1}, 0);
  dev.add_int(V4L2_CID_EXPOSURE, "Exposure", 1, 500, 1, 120);  // no absolute control: the plain one
  frames::CameraControls want;
  want.exposure = 80;
  want.gain = 10;
  want.power_line_hz = 60;
  auto results = frames::apply_controls(dev, want);
  auto r = by_name(results);
  CHECK(r["exposure"].outcome == ControlOutcome::kSet);
  CHECK(dev.value(V4L2_CID_EXPOSURE) == 80);
  CHECK(r["gain"].outcome == ControlOutcome::kMissing);
  CHECK(r["gain"].warning());
  CHECK(r["power line"].outcome == ControlOutcome::kMissing);
  CHECK(r["auto white balance"].outcome == ControlOutcome::kMissing);  // may still drift by itself
  CHECK(r["auto focus"].outcome == ControlOutcome::kAbsent);          // a fixed-focus lens: fine
  CHECK(r["focus"].outcome == ControlOutcome::kAbsent);
  CHECK_FALSE(r["focus"].warning());
  CHECK(warnings(results) == 3);
}

TEST_CASE("a driver that refuses to leave automatic mode: the manual value is refused too, each a warning") {
  SECTION("auto exposure read-only") {
    FakeControlDevice dev = FakeControlDevice::uvc_webcam();
    dev.make_read_only(V4L2_CID_EXPOSURE_AUTO);
    frames::CameraControls want;
    want.exposure = 100;
    auto r = by_name(frames::apply_controls(dev, want));
    CHECK(r["auto exposure"].outcome == ControlOutcome::kRefused);
    CHECK(r["exposure"].outcome == ControlOutcome::kRefused);
    CHECK(r["exposure"].detail.find("inactive") != std::string::npos);
    CHECK(dev.value(V4L2_CID_EXPOSURE_ABSOLUTE) == 250);
  }
  SECTION("no manual mode in the menu") {
    FakeControlDevice dev;
    dev.add_menu(V4L2_CID_EXPOSURE_AUTO, "Auto Exposure", {3}, 3);
    auto r = by_name(frames::apply_controls(dev, {}));
    CHECK(r["auto exposure"].outcome == ControlOutcome::kRefused);
    CHECK(r["auto exposure"].detail == "the driver offers no manual mode");
  }
  SECTION("a switch the driver accepts and ignores") {
    FakeControlDevice dev = FakeControlDevice::uvc_webcam();
    dev.ignore_writes(V4L2_CID_AUTO_WHITE_BALANCE);
    auto r = by_name(frames::apply_controls(dev, {}));
    CHECK(r["auto white balance"].outcome == ControlOutcome::kRefused);
    CHECK(r["auto white balance"].detail == "the driver kept 1");
  }
}

TEST_CASE("inspect_automatic says what is on, what can be locked and what is locked") {
  FakeControlDevice dev = FakeControlDevice::uvc_webcam();
  auto before = frames::inspect_automatic(dev);
  REQUIRE(before.size() == 4);
  for (const auto& s : before) {
    INFO(s.name << ": " << s.detail);
    if (s.name == "auto gain") {
      CHECK_FALSE(s.present);
    } else {
      CHECK(s.present);
      CHECK(s.lockable);
      CHECK_FALSE(s.locked);
    }
  }
  frames::apply_controls(dev, {});
  for (const auto& s : frames::inspect_automatic(dev))
    if (s.present) CHECK(s.locked);
  FakeControlDevice stuck;
  stuck.add_menu(V4L2_CID_EXPOSURE_AUTO, "Auto Exposure", {3}, 3);
  auto s = frames::inspect_automatic(stuck);
  CHECK(s[0].present);
  CHECK_FALSE(s[0].lockable);
  CHECK(s[0].matters);
}

TEST_CASE("describe_controls lists every control with its range and current value") {
  FakeControlDevice dev = FakeControlDevice::uvc_webcam();
  auto lines = frames::describe_controls(dev);
  REQUIRE(lines.size() == 9);
  CHECK(lines[3] == "Exposure Time, Absolute [0x009a0902] int 3..2047 default 250 now 250 (inactive)");
  CHECK(lines[1].find("menu 1 3") != std::string::npos);
}

TEST_CASE("control flags: declared once, parsed with their ranges") {
  Flags flags("t", "t");
  frames::add_control_flags(flags);
  const char* argv[] = {"t", "--exposure", "156", "--white-balance=4600", "--power-line-hz", "50"};
  REQUIRE(flags.parse(6, argv));
  auto c = frames::parse_controls([&](const std::string& n) { return flags.get(n); });
  CHECK(c.exposure == 156);
  CHECK(c.white_balance_k == 4600);
  CHECK(c.power_line_hz == 50);
  CHECK_FALSE(c.gain);
  CHECK_FALSE(c.all_values());
  auto parse_one = [](const std::string& name, const std::string& value) {
    return frames::parse_controls([&](const std::string& n) { return n == name ? value : std::string(); });
  };
  CHECK_THROWS_WITH(parse_one("exposure", "0"), Catch::Contains("--exposure must be an integer in 1..100000"));
  CHECK_THROWS_AS(parse_one("gain", "12abc"), FlagError);
  CHECK_THROWS_WITH(parse_one("power-line-hz", "55"), Catch::Contains("50, 60 or 0"));
  CHECK_THROWS_AS(parse_one("white-balance", "100"), FlagError);
  CHECK(parse_one("focus", "0").focus == 0);
}

TEST_CASE("the kernel device: a missing node and a node that is not a camera are clear errors") {
  CHECK(frames::v4l2_device_path("0") == "/dev/video0");
  CHECK(frames::v4l2_device_path("/dev/video2") == "/dev/video2");
  CHECK_THROWS_WITH(frames::V4l2ControlDevice("/dev/video-none"), Catch::Contains("cannot open /dev/video-none"));
  // /dev/null answers VIDIOC_QUERYCAP with ENOTTY: the real ioctl path, without a camera.
  CHECK_THROWS_WITH(frames::V4l2ControlDevice("/dev/null"), Catch::Contains("/dev/null is not a V4L2 device"));
}
