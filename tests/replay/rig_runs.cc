#include "rig_runs.h"

#include <stdexcept>

#include <nlohmann/json.hpp>

#include "bricklayer/calibration/calibrate_node.h"
#include "bricklayer/command_t.hpp"
#include "bricklayer/common/channels.h"
#include "bricklayer/planner/planner_node.h"
#include "bricklayer/prediction/prediction_node.h"
#include "bricklayer/prediction/sample_stacks.h"
#include "bricklayer/projection/projection_node.h"
#include "bricklayer/runtime/config.h"
#include "bricklayer/runtime/log_file.h"
#include "bricklayer/simcam/simcam_node.h"
#include "bricklayer/stack_t.hpp"
#include "bricklayer/vision/vision_node.h"
#include "harness/rig.h"
#include "harness/scratch.h"

namespace bricklayer::test {
namespace {

using namespace std::chrono_literals;

// Every message the bus carries, at its publication time.
class LogTap {
 public:
  LogTap(harness::Rig& rig, const std::string& path) : path_(path), writer_(path) {
    rig.hub().set_tap([this](const std::string&, const std::string& ch, const uint8_t* data, size_t size, int64_t utime) {
      if (!writer_.write(utime, ch, data, size)) throw std::runtime_error("cannot write " + path_);
    });
  }
  int64_t finish() {
    if (!writer_.flush()) throw std::runtime_error("cannot write " + path_);
    return writer_.events();
  }

 private:
  std::string path_;
  runtime::LogWriter writer_;
};

template <typename NodeType>
NodeType& add_configured(harness::Rig& rig, const typename NodeType::Config& config) {
  auto& node = rig.add<NodeType>(config);
  node.set_config(NodeType::kProgram, runtime::to_json(config).dump());
  return node;
}

projection::ProjectionConfig small_projector() {
  projection::ProjectionConfig c;
  c.headless = true;
  c.mute = true;
  c.width = 320;
  c.height = 240;
  c.round_seconds = 3;
  c.status_image_every = 1;
  return c;
}

void publish_command(harness::Rig& rig, int32_t command, int32_t index = 0, const std::string& argument = "operator") {
  command_t c{};
  c.utime = rig.now();
  c.command = command;
  c.index = index;
  c.sequence = rig.now();
  c.argument = argument;
  rig.publish(channel(kCommandChannel), c);
}

std::string empty_scenario(const std::string& path) {
  harness::write_file(path, nlohmann::json{{"description", "an empty board"},
                                           {"nuisance", "mild"},
                                           {"seed", 7},
                                           {"duration_s", 600},
                                           {"keyframes", nlohmann::json::array({{{"t", 0}, {"blocks", nlohmann::json::array()}}})}}
                                .dump());
  return path;
}

calibration::CalibrateConfig calibrate_config(const std::string& output) {
  calibration::CalibrateConfig c;
  c.output = output;
  c.timeout = 2;
  return c;
}

projection::ProjectionConfig pattern_projector() {
  projection::ProjectionConfig c;
  c.headless = true;
  c.mute = true;
  return c;
}

simcam::SimcamConfig calibration_camera(const std::string& scenario) {
  simcam::SimcamConfig c;
  c.scenario = scenario;
  c.setup_seed = 4;
  return c;
}

}  // namespace

int64_t record_projection_run(const std::string& path, double seconds) {
  harness::Rig rig(1000);
  LogTap tap(rig, path);
  add_configured<prediction::PredictionNode>(rig, prediction::PredictionConfig{});
  add_configured<planner::PlannerNode>(rig, planner::PlannerConfig{});
  add_configured<projection::ProjectionNode>(rig, small_projector());
  const int frames = static_cast<int>(seconds * 30);
  for (int f = 0; f < frames; ++f) {
    const int64_t t = runtime::InProcessBus::kDefaultStartUtime + f * 33'333;
    if (t > rig.now()) rig.run_for(std::chrono::microseconds(t - rig.now()));
    // 1.2 s of an empty board, then piles of 2..9 blocks (a new one every 20 frames, some unbalanced:
    // previews, red blocks); a round starts 2 s after the first pile and runs 3 s.
    stack_t s{};
    if (f < 36) {
      s.utime = rig.now();
      s.frame_number = f;
      s.block_length = 1.0;
      s.block_height = 1.0 / 3.0;
      s.status = stack_t::STATUS_OK;
    } else {
      s = prediction::sample_stack(2 + (f / 20) % 8, static_cast<uint32_t>(f / 20), rig.now(), f);
    }
    rig.publish(channel(kStackChannel), s);
    if (f == 150) publish_command(rig, command_t::SET_CONDITION, 2);  // red
    if (f == 200) publish_command(rig, command_t::SET_CONDITION, 3);  // proposed again
    if (f == 210) publish_command(rig, command_t::START_ROUND);
    if (f % 45 == 44) publish_command(rig, command_t::REQUEST_HINT);
    rig.step();
  }
  rig.run_for(300ms);
  return tap.finish();
}

int64_t record_calibration_run(const std::string& path, const std::string& output) {
  harness::ScratchDir dir("replay-calibration-scenario");
  harness::Rig rig(2000);
  LogTap tap(rig, path);
  rig.add<simcam::SimcamNode>(calibration_camera(empty_scenario((dir / "empty.json").string())));
  add_configured<projection::ProjectionNode>(rig, pattern_projector());
  auto& node = add_configured<calibration::CalibrateNode>(rig, calibrate_config(output));
  if (!rig.run_until([&] { return node.finished(); }, 120s)) throw std::runtime_error("the calibration did not finish");
  if (node.exit_code() != 0) throw std::runtime_error("the calibration was rejected: " + node.status());
  rig.run_for(100ms);
  return tap.finish();
}

int64_t record_serve_run(const std::string& path, const std::string& calibration_file, double seconds) {
  harness::ScratchDir dir("replay-serve-scenario");
  harness::Rig rig(2000);
  LogTap tap(rig, path);
  rig.add<simcam::SimcamNode>(calibration_camera(empty_scenario((dir / "empty.json").string())));
  add_configured<projection::ProjectionNode>(rig, pattern_projector());
  calibration::CalibrateConfig c = calibrate_config(calibration_file);
  c.serve = true;
  c.republish = 1;
  add_configured<calibration::CalibrateNode>(rig, c);
  const int frames = static_cast<int>(seconds * 10);
  for (int f = 0; f < frames; ++f) {
    // What vision would say of the empty board, ten times a second.
    stack_t s{};
    s.utime = rig.now();
    s.frame_number = f;
    s.block_length = 1.0;
    s.block_height = 1.0 / 3.0;
    s.status = stack_t::STATUS_OK;
    rig.publish(channel(kStackChannel), s);
    if (f == 15) publish_command(rig, command_t::SELF_CHECK);
    rig.run_for(100ms);
  }
  return tap.finish();
}

int64_t record_regression_run(const std::string& path, double seconds) {
  harness::Rig rig(1000);
  LogTap tap(rig, path);
  simcam::SimcamConfig camera;
  camera.scenario = std::string(BRICKLAYER_SOURCE_DIR) + "/launch/scenarios/build-4-optimum.json";
  camera.fps = 5;
  camera.jpeg_quality = 40;
  camera.frames = static_cast<int64_t>(seconds * camera.fps);
  rig.add<simcam::SimcamNode>(camera);
  add_configured<vision::VisionNode>(rig, vision::VisionConfig{});
  add_configured<prediction::PredictionNode>(rig, prediction::PredictionConfig{});
  add_configured<planner::PlannerNode>(rig, planner::PlannerConfig{});
  projection::ProjectionConfig p = small_projector();
  // Small: the projector state five times a second; a round starts 1 s after the first block.
  p.state_hz = 5;
  p.round_start_hold = 1;
  p.status_image_every = 2;
  add_configured<projection::ProjectionNode>(rig, p);
  rig.run_for(std::chrono::microseconds(static_cast<int64_t>(seconds * 1e6) + 300'000));
  return tap.finish();
}

}  // namespace bricklayer::test
