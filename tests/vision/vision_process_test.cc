// bricklayer-vision as a real process. Offline: --images DIR --board FILE --json prints one predict-input
// line per image (name order). On the bus (NETNS), end to end: simcam -> vision -> prediction reproduces
// the verdicts of the scenario's true stacks. (The node's behaviour on the bus, frame by frame, is
// vision_node_test.cc.)
#include <catch2/catch.hpp>

#include <algorithm>
#include <chrono>
#include <filesystem>
#include <fstream>
#include <iostream>
#include <map>
#include <string>
#include <vector>

#include <nlohmann/json.hpp>
#include <opencv2/imgcodecs.hpp>

#include "bricklayer/board/calibration_file.h"
#include "bricklayer/common/channels.h"
#include "bricklayer/core/predict.h"
#include "bricklayer/prediction_t.hpp"
#include "bricklayer/runtime/lcm_bus.h"
#include "bricklayer/simcam/render.h"
#include "bricklayer/stack_t.hpp"
#include "harness/program.h"
#include "harness/recorder.h"
#include "harness/scratch.h"

using namespace bricklayer;
using namespace std::chrono_literals;
namespace fs = std::filesystem;

namespace {
const std::string kUrl = "udpm://239.255.76.67:7667?ttl=0";
}  // namespace

TEST_CASE("offline --json prints one predict-input stack per image, in name order") {
  harness::ScratchDir dir("vision-offline");
  fs::create_directories(dir / "images");
  std::ofstream(dir / "board.json") << R"({"edge_x_px": 320, "surface_y_px": 440, "block_length_px": 60, "block_height_px": 20})";
  simcam::Renderer renderer;
  std::vector<core::Stack> stacks(3);
  stacks[0].blocks = {{1, 0, -0.6}};
  stacks[1].blocks = {{1, 0, -0.6}, {2, 1, -0.3}};
  stacks[2].blocks = {{1, 0, -2.5}, {2, 0, -1.2}, {3, 1, -1.9}};
  for (size_t i = 0; i < stacks.size(); ++i) {
    auto frame = renderer.render(stacks[i], simcam::Nuisance::level(1), nullptr, i + 1);
    cv::imwrite((dir / "images" / ("frame" + std::to_string(i) + ".png")).string(), frame.bgr);
  }
  const auto ran = harness::run_program("bricklayer-vision", {"--images", (dir / "images").string(), "--board",
                                                             (dir / "board.json").string(), "--json"});
  const std::string& out = ran.out;
  INFO(ran.err);
  CHECK(ran.status.clean());
  std::vector<nlohmann::json> lines;
  size_t start = 0;
  while (start < out.size()) {
    size_t end = out.find('\n', start);
    if (end == std::string::npos) end = out.size();
    if (end > start) lines.push_back(nlohmann::json::parse(out.substr(start, end - start)));
    start = end + 1;
  }
  INFO(out);
  REQUIRE(lines.size() == 3);
  for (size_t i = 0; i < 3; ++i) {
    // Parsed by the core's own parser: the output is bricklayer-predict's input format.
    core::Stack got = core::stack_from_json(lines[i]);
    REQUIRE(got.blocks.size() == stacks[i].blocks.size());
    for (size_t k = 0; k < got.blocks.size(); ++k) {
      CHECK(got.blocks[k].row == stacks[i].blocks[k].row);
      CHECK(got.blocks[k].x == Approx(stacks[i].blocks[k].x).margin(0.02));
    }
  }
}

TEST_CASE("vision takes bricklayer-calibrate's calibration file and refuses a malformed one naming the problem") {
  harness::ScratchDir dir("vision-calibration");
  fs::create_directories(dir / "images");
  core::Stack stack;
  stack.blocks = {{1, 0, -2.5}, {2, 0, -1.2}, {3, 1, -1.9}};
  simcam::Renderer renderer;
  cv::imwrite((dir / "images" / "frame0.png").string(), renderer.render(stack, simcam::Nuisance::level(1), nullptr, 3).bgr);
  // The default calibration describes the default camera simcam renders: same blocks through the calibrated path.
  board::save_calibration((dir / "calibration.json").string(), board::default_calibration());
  auto ran = harness::run_program("bricklayer-vision", {"--images", (dir / "images").string(), "--calibration",
                                                      (dir / "calibration.json").string(), "--json"});
  INFO(ran.err);
  CHECK(ran.status.clean());
  const core::Stack got = core::stack_from_json(nlohmann::json::parse(ran.out));
  REQUIRE(got.blocks.size() == 3);
  for (size_t k = 0; k < 3; ++k) {
    CHECK(got.blocks[k].row == stack.blocks[k].row);
    CHECK(got.blocks[k].x == Approx(stack.blocks[k].x).margin(0.02));
  }
  // Strict: a key missing is an error naming the file and the key, and nothing is detected.
  std::ofstream(dir / "bad.json") << R"({"format": "bricklayer-calibration", "version": 1, "camera_width": 640})";
  ran = harness::run_program("bricklayer-vision",
                             {"--images", (dir / "images").string(), "--calibration", (dir / "bad.json").string(), "--json"});
  INFO(ran.err);
  CHECK_FALSE(ran.status.clean());
  CHECK(ran.err.find("bad.json") != std::string::npos);
  CHECK(ran.out.find("\"blocks\"") == std::string::npos);
}

TEST_CASE("simcam -> vision -> prediction over LCM reproduces the verdicts of the true stacks") {
  harness::ScratchDir dir("vision-e2e");
  // A balanced pile with margin, then a third block placed too far out (unbalanced, it is the cause).
  // (Zero-margin optima are knife edges that measurement error may tip either way: not compared here.)
  std::ofstream(dir / "scenario.json") << R"({"nuisance": "mild", "seed": 5, "duration_s": 4, "keyframes": [
    {"t": 0, "blocks": [{"id":1,"row":0,"x":-0.6},{"id":2,"row":1,"x":-1.05}]},
    {"t": 2, "blocks": [{"id":1,"row":0,"x":-0.6},{"id":2,"row":1,"x":-1.05},{"id":3,"row":1,"x":-0.03}]}]})";
  runtime::LcmBus bus(kUrl);
  auto rec = harness::Recorder::live(bus, {channel(kTruthChannel), channel(kPredictionChannel), channel(kHeartbeatChannel)});
  harness::Program prediction("bricklayer-prediction", {"--lcm-url", kUrl});
  harness::Program vision("bricklayer-vision", {"--lcm-url", kUrl});
  REQUIRE(rec.wait_for_heartbeat("vision", {}, 10s));
  REQUIRE(rec.wait_for_heartbeat("prediction", {}, 10s));
  harness::Program simcam("bricklayer-simcam", {"--scenario", (dir / "scenario.json").string(), "--fps", "15",
                                               "--no-projector", "--lcm-url", kUrl});
  // The scenario lasts 4 s at 15 frames a second; then the last predictions arrive.
  const auto ended = simcam.wait_exit(15s);
  INFO(simcam.stderr_text());
  CHECK(ended);
  rec.pump_for(500ms);
  prediction.stop();
  vision.stop();
  std::map<int64_t, bricklayer::stack_t> truth;
  std::map<int64_t, prediction_t> predictions;
  for (const auto& s : rec.all<bricklayer::stack_t>(channel(kTruthChannel))) truth[s.frame_number] = s;
  for (const auto& p : rec.all<prediction_t>(channel(kPredictionChannel))) predictions[p.frame_number] = p;

  // Compare every answered frame whose true stack has been the same for the last 5 frames (the temporal
  // filter needs a few frames to confirm a change).
  int compared = 0, agreed = 0, unbalanced_seen = 0;
  for (const auto& [frame, p] : predictions) {
    auto t = truth.find(frame);
    if (t == truth.end() || p.status != prediction_t::STATUS_OK) continue;
    bool settled = true;
    for (int64_t k = frame - 5; k < frame; ++k) {
      auto prev = truth.find(k);
      settled &= prev != truth.end() && prev->second.num_blocks == t->second.num_blocks;
    }
    if (!settled) continue;
    core::Stack s;
    s.block_height = t->second.block_height;
    for (const auto& b : t->second.blocks) s.blocks.push_back({b.id, b.row, b.x});
    core::Prediction expected = core::predict(s);
    ++compared;
    unbalanced_seen += !expected.balanced;
    int causes = static_cast<int>(std::count_if(p.blocks.begin(), p.blocks.end(), [](const block_prediction_t& b) {
      return b.state == block_prediction_t::STATE_CAUSE;
    }));
    // Score within one point: vision's temporal filter publishes x within a 0.01-block deadband (1 point).
    if (expected.balanced == p.balanced && std::abs(expected.score - p.score) <= 1 &&
        static_cast<int>(expected.causes().size()) == causes)
      ++agreed;
    else
      std::cerr << "frame " << frame << ": expected balanced " << expected.balanced << " score " << expected.score
                << " causes " << expected.causes().size() << "; got balanced " << int{p.balanced} << " score " << p.score
                << " causes " << causes << " (" << p.num_blocks << " blocks)\n";
  }
  INFO(compared << " settled frames compared, " << agreed << " agreed, " << unbalanced_seen << " unbalanced");
  CHECK(compared >= 20);
  CHECK(unbalanced_seen >= 5);
  CHECK(agreed == compared);
}
