// bricklayer-simcam as a real process on the real bus (NETNS): frames decode, frame numbers count up,
// the true stack rides along, projected light shows in the frames, bad configuration fails loudly.
#include <catch2/catch.hpp>

#include <signal.h>
#include <sys/wait.h>
#include <unistd.h>

#include <chrono>
#include <cstdlib>
#include <string>
#include <vector>

#include <opencv2/imgcodecs.hpp>

#include "../common/spawn_util.h"
#include "bricklayer/common/channels.h"
#include "bricklayer/common/module.h"
#include "bricklayer/image_t.hpp"
#include "bricklayer/projector_state_t.hpp"
#include "bricklayer/stack_t.hpp"

using namespace bricklayer;
using test::spawn;
using test::stop;
using test::wait_exit;

namespace {
const std::string kBin = test::program("bricklayer-simcam");
const std::string kScenarios = std::string(BRICKLAYER_SOURCE_DIR) + "/launch/scenarios/";
constexpr const char* kUrl = "udpm://239.255.76.67:7667?ttl=0";



void pump_for(Module& m, double seconds) {
  auto end = std::chrono::steady_clock::now() + std::chrono::duration<double>(seconds);
  while (std::chrono::steady_clock::now() < end) m.lcm().handleTimeout(10);
}
}  // namespace

TEST_CASE("simcam publishes decodable frames with counting frame numbers and the true stack") {
  Module m("test", kUrl);
  std::vector<image_t> frames;
  std::vector<bricklayer::stack_t> truths;
  m.subscribe<image_t>(channel(kImageChannel), [&](const image_t& im) { frames.push_back(im); });
  m.subscribe<bricklayer::stack_t>(channel(kTruthChannel), [&](const bricklayer::stack_t& s) { truths.push_back(s); });
  // 30 fps for 20 frames from t=0 of wall-60: 0.67 s of scenario time.
  pid_t pid = spawn({kBin, "--scenario", kScenarios + "wall-60.json", "--fps", "30", "--frames", "20",
                     "--lcm-url", kUrl});
  auto end = std::chrono::steady_clock::now() + std::chrono::seconds(10);
  while (truths.size() < 20 && std::chrono::steady_clock::now() < end) m.lcm().handleTimeout(20);
  CHECK(wait_exit(pid, 5) == 0);
  REQUIRE(frames.size() == 20);
  REQUIRE(truths.size() == 20);
  for (size_t i = 0; i < frames.size(); ++i) {
    CHECK(frames[i].frame_number == static_cast<int64_t>(i));
    CHECK(truths[i].frame_number == frames[i].frame_number);
    CHECK(truths[i].utime == frames[i].utime);
    CHECK(frames[i].format == image_t::FORMAT_JPEG);
    cv::Mat bgr = cv::imdecode(frames[i].data, cv::IMREAD_COLOR);
    REQUIRE_FALSE(bgr.empty());
    CHECK(bgr.cols == 640);
    CHECK(bgr.rows == 480);
  }
  // wall-60 starts empty and places its first row at t = 1 s: not yet in 20 frames at 30 fps.
  CHECK(truths.front().num_blocks == 0);
}

TEST_CASE("projected light from BL_PROJECTOR appears in simcam's frames (closed loop)") {
  Module m("test", kUrl);
  std::vector<image_t> frames;
  m.subscribe<image_t>(channel(kImageChannel), [&](const image_t& im) { frames.push_back(im); });
  pid_t pid = spawn({kBin, "--scenario", kScenarios + "wall-60.json", "--fps", "20", "--format", "png",
                     "--nuisance", "clean", "--lcm-url", kUrl});
  pump_for(m, 1.0);
  REQUIRE_FALSE(frames.empty());
  cv::Mat dark = cv::imdecode(frames.back().data, cv::IMREAD_COLOR);

  // The projector lights the whole board pure red.
  projector_state_t p{};
  p.mode = projector_state_t::MODE_PATTERN;
  cv::Mat red(192, 256, CV_8UC3, cv::Scalar(0, 0, 255));
  cv::imencode(".png", red, p.image.data);
  p.image.size = static_cast<int32_t>(p.image.data.size());
  p.image.width = 256;
  p.image.height = 192;
  p.image.format = image_t::FORMAT_PNG;
  m.publish(channel(kProjectorChannel), p);
  pump_for(m, 1.0);
  kill(pid, SIGTERM);
  CHECK(wait_exit(pid, 5) == 0);
  cv::Mat lit = cv::imdecode(frames.back().data, cv::IMREAD_COLOR);
  cv::Scalar before = cv::mean(dark), after = cv::mean(lit);
  CHECK(after[2] > before[2] + 40);  // red rose a lot
  CHECK(after[1] > before[1] + 5);   // and some of it leaked into green, as real optics do
}

TEST_CASE("simcam refuses bad configuration with a clear error") {
  CHECK(wait_exit(spawn({kBin, "--lcm-url", kUrl}), 5) == 2);  // no scenario
  CHECK(wait_exit(spawn({kBin, "--scenario", "/nonexistent.json", "--lcm-url", kUrl}), 5) == 1);
  CHECK(wait_exit(spawn({kBin, "--scenario", kScenarios + "wall-60.json", "--fps", "0", "--lcm-url", kUrl}), 5) == 2);
  CHECK(wait_exit(spawn({kBin, "--scenario", kScenarios + "wall-60.json", "--lcm-url",
                         "udpm://239.255.76.67:7667?ttl=7"}), 5) == 1);
}
