// SimcamNode on the in-process rig: the scenario's frames and true stacks, paced by the bus clock, and
// the projector's light drawn into the frames (the closed loop), checked in milliseconds.
#include <catch2/catch.hpp>

#include <opencv2/imgcodecs.hpp>

#include "bricklayer/common/channels.h"
#include "bricklayer/image_t.hpp"
#include "bricklayer/simcam/simcam_node.h"
#include "bricklayer/stack_t.hpp"
#include "harness/rig.h"

using namespace bricklayer;
using namespace std::chrono_literals;

namespace {
const std::string kScenarios = std::string(BRICKLAYER_SOURCE_DIR) + "/launch/scenarios/";
const std::string kImages = channel(kImageChannel);
const std::string kTruth = channel(kTruthChannel);
}  // namespace

TEST_CASE("the simcam node publishes decodable frames at its rate with counting numbers and the true stack, then stops") {
  harness::Rig rig;
  simcam::SimcamConfig config;
  config.scenario = kScenarios + "wall-60.json";
  config.frames = 20;
  auto& node = rig.add<simcam::SimcamNode>(config);
  auto& rec = rig.record({kImages, kTruth});
  rig.run_for(490ms);  // frames at 0, 1/30, ..., 0.4667 s: 15 of them
  CHECK(rec.count(kImages) == 15);
  rig.run_for(1s);
  const auto frames = rec.all<image_t>(kImages);
  const auto truths = rec.all<stack_t>(kTruth);
  REQUIRE(frames.size() == 20);
  REQUIRE(truths.size() == 20);
  for (size_t i = 0; i < frames.size(); ++i) {
    CHECK(frames[i].frame_number == static_cast<int64_t>(i));
    CHECK(truths[i].frame_number == frames[i].frame_number);
    CHECK(truths[i].utime == frames[i].utime);
    CHECK(frames[i].format == image_t::FORMAT_JPEG);
    const cv::Mat bgr = cv::imdecode(frames[i].data, cv::IMREAD_COLOR);
    REQUIRE_FALSE(bgr.empty());
    CHECK(bgr.cols == 640);
    CHECK(bgr.rows == 480);
  }
  // The capture time is the bus clock: 1/30 s apart.
  CHECK(frames[10].utime - frames[0].utime == Approx(10 * 1e6 / 30).margin(1000));
  // wall-60 starts empty and places its first row at t = 1 s: not yet in 20 frames at 30 fps.
  CHECK(truths.front().num_blocks == 0);
  CHECK(node.status() == "frame limit reached");  // and stopped: run() returns
  CHECK(node.frames_published() == 20);
}

TEST_CASE("the same scenario gives the same frames byte for byte") {
  auto frames_of = [] {
    harness::Rig rig;
    simcam::SimcamConfig config;
    config.scenario = kScenarios + "wall-60.json";
    config.frames = 5;
    config.format = "png";
    rig.add<simcam::SimcamNode>(config);
    auto& rec = rig.record({kImages});
    rig.run_for(300ms);
    std::vector<std::vector<uint8_t>> out;
    for (const auto& f : rec.all<image_t>(kImages)) out.push_back(f.data);
    return out;
  };
  const auto a = frames_of();
  REQUIRE(a.size() == 5);
  CHECK(a == frames_of());
}

TEST_CASE("projected light from BL_PROJECTOR appears in the simcam node's frames (closed loop)") {
  harness::Rig rig;
  simcam::SimcamConfig config;
  config.scenario = kScenarios + "wall-60.json";
  config.fps = 20;
  config.format = "png";
  config.nuisance = "clean";
  rig.add<simcam::SimcamNode>(config);
  auto& rec = rig.record({kImages});
  rig.run_for(200ms);
  REQUIRE(rec.count(kImages) > 0);
  const cv::Mat dark = cv::imdecode(rec.all<image_t>(kImages).back().data, cv::IMREAD_COLOR);

  // The projector lights the whole board pure red.
  projector_state_t p{};
  p.mode = projector_state_t::MODE_PATTERN;
  const cv::Mat red(192, 256, CV_8UC3, cv::Scalar(0, 0, 255));
  cv::imencode(".png", red, p.image.data);
  p.image.size = static_cast<int32_t>(p.image.data.size());
  p.image.width = 256;
  p.image.height = 192;
  p.image.format = image_t::FORMAT_PNG;
  rig.publish(channel(kProjectorChannel), p);
  rig.run_for(200ms);
  const cv::Mat lit = cv::imdecode(rec.all<image_t>(kImages).back().data, cv::IMREAD_COLOR);
  const cv::Scalar before = cv::mean(dark), after = cv::mean(lit);
  CHECK(after[2] > before[2] + 40);  // red rose a lot
  CHECK(after[1] > before[1] + 5);   // and some of it leaked into green, as real optics do
}

TEST_CASE("a broken projector image is a counted error and changes nothing") {
  harness::Rig rig;
  simcam::SimcamConfig config;
  config.scenario = kScenarios + "wall-60.json";
  auto& node = rig.add<simcam::SimcamNode>(config);
  projector_state_t p{};
  p.image.data = std::vector<uint8_t>(100, 7);
  p.image.size = 100;
  rig.publish(channel(kProjectorChannel), p);
  rig.step();  // one at a time: the newest projector image replaces one still waiting
  p.image.size = 5;  // does not match its data
  rig.publish(channel(kProjectorChannel), p);
  rig.run_for(100ms);
  CHECK(node.counters().errors == 2);
  CHECK(node.frames_published() > 0);
}
