// bricklayer-camera as a real process on the real bus (NETNS), reading a folder of images and a video
// file this test writes (no camera exists on a CI machine); missing sources fail loudly.
#include <catch2/catch.hpp>

#include <algorithm>
#include <chrono>
#include <filesystem>
#include <functional>
#include <optional>
#include <string>
#include <vector>

#include <opencv2/imgcodecs.hpp>
#include <opencv2/imgproc.hpp>
#include <opencv2/videoio.hpp>

#include "bricklayer/common/channels.h"
#include "bricklayer/frames/frame_source.h"
#include "bricklayer/heartbeat_t.hpp"
#include "bricklayer/image_t.hpp"
#include "bricklayer/runtime/lcm_bus.h"
#include "harness/live_bus.h"
#include "harness/program.h"
#include "harness/recorder.h"
#include "harness/scratch.h"

using namespace bricklayer;
using namespace std::chrono_literals;
namespace fs = std::filesystem;

namespace {
constexpr const char* kCamera = "bricklayer-camera";
const char* const kUrl = harness::kLiveUrl;

// Frame k: a grey level that encodes k, so order and identity can be checked after JPEG.
cv::Mat numbered_frame(int k) { return cv::Mat(120, 160, CV_8UC3, cv::Scalar::all(20 + 40 * k)); }

// The test's side of the bus: every frame and heartbeat, in arrival order.
struct Peer {
  runtime::LcmBus bus{kUrl};
  harness::Recorder rec = harness::Recorder::live(bus, {channel(kImageChannel), channel(kHeartbeatChannel)});

  std::vector<image_t> frames() const { return rec.all<image_t>(channel(kImageChannel)); }
  // Pumps until at least `want` frames arrived or the timeout; the frames.
  std::vector<image_t> collect(size_t want, std::chrono::milliseconds timeout) {
    rec.wait_until([&] { return rec.count(channel(kImageChannel)) >= want; }, timeout);
    return frames();
  }
};

// The exit code of bricklayer-camera with args (-1 killed by a signal, -2 still running after 10 s).
int exit_code(std::vector<std::string> args) {
  const harness::Ran ran = harness::run_program(kCamera, std::move(args), 10s);
  if (ran.timed_out) return -2;
  return ran.status.signal != 0 ? -1 : ran.status.code;
}

// How the camera program ended once it exited by itself within timeout (nullopt: still running).
std::optional<int> exited(harness::Program& camera, std::chrono::milliseconds timeout) {
  const auto status = camera.wait_exit(timeout);
  if (!status) return std::nullopt;
  return status->signal != 0 ? -1 : status->code;
}
}  // namespace

TEST_CASE("a folder of images is published in name order with counting frame numbers") {
  harness::ScratchDir dir("camera-folder");
  for (int k = 0; k < 5; ++k) cv::imwrite((dir / ("f" + std::to_string(k) + ".png")).string(), numbered_frame(k));
  harness::write_file(dir / "notes.txt", "not an image");
  Peer peer;
  harness::Program camera(kCamera, {"--images", dir.str(), "--fps", "20", "--format", "png", "--lcm-url", kUrl});
  const std::vector<image_t> frames = peer.collect(5, 10s);
  CHECK(exited(camera, 5s) == 0);  // exits by itself at the end of the folder
  REQUIRE(frames.size() == 5);
  for (int k = 0; k < 5; ++k) {
    CHECK(frames[k].frame_number == k);
    CHECK(frames[k].format == image_t::FORMAT_PNG);
    cv::Mat bgr = cv::imdecode(frames[k].data, cv::IMREAD_COLOR);
    REQUIRE(bgr.cols == 160);
    CHECK(bgr.at<cv::Vec3b>(60, 80)[1] == 20 + 40 * k);
    if (k > 0) CHECK(frames[k].utime > frames[k - 1].utime);
  }
}

TEST_CASE("a video file is published frame by frame as JPEG") {
  harness::ScratchDir dir("camera-video");
  std::string path = (dir / "clip.avi").string();
  {
    cv::VideoWriter writer(path, cv::VideoWriter::fourcc('M', 'J', 'P', 'G'), 25, cv::Size(160, 120));
    REQUIRE(writer.isOpened());
    for (int k = 0; k < 6; ++k) writer.write(numbered_frame(k));
  }
  Peer peer;
  harness::Program camera(kCamera, {"--video", path, "--fps", "30", "--lcm-url", kUrl});
  const std::vector<image_t> frames = peer.collect(6, 10s);
  CHECK(exited(camera, 5s) == 0);
  REQUIRE(frames.size() == 6);
  for (int k = 0; k < 6; ++k) {
    CHECK(frames[k].frame_number == k);
    CHECK(frames[k].format == image_t::FORMAT_JPEG);
    cv::Mat bgr = cv::imdecode(frames[k].data, cv::IMREAD_COLOR);
    REQUIRE_FALSE(bgr.empty());
    CHECK(std::abs(bgr.at<cv::Vec3b>(60, 80)[1] - (20 + 40 * k)) <= 6);  // JPEG twice: close, not exact
  }
}

TEST_CASE("with --exit-when-missing a missing source is a clear error, and bad flags always are") {
  CHECK(exit_code({"--device", "/dev/video-none", "--exit-when-missing", "--lcm-url", kUrl}) == 1);
  CHECK(exit_code({"--video", "/nonexistent.avi", "--exit-when-missing", "--lcm-url", kUrl}) == 1);
  CHECK(exit_code({"--images", "/nonexistent-dir", "--exit-when-missing", "--lcm-url", kUrl}) == 1);
  CHECK(exit_code({"--images", "/tmp", "--video", "x.avi", "--lcm-url", kUrl}) == 2);
  CHECK(exit_code({"--images", "/tmp", "--format", "gif", "--lcm-url", kUrl}) == 2);
  CHECK(exit_code({"--images", "/tmp", "--exposure", "fast", "--lcm-url", kUrl}) == 2);
  CHECK(exit_code({"--images", "/tmp", "--power-line-hz", "55", "--lcm-url", kUrl}) == 2);
  // --list-controls asks the kernel: /dev/null is a device node but not a camera.
  CHECK(exit_code({"--device", "/dev/null", "--list-controls"}) == 1);
  harness::ScratchDir empty("camera-empty");
  CHECK(exit_code({"--images", empty.str(), "--exit-when-missing", "--lcm-url", kUrl}) == 1);
  // The profile check: a missing file source is an error, a camera not plugged in yet is not.
  CHECK(exit_code({"--images", "/nonexistent-dir", "--check-config"}) == 2);
  CHECK(exit_code({"--images", empty.str(), "--check-config"}) == 0);
  CHECK(exit_code({"--device", "/dev/video-none", "--check-config"}) == 0);
}

namespace {
// The camera's newest heartbeat from this process once it satisfies want, within timeout; nullopt
// when none did.
std::optional<heartbeat_t> camera_heartbeat(Peer& peer, pid_t pid, std::chrono::milliseconds timeout,
                                            const std::function<bool(const heartbeat_t&)>& want) {
  auto newest = [&]() -> std::optional<heartbeat_t> {
    const std::vector<heartbeat_t> beats = peer.rec.all<heartbeat_t>(channel(kHeartbeatChannel));
    for (auto it = beats.rbegin(); it != beats.rend(); ++it)
      if (it->module == "camera" && it->pid == pid) return *it;
    return std::nullopt;
  };
  std::optional<heartbeat_t> hb;
  if (!peer.rec.wait_until([&] { return (hb = newest()) && want(*hb); }, timeout)) return std::nullopt;
  return hb;
}
double value_of(const heartbeat_t& hb, const std::string& name) {
  return harness::heartbeat_value(hb, name).value_or(-1);
}
size_t lines_of(const std::string& text) { return static_cast<size_t>(std::count(text.begin(), text.end(), '\n')); }
}  // namespace

TEST_CASE("a source absent at start is waited for, said in the heartbeat, and published once it is there") {
  harness::ScratchDir base("camera-absent");
  const fs::path dir = base / "frames";  // not there yet
  Peer peer;
  harness::Program camera(kCamera, {"--images", dir.string(), "--fps", "20", "--loop", "--lcm-url", kUrl});
  auto hb = camera_heartbeat(peer, camera.pid(), 5s, [](const heartbeat_t& h) { return h.uptime_us > 2'000'000; });
  REQUIRE(hb);
  CHECK(hb->status.find("waiting for folder " + dir.string()) == 0);
  CHECK(value_of(*hb, "waiting") == 1);
  CHECK(peer.frames().empty());
  CHECK(camera.running());  // still running: no crash loop

  fs::create_directories(dir);
  for (int k = 0; k < 3; ++k) cv::imwrite((dir / ("f" + std::to_string(k) + ".png")).string(), numbered_frame(k));
  const std::vector<image_t> frames = peer.collect(5, 5s);
  REQUIRE(frames.size() >= 5);
  CHECK(frames[0].frame_number == 0);
  hb = camera_heartbeat(peer, camera.pid(), 3s, [](const heartbeat_t& h) { return h.status == "ok"; });
  REQUIRE(hb);
  CHECK(value_of(*hb, "waiting") == 0);
  CHECK(camera.stop().clean());
}

TEST_CASE("a folder emptied while running: the camera waits (no crash loop) and resumes, numbering on, when refilled") {
  harness::ScratchDir dir("camera-emptied");
  for (int k = 0; k < 3; ++k) cv::imwrite((dir / ("f" + std::to_string(k) + ".png")).string(), numbered_frame(k));
  Peer peer;
  harness::Program camera(kCamera, {"--images", dir.str(), "--fps", "20", "--loop", "--lcm-url", kUrl});
  REQUIRE(peer.collect(6, 10s).size() >= 6);

  for (int k = 0; k < 3; ++k) fs::remove(dir / ("f" + std::to_string(k) + ".png"));
  auto hb = camera_heartbeat(peer, camera.pid(), 5s, [](const heartbeat_t& h) { return value_of(h, "waiting") == 1; });
  REQUIRE(hb);
  CHECK(hb->status.find("waiting for folder " + dir.str()) == 0);
  // Waiting, not looping: for 2 s no frame, the same process.
  peer.rec.clear();
  peer.rec.pump_for(2s);
  CHECK(peer.frames().empty());
  CHECK(camera.running());

  cv::imwrite((dir / "g.png").string(), numbered_frame(4));
  const std::vector<image_t> frames = peer.collect(3, 5s);
  REQUIRE(frames.size() >= 3);
  CHECK(frames[0].frame_number >= 6);  // numbered on from before the outage
  cv::Mat bgr = cv::imdecode(frames[0].data, cv::IMREAD_COLOR);
  REQUIRE_FALSE(bgr.empty());
  CHECK(std::abs(bgr.at<cv::Vec3b>(60, 80)[1] - (20 + 40 * 4)) <= 6);
  hb = camera_heartbeat(peer, camera.pid(), 3s, [](const heartbeat_t& h) { return value_of(h, "reopens") >= 1; });
  REQUIRE(hb);
  CHECK(hb->status == "ok");
  CHECK(camera.stop().clean());
}

TEST_CASE("the folder source skips unreadable images and lists only image files") {
  harness::ScratchDir dir("camera-list");
  cv::imwrite((dir / "b.png").string(), numbered_frame(1));
  cv::imwrite((dir / "a.jpg").string(), numbered_frame(0));
  harness::write_file(dir / "c.png", "corrupt");
  harness::write_file(dir / "readme.md", "x");
  auto files = frames::list_image_files(dir.str());
  REQUIRE(files.size() == 3);
  CHECK(files[0].filename() == "a.jpg");
  auto source = frames::open_folder(dir.str(), 10, false);
  cv::Mat frame;
  int read = 0;
  while (source->next(frame)) ++read;
  CHECK(read == 2);
  CHECK(source->unreadable() == 1);  // bricklayer-camera and bricklayer-vision count it as an error
}

TEST_CASE("waiting for a camera that is not there prints its reason once, not a line a second") {
  Peer peer;
  // An index, so OpenCV's V4L2 backend is asked (and would warn) at every attempt.
  harness::Program camera(kCamera, {"--device", "57", "--lcm-url", kUrl});
  // Its heartbeat says when 4.5 s of waiting have passed, about four attempts.
  REQUIRE(camera_heartbeat(peer, camera.pid(), 10s, [](const heartbeat_t& h) { return h.uptime_us > 4'500'000; }));
  REQUIRE(camera.running());  // waiting, not exited
  camera.stop();
  const std::string text = camera.stdout_text() + camera.stderr_text();
  INFO(text);
  CHECK(lines_of(text) <= 4);  // OpenCV's first warning, ours, the stop line
  CHECK(text.find("waiting for camera 57") != std::string::npos);
}

TEST_CASE("a looping folder with a corrupt image counts it at every pass and says so once") {
  harness::ScratchDir dir("camera-corrupt");
  cv::imwrite((dir / "a.png").string(), numbered_frame(1));
  harness::write_file(dir / "b.png", "corrupt");
  Peer peer;
  harness::Program camera(kCamera, {"--images", dir.str(), "--loop", "--fps", "30", "--lcm-url", kUrl});
  const auto hb = camera_heartbeat(peer, camera.pid(), 6s, [](const heartbeat_t& h) { return h.uptime_us > 2'500'000; });
  REQUIRE(hb);
  CHECK(hb->errors > 20);  // about 15 passes a second, each counting the corrupt image
  camera.stop();
  const std::string text = camera.stdout_text() + camera.stderr_text();
  INFO(text);
  size_t said = 0;
  for (size_t at = text.find("skipping unreadable image"); at != std::string::npos; at = text.find("skipping unreadable image", at + 1))
    ++said;
  CHECK(said == 1);
}
