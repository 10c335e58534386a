// bricklayer-camera as a real process on the real bus (NETNS), reading a folder of images and a video
// file this test writes (no camera exists on a CI machine); missing sources fail loudly.
#include <catch2/catch.hpp>

#include <signal.h>
#include <sys/wait.h>
#include <unistd.h>

#include <chrono>
#include <functional>
#include <iterator>
#include <thread>
#include <filesystem>
#include <fstream>
#include <string>
#include <vector>

#include <opencv2/imgcodecs.hpp>
#include <opencv2/imgproc.hpp>
#include <opencv2/videoio.hpp>

#include "bricklayer/frames/frame_source.h"
#include "../common/spawn_util.h"
#include "bricklayer/common/channels.h"
#include "bricklayer/common/module.h"
#include "bricklayer/heartbeat_t.hpp"
#include "bricklayer/image_t.hpp"
#include "bricklayer/launcher/process.h"

using namespace bricklayer;
using test::spawn;
using test::stop;
using test::wait_exit;
namespace fs = std::filesystem;

namespace {
const std::string kBin = test::program("bricklayer-camera");
constexpr const char* kUrl = "udpm://239.255.76.67:7667?ttl=0";



// Frame k: a grey level that encodes k, so order and identity can be checked after JPEG.
cv::Mat numbered_frame(int k) { return cv::Mat(120, 160, CV_8UC3, cv::Scalar::all(20 + 40 * k)); }

fs::path temp_dir(const std::string& name) {
  fs::path dir = fs::temp_directory_path() / ("bricklayer-camera-test-" + name + "-" + std::to_string(getpid()));
  fs::remove_all(dir);
  fs::create_directories(dir);
  return dir;
}

std::vector<image_t> collect(Module& m, std::vector<image_t>& frames, size_t want, double seconds) {
  auto end = std::chrono::steady_clock::now() + std::chrono::duration<double>(seconds);
  while (frames.size() < want && std::chrono::steady_clock::now() < end) m.lcm().handleTimeout(20);
  return frames;
}
}  // namespace

TEST_CASE("a folder of images is published in name order with counting frame numbers") {
  fs::path dir = temp_dir("folder");
  for (int k = 0; k < 5; ++k) cv::imwrite((dir / ("f" + std::to_string(k) + ".png")).string(), numbered_frame(k));
  std::ofstream(dir / "notes.txt") << "not an image";
  Module m("test", kUrl);
  std::vector<image_t> frames;
  m.subscribe<image_t>(channel(kImageChannel), [&](const image_t& im) { frames.push_back(im); });
  pid_t pid = spawn({kBin, "--images", dir.string(), "--fps", "20", "--format", "png", "--lcm-url", kUrl});
  collect(m, frames, 5, 10);
  CHECK(wait_exit(pid, 5) == 0);  // exits by itself at the end of the folder
  REQUIRE(frames.size() == 5);
  for (int k = 0; k < 5; ++k) {
    CHECK(frames[k].frame_number == k);
    CHECK(frames[k].format == image_t::FORMAT_PNG);
    cv::Mat bgr = cv::imdecode(frames[k].data, cv::IMREAD_COLOR);
    REQUIRE(bgr.cols == 160);
    CHECK(bgr.at<cv::Vec3b>(60, 80)[1] == 20 + 40 * k);
    if (k > 0) CHECK(frames[k].utime > frames[k - 1].utime);
  }
  fs::remove_all(dir);
}

TEST_CASE("a video file is published frame by frame as JPEG") {
  fs::path dir = temp_dir("video");
  std::string path = (dir / "clip.avi").string();
  {
    cv::VideoWriter writer(path, cv::VideoWriter::fourcc('M', 'J', 'P', 'G'), 25, cv::Size(160, 120));
    REQUIRE(writer.isOpened());
    for (int k = 0; k < 6; ++k) writer.write(numbered_frame(k));
  }
  Module m("test", kUrl);
  std::vector<image_t> frames;
  m.subscribe<image_t>(channel(kImageChannel), [&](const image_t& im) { frames.push_back(im); });
  pid_t pid = spawn({kBin, "--video", path, "--fps", "30", "--lcm-url", kUrl});
  collect(m, frames, 6, 10);
  CHECK(wait_exit(pid, 5) == 0);
  REQUIRE(frames.size() == 6);
  for (int k = 0; k < 6; ++k) {
    CHECK(frames[k].frame_number == k);
    CHECK(frames[k].format == image_t::FORMAT_JPEG);
    cv::Mat bgr = cv::imdecode(frames[k].data, cv::IMREAD_COLOR);
    REQUIRE_FALSE(bgr.empty());
    CHECK(std::abs(bgr.at<cv::Vec3b>(60, 80)[1] - (20 + 40 * k)) <= 6);  // JPEG twice: close, not exact
  }
  fs::remove_all(dir);
}

TEST_CASE("with --exit-when-missing a missing source is a clear error, and bad flags always are") {
  CHECK(wait_exit(spawn({kBin, "--device", "/dev/video-none", "--exit-when-missing", "--lcm-url", kUrl}), 10) == 1);
  CHECK(wait_exit(spawn({kBin, "--video", "/nonexistent.avi", "--exit-when-missing", "--lcm-url", kUrl}), 10) == 1);
  CHECK(wait_exit(spawn({kBin, "--images", "/nonexistent-dir", "--exit-when-missing", "--lcm-url", kUrl}), 10) == 1);
  CHECK(wait_exit(spawn({kBin, "--images", "/tmp", "--video", "x.avi", "--lcm-url", kUrl}), 10) == 2);
  CHECK(wait_exit(spawn({kBin, "--images", "/tmp", "--format", "gif", "--lcm-url", kUrl}), 10) == 2);
  CHECK(wait_exit(spawn({kBin, "--images", "/tmp", "--exposure", "fast", "--lcm-url", kUrl}), 10) == 2);
  CHECK(wait_exit(spawn({kBin, "--images", "/tmp", "--power-line-hz", "55", "--lcm-url", kUrl}), 10) == 2);
  // --list-controls asks the kernel: /dev/null is a device node but not a camera.
  CHECK(wait_exit(spawn({kBin, "--device", "/dev/null", "--list-controls"}), 10) == 1);
  fs::path empty = temp_dir("empty");
  CHECK(wait_exit(spawn({kBin, "--images", empty.string(), "--exit-when-missing", "--lcm-url", kUrl}), 10) == 1);
  // The profile check: a missing file source is an error, a camera not plugged in yet is not.
  CHECK(wait_exit(spawn({kBin, "--images", "/nonexistent-dir", "--check-config"}), 10) == 2);
  CHECK(wait_exit(spawn({kBin, "--images", empty.string(), "--check-config"}), 10) == 0);
  CHECK(wait_exit(spawn({kBin, "--device", "/dev/video-none", "--check-config"}), 10) == 0);
  fs::remove_all(empty);
}

namespace {
// The camera's newest heartbeat from pid, within seconds; false if none came.
bool camera_heartbeat(Module& m, std::vector<heartbeat_t>& beats, pid_t pid, heartbeat_t& out, double seconds,
                      const std::function<bool(const heartbeat_t&)>& want = nullptr) {
  auto end = std::chrono::steady_clock::now() + std::chrono::duration<double>(seconds);
  while (std::chrono::steady_clock::now() < end) {
    m.lcm().handleTimeout(20);
    for (auto it = beats.rbegin(); it != beats.rend(); ++it) {
      if (it->module != "camera" || it->pid != pid) continue;
      if (!want || want(*it)) {
        out = *it;
        return true;
      }
      break;
    }
  }
  return false;
}
double value_of(const heartbeat_t& hb, const std::string& name) {
  for (int i = 0; i < hb.num_values; ++i)
    if (hb.value_names[i] == name) return hb.values[i];
  return -1;
}
}  // namespace

TEST_CASE("a source absent at start is waited for, said in the heartbeat, and published once it is there") {
  const fs::path base = temp_dir("absent");
  const fs::path dir = base / "frames";  // not there yet
  Module m("test", kUrl);
  std::vector<image_t> frames;
  std::vector<heartbeat_t> beats;
  m.subscribe<image_t>(channel(kImageChannel), [&](const image_t& im) { frames.push_back(im); });
  m.subscribe<heartbeat_t>(channel(kHeartbeatChannel), [&](const heartbeat_t& hb) { beats.push_back(hb); });
  pid_t pid = spawn({kBin, "--images", dir.string(), "--fps", "20", "--loop", "--lcm-url", kUrl});
  heartbeat_t hb{};
  REQUIRE(camera_heartbeat(m, beats, pid, hb, 5, [](const heartbeat_t& h) { return h.uptime_us > 2'000'000; }));
  CHECK(hb.status.find("waiting for folder " + dir.string()) == 0);
  CHECK(value_of(hb, "waiting") == 1);
  CHECK(frames.empty());
  CHECK(::waitpid(pid, nullptr, WNOHANG) == 0);  // still running: no crash loop

  fs::create_directories(dir);
  for (int k = 0; k < 3; ++k) cv::imwrite((dir / ("f" + std::to_string(k) + ".png")).string(), numbered_frame(k));
  collect(m, frames, 5, 5);
  REQUIRE(frames.size() >= 5);
  CHECK(frames[0].frame_number == 0);
  REQUIRE(camera_heartbeat(m, beats, pid, hb, 3, [](const heartbeat_t& h) { return h.status == "ok"; }));
  CHECK(value_of(hb, "waiting") == 0);
  CHECK(stop(pid) == 0);
  fs::remove_all(base);
}

TEST_CASE("a folder emptied while running: the camera waits (no crash loop) and resumes, numbering on, when refilled") {
  const fs::path dir = temp_dir("emptied");
  for (int k = 0; k < 3; ++k) cv::imwrite((dir / ("f" + std::to_string(k) + ".png")).string(), numbered_frame(k));
  Module m("test", kUrl);
  std::vector<image_t> frames;
  std::vector<heartbeat_t> beats;
  m.subscribe<image_t>(channel(kImageChannel), [&](const image_t& im) { frames.push_back(im); });
  m.subscribe<heartbeat_t>(channel(kHeartbeatChannel), [&](const heartbeat_t& hb) { beats.push_back(hb); });
  pid_t pid = spawn({kBin, "--images", dir.string(), "--fps", "20", "--loop", "--lcm-url", kUrl});
  collect(m, frames, 6, 10);
  REQUIRE(frames.size() >= 6);

  for (int k = 0; k < 3; ++k) fs::remove(dir / ("f" + std::to_string(k) + ".png"));
  heartbeat_t hb{};
  REQUIRE(camera_heartbeat(m, beats, pid, hb, 5, [](const heartbeat_t& h) { return value_of(h, "waiting") == 1; }));
  CHECK(hb.status.find("waiting for folder " + dir.string()) == 0);
  // Waiting, not looping: for 2 s no frame, the same process.
  frames.clear();
  collect(m, frames, 1000, 2);
  CHECK(frames.empty());
  CHECK(::waitpid(pid, nullptr, WNOHANG) == 0);

  cv::imwrite((dir / "g.png").string(), numbered_frame(4));
  collect(m, frames, 3, 5);
  REQUIRE(frames.size() >= 3);
  CHECK(frames[0].frame_number >= 6);  // numbered on from before the outage
  cv::Mat bgr = cv::imdecode(frames[0].data, cv::IMREAD_COLOR);
  REQUIRE_FALSE(bgr.empty());
  CHECK(std::abs(bgr.at<cv::Vec3b>(60, 80)[1] - (20 + 40 * 4)) <= 6);
  REQUIRE(camera_heartbeat(m, beats, pid, hb, 3, [](const heartbeat_t& h) { return value_of(h, "reopens") >= 1; }));
  CHECK(hb.status == "ok");
  CHECK(stop(pid) == 0);
  fs::remove_all(dir);
}

TEST_CASE("the folder source skips unreadable images and lists only image files") {
  fs::path dir = temp_dir("list");
  cv::imwrite((dir / "b.png").string(), numbered_frame(1));
  cv::imwrite((dir / "a.jpg").string(), numbered_frame(0));
  std::ofstream(dir / "c.png") << "corrupt";
  std::ofstream(dir / "readme.md") << "x";
  auto files = frames::list_image_files(dir.string());
  REQUIRE(files.size() == 3);
  CHECK(files[0].filename() == "a.jpg");
  auto source = frames::open_folder(dir.string(), 10, false);
  cv::Mat frame;
  int read = 0;
  while (source->next(frame)) ++read;
  CHECK(read == 2);
  CHECK(source->unreadable() == 1);  // bricklayer-camera and bricklayer-vision count it as an error
  fs::remove_all(dir);
}

TEST_CASE("waiting for a camera that is not there prints its reason once, not a line a second") {
  const fs::path dir = temp_dir("quiet");
  launcher::SpawnOptions o;
  o.stdout_path = (dir / "out").string();
  o.merge_stderr = true;
  // An index, so OpenCV's V4L2 backend is asked (and would warn) at every attempt.
  auto camera = launcher::Process::spawn({kBin, "--device", "57", "--lcm-url", kUrl}, o);
  std::this_thread::sleep_for(std::chrono::milliseconds(4500));
  REQUIRE(camera.running());  // waiting, not exited
  camera.stop(std::chrono::seconds(5));
  std::ifstream in(dir / "out");
  std::string text((std::istreambuf_iterator<char>(in)), std::istreambuf_iterator<char>());
  INFO(text);
  size_t lines = static_cast<size_t>(std::count(text.begin(), text.end(), '\n'));
  CHECK(lines <= 4);  // OpenCV's first warning, ours, the stop line
  CHECK(text.find("waiting for camera 57") != std::string::npos);
  fs::remove_all(dir);
}

TEST_CASE("a looping folder with a corrupt image counts it at every pass and says so once") {
  const fs::path dir = temp_dir("corrupt");
  cv::imwrite((dir / "a.png").string(), numbered_frame(1));
  std::ofstream(dir / "b.png") << "corrupt";
  launcher::SpawnOptions o;
  o.stdout_path = (dir / "out").string();
  o.merge_stderr = true;
  const fs::path images = dir;
  auto camera = launcher::Process::spawn({kBin, "--images", images.string(), "--loop", "--fps", "30", "--lcm-url", kUrl}, o);
  Module m("test", kUrl);
  std::vector<heartbeat_t> beats;
  m.subscribe<heartbeat_t>(channel(kHeartbeatChannel), [&](const heartbeat_t& hb) { beats.push_back(hb); });
  heartbeat_t hb{};
  REQUIRE(camera_heartbeat(m, beats, camera.pid(), hb, 6, [](const heartbeat_t& h) { return h.uptime_us > 2'500'000; }));
  CHECK(hb.errors > 20);  // about 15 passes a second, each counting the corrupt image
  camera.stop(std::chrono::seconds(5));
  std::ifstream in(dir / "out");
  std::string text((std::istreambuf_iterator<char>(in)), std::istreambuf_iterator<char>());
  INFO(text);
  size_t said = 0;
  for (size_t at = text.find("skipping unreadable image"); at != std::string::npos; at = text.find("skipping unreadable image", at + 1))
    ++said;
  CHECK(said == 1);
  fs::remove_all(dir);
}
