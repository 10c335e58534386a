// VisionNode on the in-process rig: real frames rendered by simcam's renderer, decoded and detected by
// the real detector, with the rig's clock, so pacing, staleness and the calibration's arrival are
// checked in milliseconds and the same way every run.
#include <catch2/catch.hpp>

#include <opencv2/imgcodecs.hpp>

#include "bricklayer/board/calibration_file.h"
#include "bricklayer/common/channels.h"
#include "bricklayer/heartbeat_t.hpp"
#include "bricklayer/timing_t.hpp"
#include "bricklayer/simcam/render.h"
#include "bricklayer/stack_t.hpp"
#include "bricklayer/vision/vision_node.h"
#include "harness/rig.h"
#include "harness/scratch.h"

using namespace bricklayer;
using namespace std::chrono_literals;

namespace {
const std::string kImages = channel(kImageChannel);
const std::string kStacks = channel(kStackChannel);

core::Stack three_blocks() {
  core::Stack s;
  s.blocks = {{1, 0, -2.5}, {2, 0, -1.2}, {3, 1, -1.9}};
  return s;
}

image_t jpeg_frame(const std::vector<uint8_t>& jpeg, int64_t number) {
  image_t img{};
  img.utime = 1000 + number * 33333;
  img.frame_number = number;
  img.width = 640;
  img.height = 480;
  img.format = image_t::FORMAT_JPEG;
  img.source = "test";
  img.data = jpeg;
  img.size = static_cast<int32_t>(jpeg.size());
  return img;
}

std::vector<uint8_t> rendered_jpeg(const core::Stack& stack) {
  simcam::Renderer renderer;
  std::vector<uint8_t> jpeg;
  cv::imencode(".jpg", renderer.render(stack, simcam::Nuisance::level(1), nullptr, 3).bgr, jpeg,
               {cv::IMWRITE_JPEG_QUALITY, 90});
  return jpeg;
}
}  // namespace

TEST_CASE("the vision node answers every frame with a stack carrying its utime and frame number") {
  harness::Rig rig;
  rig.add<vision::VisionNode>(vision::VisionConfig{});
  auto& rec = rig.record({kStacks, channel(kTimingChannel)});
  const auto jpeg = rendered_jpeg(three_blocks());
  for (int f = 0; f < 6; ++f) {
    rig.publish(kImages, jpeg_frame(jpeg, f));
    auto s = rec.wait_for<stack_t>(kStacks, [f](const stack_t& m) { return m.frame_number == f; }, 100ms);
    REQUIRE(s);
    CHECK(s->utime == 1000 + f * 33333);
    CHECK(s->status == stack_t::STATUS_OK);
  }
  // The temporal filter confirms a block seen in 2 of the last 3 frames: from the second frame on,
  // all three, where they stand.
  const auto last = rec.all<stack_t>(kStacks).back();
  REQUIRE(last.num_blocks == 3);
  const core::Stack truth = three_blocks();
  for (size_t k = 0; k < 3; ++k) {
    CHECK(last.blocks[k].row == truth.blocks[k].row);
    CHECK(last.blocks[k].x == Approx(truth.blocks[k].x).margin(0.02));
  }
  const auto timings = rec.all<timing_t>(channel(kTimingChannel));
  REQUIRE(timings.size() == 6);
  CHECK(timings.back().stage == "detect");
}

TEST_CASE("with --require-calibration the vision node publishes nothing until a calibration arrives, and a republished one changes nothing") {
  // What an exhibit's launcher runs: a restarted vision must not publish stacks measured in the wrong
  // frame, and bricklayer-calibrate --serve republishing the same calibration must not reset it.
  harness::Rig rig;
  vision::VisionConfig config;
  config.require_calibration = true;
  auto& node = rig.add<vision::VisionNode>(config);
  auto& rec = rig.record({kStacks});
  const auto jpeg = rendered_jpeg(three_blocks());
  int64_t frame = 0;
  auto stream = [&](int frames, const std::function<void()>& each) {
    for (int i = 0; i < frames; ++i) {
      rig.publish(kImages, jpeg_frame(jpeg, frame++));
      if (each) each();
      rig.run_for(33ms);
    }
  };
  stream(20, nullptr);
  CHECK(rec.count(kStacks) == 0);
  CHECK(node.status() == "waiting for a calibration");

  // The default calibration describes the default camera simcam renders.
  const calibration_t calibration = board::default_calibration();
  rig.publish(channel(kCalibrationChannel), calibration);
  stream(10, nullptr);
  REQUIRE(rec.count(kStacks) > 0);
  CHECK(rec.all<stack_t>(kStacks).back().num_blocks == 3);
  CHECK(node.status() == "ok");
  const size_t before = rec.count(kStacks);
  int republished = 0;
  stream(30, [&] {
    if (frame % 3 == 0) rig.publish(channel(kCalibrationChannel), calibration), ++republished;
  });
  CHECK(republished == 10);
  const auto stacks = rec.all<stack_t>(kStacks);
  REQUIRE(stacks.size() == before + 30);
  int short_stacks = 0;  // a reset temporal filter would publish fewer blocks until it confirms them again
  for (size_t k = before; k < stacks.size(); ++k) short_stacks += stacks[k].num_blocks != 3;
  CHECK(short_stacks == 0);
}

TEST_CASE("a corrupt frame is a no-frame stack and a counted error, the next good frame is measured") {
  harness::Rig rig;
  auto& node = rig.add<vision::VisionNode>(vision::VisionConfig{});
  auto& rec = rig.record({kStacks});
  auto jpeg = rendered_jpeg(three_blocks());
  std::vector<uint8_t> torn(jpeg.begin(), jpeg.begin() + static_cast<std::ptrdiff_t>(jpeg.size() / 3));
  rig.publish(kImages, jpeg_frame(std::vector<uint8_t>(1000, 0x5a), 0));
  rig.step();
  rig.publish(kImages, jpeg_frame(torn, 1));
  rig.step();
  rig.publish(kImages, jpeg_frame(jpeg, 2));
  rig.step();
  const auto stacks = rec.all<stack_t>(kStacks);
  REQUIRE(stacks.size() == 3);
  CHECK(stacks[0].status == stack_t::STATUS_NO_FRAME);
  CHECK(stacks[2].status == stack_t::STATUS_OK);
  CHECK(stacks[2].frame_number == 2);
  CHECK(node.counters().errors >= 1);
  CHECK(node.counters().received == 3);
}

TEST_CASE("when frames stop the vision node's status says so, and clears when they return") {
  harness::Rig rig(10'000);
  auto& node = rig.add<vision::VisionNode>(vision::VisionConfig{});
  const auto jpeg = rendered_jpeg(three_blocks());
  rig.publish(kImages, jpeg_frame(jpeg, 0));
  rig.run_for(1s);
  CHECK(node.status() == "ok");
  rig.run_for(4s);
  CHECK(node.status().rfind("no frames for ", 0) == 0);
  rig.publish(kImages, jpeg_frame(jpeg, 1));
  rig.step();
  CHECK(node.status() == "ok");
}

TEST_CASE("a folder of images is read at its rate by the bus clock, each frame's utime its place in the sequence") {
  harness::ScratchDir dir("vision-node-folder");
  simcam::Renderer renderer;
  for (int i = 0; i < 5; ++i)
    cv::imwrite((dir / ("frame" + std::to_string(i) + ".png")).string(),
                renderer.render(three_blocks(), simcam::Nuisance::level(1), nullptr, 3).bgr);
  harness::Rig rig(5'000);
  vision::VisionConfig config;
  config.images = dir.path().string();
  config.rate = 10;
  auto& node = rig.add<vision::VisionNode>(config);
  auto& rec = rig.record({kStacks});
  rig.run_for(250ms);  // frames at 0, 0.1 and 0.2 s
  CHECK(rec.count(kStacks) == 3);
  rig.run_for(1s);
  const auto stacks = rec.all<stack_t>(kStacks);
  REQUIRE(stacks.size() == 5);
  for (int i = 0; i < 5; ++i) {
    CHECK(stacks[static_cast<size_t>(i)].frame_number == i);
    CHECK(stacks[static_cast<size_t>(i)].utime == i * 100'000);
  }
  CHECK(node.status() == "source exhausted");
}

TEST_CASE("the vision configuration is checked where it is declared") {
  vision::VisionConfig c;
  CHECK_NOTHROW(vision::VisionNode::check(c));
  c.confirm = "3/2";
  CHECK_THROWS_WITH(vision::VisionNode::check(c), Catch::Contains("1 <= N <= M"));
  c.confirm = "two";
  CHECK_THROWS_WITH(vision::VisionNode::check(c), Catch::Contains("N/M"));
  c = {};
  c.video = "a.avi";
  c.images = "dir";
  CHECK_THROWS_WITH(vision::VisionNode::check(c), Catch::Contains("at most one"));
  c = {};
  c.json = true;
  CHECK_THROWS_WITH(vision::VisionNode::check(c), Catch::Contains("--json needs --images"));
}

TEST_CASE("every published block carries its own position uncertainty, never below the calibration's residual or --min-uncertainty") {
  const auto jpeg = rendered_jpeg(three_blocks());
  auto last_stack = [&](const vision::VisionConfig& config, const calibration_t* calibration) {
    harness::Rig rig;
    rig.add<vision::VisionNode>(config);
    auto& rec = rig.record({kStacks});
    if (calibration) rig.publish(channel(kCalibrationChannel), *calibration);
    for (int f = 0; f < 6; ++f) {
      rig.publish(kImages, jpeg_frame(jpeg, f));
      rig.step();
    }
    const auto stacks = rec.all<stack_t>(kStacks);
    REQUIRE(!stacks.empty());
    REQUIRE(stacks.back().num_blocks == 3);
    return stacks.back();
  };
  // Measured: positive, small on a mild frame (a few thousandths of a block at most), and covering the error.
  const stack_t measured = last_stack({}, nullptr);
  const core::Stack truth = three_blocks();
  for (size_t k = 0; k < 3; ++k) {
    CHECK(measured.blocks[k].x_uncertainty > 0.0);
    CHECK(measured.blocks[k].x_uncertainty < 0.005);
    CHECK(std::abs(measured.blocks[k].x - truth.blocks[k].x) <= measured.blocks[k].x_uncertainty);
  }
  vision::VisionConfig floor;
  floor.min_uncertainty = 0.02;
  for (const block_t& b : last_stack(floor, nullptr).blocks) CHECK(b.x_uncertainty == 0.02);
  // A calibration whose residual is 1 projector pixel: 1/96 block lengths in the default setup.
  calibration_t calibration = board::default_calibration();
  calibration.reprojection_error_mean_px = 1.0;
  calibration.reprojection_error_max_px = 1.0;
  for (const block_t& b : last_stack({}, &calibration).blocks) CHECK(b.x_uncertainty == Approx(1.0 / 96));
}
