// The camera checks of the real bricklayer-doctor on the sources a CI machine has: a video file and a
// folder of images this test writes (sizes and rates known), a missing device node; the automatic-mode
// lines on a device that behaves like a V4L2 driver (no camera exists here).
#include <catch2/catch.hpp>

#include <linux/videodev2.h>

#include <filesystem>

#include <opencv2/imgcodecs.hpp>
#include <opencv2/videoio.hpp>

#include "../frames/fake_control_device.h"
#include "bricklayer/board/calibration_file.h"
#include "bricklayer/frames/camera_controls.h"
#include "bricklayer/doctor/camera_check.h"
#include "doctor_test_util.h"
#include "harness/program.h"

using namespace bricklayer;
using test::check_line;
using test::run_doctor;
using test::severity;
namespace fs = std::filesystem;

namespace {

std::string write_video(const fs::path& path, double fps, cv::Size size, int frames) {
  cv::VideoWriter writer(path.string(), cv::VideoWriter::fourcc('M', 'J', 'P', 'G'), fps, size);
  REQUIRE(writer.isOpened());
  for (int k = 0; k < frames; ++k) writer.write(cv::Mat(size, CV_8UC3, cv::Scalar(40, 80 + k, 120)));
  return path.string();
}

std::string camera_profile(const fs::path& dir, const std::string& source_flag, const std::string& source,
                           const std::string& calibration = "") {
  std::string modules = R"({"name":"camera","command":["bricklayer-camera",")" + source_flag + R"(",")" + source + R"("]})";
  if (!calibration.empty())
    modules = R"({"name":"calibrate","command":["bricklayer-calibrate","--serve","--output",")" + calibration + R"("]},)" + modules;
  return test::write_file(dir / "camera.json", R"({"modules":[)" + modules + "]}");
}

}  // namespace

TEST_CASE("a 640x480 video at 30 frames/s: camera and rate ok, no controls to lock, the first frame saved") {
  auto dir = test::temp_dir("video30");
  const std::string video = write_video(dir / "clip.avi", 30, {640, 480}, 10);
  const std::string frame = (dir / "first.png").string();
  auto r = run_doctor({camera_profile(dir, "--video", video), "--checks", "camera", "--save-frame", frame});
  INFO(r.out);
  CHECK(check_line(r.out, "camera").find("ok       camera               video " + video + ", 640x480") == 0);
  CHECK(check_line(r.out, "camera rate").find("paced at 30.0 frames/s") != std::string::npos);
  CHECK(severity(check_line(r.out, "camera rate")) == "ok");
  CHECK(severity(check_line(r.out, "camera controls")) == "ok");
  CHECK(r.code == 0);
  cv::Mat saved = cv::imread(frame);
  REQUIRE(saved.cols == 640);
  CHECK(std::abs(saved.at<cv::Vec3b>(240, 320)[2] - 120) <= 4);
  fs::remove_all(dir);
}

TEST_CASE("a 15 frames/s video warns about the rate") {
  auto dir = test::temp_dir("video15");
  auto r = run_doctor({camera_profile(dir, "--video", write_video(dir / "slow.avi", 15, {640, 480}, 5)), "--checks", "camera"});
  INFO(r.out);
  const std::string line = check_line(r.out, "camera rate");
  CHECK(severity(line) == "warning");
  CHECK(line.find("paced at 15.0 frames/s, below the wanted 30.0 frames/s") != std::string::npos);
  CHECK(r.code == 0);
  // The wanted rate is a flag.
  r = run_doctor({dir / "camera.json", "--checks", "camera", "--wanted-fps", "15"});
  CHECK(severity(check_line(r.out, "camera rate")) == "ok");
  fs::remove_all(dir);
}

TEST_CASE("a folder of 320x240 images against a calibration made for 640x480 fails") {
  auto dir = test::temp_dir("folder");
  fs::create_directories(dir / "frames");
  for (int k = 0; k < 3; ++k) cv::imwrite((dir / "frames" / ("f" + std::to_string(k) + ".png")).string(), cv::Mat(240, 320, CV_8UC3, cv::Scalar::all(90)));
  auto cal = board::default_calibration();  // camera 640x480
  board::save_calibration((dir / "calibration.json").string(), cal);
  auto r = run_doctor({camera_profile(dir, "--images", (dir / "frames").string(), (dir / "calibration.json").string()), "--checks", "camera"});
  INFO(r.out);
  const std::string line = check_line(r.out, "camera");
  CHECK(severity(line) == "FAILED");
  CHECK(line.find("gives 320x240, " + (dir / "calibration.json").string() + " wants 640x480") != std::string::npos);
  CHECK(r.code == 1);
  // Without the calibration nothing asks for a size: ok.
  r = run_doctor({camera_profile(dir, "--images", (dir / "frames").string()), "--checks", "camera"});
  INFO(r.out);
  CHECK(severity(check_line(r.out, "camera")) == "ok");
  CHECK(r.code == 0);
  fs::remove_all(dir);
}

TEST_CASE("a missing source fails: a device node that does not exist, a video that does not exist") {
  auto dir = test::temp_dir("missing");
  auto r = run_doctor({camera_profile(dir, "--device", "/dev/video-none"), "--checks", "camera"});
  INFO(r.out);
  CHECK(check_line(r.out, "camera").find("FAILED   camera               cannot open /dev/video-none") == 0);
  CHECK(r.code == 1);
  r = run_doctor({camera_profile(dir, "--video", (dir / "none.avi").string()), "--checks", "camera"});
  CHECK(severity(check_line(r.out, "camera")) == "FAILED");
  // /dev/null is a device node, but no camera.
  r = run_doctor({camera_profile(dir, "--device", "/dev/null"), "--checks", "camera"});
  CHECK(check_line(r.out, "camera").find("/dev/null is not a V4L2 device") != std::string::npos);
  fs::remove_all(dir);
}

TEST_CASE("automatic modes: lockable ones are ok before bricklayer-camera runs, locked ones ok, stuck ones warn") {
  auto by_name = [](const std::vector<doctor::CheckResult>& rs, const std::string& name) {
    for (const auto& r : rs)
      if (r.name == name) return r;
    FAIL("no line " << name);
    return doctor::CheckResult{};
  };
  test::FakeControlDevice dev = test::FakeControlDevice::uvc_webcam();
  auto idle = doctor::check_automatic_controls(dev, false);
  CHECK(by_name(idle, "auto exposure").severity == doctor::Severity::kOk);
  CHECK(by_name(idle, "auto exposure").detail.find("lockable") != std::string::npos);
  CHECK(by_name(idle, "auto gain").severity == doctor::Severity::kOk);  // none: follows auto exposure
  // In use by something that left them on: warnings.
  auto busy = doctor::check_automatic_controls(dev, true);
  CHECK(by_name(busy, "auto exposure").severity == doctor::Severity::kWarning);
  CHECK(by_name(busy, "auto white balance").severity == doctor::Severity::kWarning);
  // Locked by bricklayer-camera's controls: ok while in use.
  frames::apply_controls(dev, {});
  for (const auto& r : doctor::check_automatic_controls(dev, true)) {
    INFO(r.name << ": " << r.detail);
    CHECK(r.severity == doctor::Severity::kOk);
  }
  // A camera whose auto exposure cannot be switched off, and one without a white balance switch.
  test::FakeControlDevice stuck;
  stuck.add_menu(V4L2_CID_EXPOSURE_AUTO, "Auto Exposure", {3}, 3);
  auto s = doctor::check_automatic_controls(stuck, false);
  CHECK(by_name(s, "auto exposure").severity == doctor::Severity::kWarning);
  CHECK(by_name(s, "auto white balance").severity == doctor::Severity::kWarning);
  CHECK(by_name(s, "auto focus").severity == doctor::Severity::kOk);
}

TEST_CASE("a device held open by another process is found through /proc (a camera in use)") {
  auto dir = test::temp_dir("users");
  const std::string node = test::write_file(dir / "video9", "");
  CHECK(doctor::processes_using(node).empty());
  harness::Program holder("/bin/sh", {"-c", "exec 3<" + node + " && exec sleep 30"});
  // The shell opens the device and then becomes sleep: wait for the exec, or the name read is "sh".
  const std::string expected = "sleep (pid " + std::to_string(holder.pid()) + ")";
  std::vector<std::string> users;
  for (int i = 0; i < 250 && (users.size() != 1 || users[0] != expected); ++i) {
    usleep(20000);
    users = doctor::processes_using(node);
  }
  REQUIRE(users.size() == 1);
  CHECK(users[0] == expected);
  holder.stop();
  CHECK(doctor::processes_using(node).empty());
  fs::remove_all(dir);
}
