// CalibrateNode on the in-process rig with the real SimcamNode (a random camera and projector setup,
// the projector's light drawn into its frames) and the real ProjectionNode (SDL's offscreen driver)
// answering its pattern commands: the closed loop of the exhibit, on a clock that moves only when the
// test steps it. A full calibration completes within the documented bounds (--max-error-px and
// --max-point-error-px, and within 1.5 projector px of simcam's true mapping); the self-check on the
// empty board passes unmoved and reports drift for a moved camera; --scale-from-blocks puts the bottom
// row's board x within 0.01 block lengths; --serve republishes and self-checks on command only on an
// empty board; without a projector the run fails
// after exactly twice --timeout of bus time with a counted error naming what is missing; the same
// run twice writes the same file byte for byte, and so does the node alone replaying the recorded
// run on the log bus (twice, and the same as the live run). --serve runs the same calibration on the
// command CALIBRATE once the board has been empty --empty-for seconds (it waits while blocks are on
// it, and gives up after --calibrate-wait), saves and serves it, or keeps the old one when it is
// rejected.
#include <catch2/catch.hpp>

#include <algorithm>

#include <nlohmann/json.hpp>

#include "bricklayer/board/board_geometry.h"
#include "bricklayer/board/calibration_file.h"
#include "bricklayer/board/mapping.h"
#include "bricklayer/calibration/board_x_accuracy.h"
#include "bricklayer/calibration/calibrate_node.h"
#include "bricklayer/calibration_t.hpp"
#include "bricklayer/command_t.hpp"
#include "bricklayer/heartbeat_t.hpp"
#include "bricklayer/common/channels.h"
#include "bricklayer/projection/projection_node.h"
#include "bricklayer/runtime/log_bus.h"
#include "bricklayer/runtime/log_file.h"
#include "bricklayer/simcam/render.h"
#include "bricklayer/simcam/simcam_node.h"
#include "bricklayer/stack_t.hpp"
#include "harness/rig.h"
#include "harness/scratch.h"

using namespace bricklayer;
using namespace std::chrono_literals;
using calibration::CalibrateConfig;
using calibration::CalibrateNode;

namespace {

constexpr int64_t kStepUs = 2'000;  // the rig's step: frames at 30 Hz land within 2 ms of their time
constexpr uint64_t kSetupSeed = 4;  // simcam's random camera + projector setup (the process test's)

const std::string kCommands = channel(kCommandChannel);
const std::string kCalibrations = channel(kCalibrationChannel);
const std::string kHeartbeats = channel(kHeartbeatChannel);

// An empty board for ten minutes, mild nuisance (blur, noise, shadow, JPEG).
std::string empty_scenario(const harness::ScratchDir& dir) {
  const std::string path = dir / "empty.json";
  harness::write_file(path, nlohmann::json{{"description", "an empty board"},
                                           {"nuisance", "mild"},
                                           {"seed", 7},
                                           {"duration_s", 600},
                                           {"keyframes", nlohmann::json::array({{{"t", 0}, {"blocks", nlohmann::json::array()}}})}}
                                .dump());
  return path;
}

// Four blocks standing apart on the bottom row and one on top, for ten minutes (--scale-from-blocks).
std::string blocks_scenario(const harness::ScratchDir& dir) {
  const std::string path = dir / "blocks.json";
  nlohmann::json blocks = nlohmann::json::array();
  for (auto [id, row, x] : {std::tuple<int, int, double>{1, 0, -3.4}, {2, 0, -1.9}, {3, 0, -0.6}, {4, 0, 0.7}, {5, 1, -3.1}})
    blocks.push_back({{"id", id}, {"row", row}, {"x", x}});
  harness::write_file(path, nlohmann::json{{"description", "four blocks apart on the bottom row, one on top"},
                                           {"nuisance", "mild"},
                                           {"seed", 7},
                                           {"duration_s", 600},
                                           {"keyframes", nlohmann::json::array({{{"t", 0}, {"blocks", blocks}}})}}
                                .dump());
  return path;
}

// What an operator lays for the scale step: four blocks apart on the bottom row, each standing (its middle
// over the surface: -4.6 .. -0.7, right end 0.3), and with `top` > 0 a tower on the blocks at -3.4 and -0.7,
// one block on another up to row `top`, each a few hundredths off the one below as hands leave them.
std::string ruler_scenario(const harness::ScratchDir& dir, int top) {
  const std::string path = dir / ("ruler-" + std::to_string(top) + ".json");
  nlohmann::json blocks = nlohmann::json::array();
  int id = 1;
  for (double x : {-4.6, -3.4, -2.1, -0.7}) blocks.push_back({{"id", id++}, {"row", 0}, {"x", x}});
  for (int row = 1; row <= top; ++row) {
    const double jitter = 0.03 * ((row * 7) % 5 - 2) / 2.0;
    blocks.push_back({{"id", id++}, {"row", row}, {"x", -3.4 + jitter}});
    blocks.push_back({{"id", id++}, {"row", row}, {"x", -0.7 - jitter}});
  }
  harness::write_file(path, nlohmann::json{{"description", "four blocks apart on the bottom row, towers to row " + std::to_string(top)},
                                           {"nuisance", "mild"},
                                           {"seed", 7},
                                           {"duration_s", 600},
                                           {"keyframes", nlohmann::json::array({{{"t", 0}, {"blocks", blocks}}})}}
                                .dump());
  return path;
}

// The largest |board x - true x| over the whole board the camera sees (x -5..5 in quarters, the middle of
// rows 0, 3, 6 and 9), the points judged, and the largest error / the calibration's stated bound there.
struct WholeBoard {
  double worst = 0.0, worst_far = 0.0, worst_high = 0.0, ratio = 0.0;  // worst_far: x +4..+5; worst_high: rows 6 and 9
  int points = 0, covered = 0;
};
WholeBoard whole_board(const calibration_t& c, uint64_t seed) {
  const simcam::CameraSetup camera = simcam::CameraSetup::random(seed);
  const double h = camera.board.block_height_px / camera.board.block_length_px;
  const double* a = c.board_x_accuracy;
  WholeBoard w;
  for (int row : {0, 3, 6, 9})
    for (double x = -5; x <= 5 + 1e-9; x += 0.25) {
      const double y = (row + 0.5) * h;
      const cv::Point2d p = simcam::rectified_to_camera(camera, {camera.board.to_px_x(x), camera.board.to_px_y(y)});
      if (p.x < 2 || p.y < 2 || p.x > camera.size.width - 3 || p.y > camera.size.height - 3) continue;
      const double error = std::abs(board::camera_to_board(c, p).x - x);
      const double bound = a[0] + a[1] * std::abs(x) + a[2] * y;
      ++w.points;
      w.covered += error <= bound;
      w.worst = std::max(w.worst, error);
      if (x >= 4 - 1e-9) w.worst_far = std::max(w.worst_far, error);
      if (row >= 6) w.worst_high = std::max(w.worst_high, error);
      w.ratio = std::max(w.ratio, bound > 0 ? error / bound : 1e9);
    }
  return w;
}

// Board x the calibration reads at true board (x, y) of simcam's setup.
double calibrated_x(const calibration_t& c, uint64_t seed, double x, double y = 0.2) {
  const simcam::CameraSetup camera = simcam::CameraSetup::random(seed);
  const BoardGeometry& g = camera.board;
  return board::camera_to_board(c, simcam::rectified_to_camera(camera, {g.to_px_x(x), g.to_px_y(y)})).x;
}

simcam::SimcamConfig camera_config(const std::string& scenario, int64_t setup_seed) {
  simcam::SimcamConfig c;
  c.scenario = scenario;
  c.setup_seed = setup_seed;
  return c;
}

projection::ProjectionConfig projector_config() {
  projection::ProjectionConfig c;
  c.headless = true;
  c.mute = true;
  return c;
}

CalibrateConfig calibrate_config(const std::string& output) {
  CalibrateConfig c;
  c.output = output;
  c.timeout = 2;
  return c;
}

// The largest distance (projector px) between the calibration's camera -> projector mapping and
// simcam's true one, over a 20 px grid of the rectified frame.
double max_mapping_error(const calibration_t& c, uint64_t seed) {
  const simcam::CameraSetup camera = simcam::CameraSetup::random(seed);
  const simcam::ProjectorSetup projector = simcam::ProjectorSetup::random(seed);
  double worst = 0;
  for (double y = 10; y <= 470; y += 20) {
    for (double x = 10; x <= 630; x += 20) {
      const cv::Point2d p = simcam::rectified_to_camera(camera, {x, y});
      if (p.x < 2 || p.y < 2 || p.x > camera.size.width - 3 || p.y > camera.size.height - 3) continue;
      worst = std::max(worst, cv::norm(board::camera_to_projector(c, p) - simcam::camera_to_projector(camera, projector, p)));
    }
  }
  return worst;
}

struct Run {
  int exit_code = -1;
  bool finished = false;
  int64_t bus_us = 0;  // bus time from start to finish
  std::string file;    // what the node wrote to --output ("" when nothing)
  std::vector<calibration_t> published;
  std::vector<command_t> commands;
  int64_t errors = 0;
  std::string status;
  heartbeat_t heartbeat;  // the node's last (what the status page reads)
};

// The whole exhibit loop on a rig: simcam, projection (unless without_projector) and calibrate;
// everything published is written to log_path when one is given.
Run run_calibrate(const CalibrateConfig& config, const std::string& scenario, int64_t setup_seed,
                  bool with_projector = true, std::chrono::microseconds max = 120s, const std::string& log_path = "") {
  harness::Rig rig(kStepUs);
  std::unique_ptr<runtime::LogWriter> log;
  if (!log_path.empty()) {
    log = std::make_unique<runtime::LogWriter>(log_path);
    rig.hub().set_tap([&log](const std::string&, const std::string& channel, const uint8_t* data, size_t size,
                             int64_t utime) { REQUIRE(log->write(utime, channel, data, size)); });
  }
  rig.add<simcam::SimcamNode>(camera_config(scenario, setup_seed));
  if (with_projector) rig.add<projection::ProjectionNode>(projector_config());
  auto& rec = rig.record({kCommands, kCalibrations});
  const int64_t start = rig.now();
  auto& node = rig.add<CalibrateNode>(config);
  Run r;
  r.finished = rig.run_until([&] { return node.finished(); }, max);
  rig.settle();
  r.exit_code = node.exit_code();
  r.bus_us = rig.now() - start;
  if (std::filesystem::exists(config.output)) r.file = harness::read_file(config.output);
  r.published = rec.all<calibration_t>(kCalibrations);
  r.commands = rec.all<command_t>(kCommands);
  r.errors = node.counters().errors;
  r.status = node.status();
  r.heartbeat = node.heartbeat();
  return r;
}

// CalibrateNode alone on a recorded log (the log bus: its clock is the events' times), as bricklayer-replay
// runs a module: to its finish or the log's end.
Run replay_calibrate(const CalibrateConfig& config, const std::string& log_path) {
  Run r;
  runtime::LogBus bus(log_path, {}, [&r](const std::string& channel, const uint8_t* data, size_t size, int64_t) {
    if (channel == kCalibrations)
      if (auto c = runtime::decode<calibration_t>(data, size)) r.published.push_back(*c);
    if (channel == kCommands)
      if (auto c = runtime::decode<command_t>(data, size)) r.commands.push_back(*c);
  });
  const int64_t start = bus.now_utime();
  CalibrateNode node(config, bus);
  while (!node.finished() && node.step(20)) {
  }
  r.finished = node.finished();
  r.exit_code = node.exit_code();
  r.bus_us = bus.now_utime() - start;
  if (std::filesystem::exists(config.output)) r.file = harness::read_file(config.output);
  r.errors = node.counters().errors;
  r.status = node.status();
  return r;
}

// One calibration for the test cases that need a calibrated setup (made once: a run is seconds).
const std::string& calibrated_file() {
  static harness::ScratchDir dir("calibrate-node-shared");
  static const std::string path = [] {
    const std::string out = dir / "calibration.json";
    const Run r = run_calibrate(calibrate_config(out), empty_scenario(dir), kSetupSeed);
    REQUIRE(r.exit_code == 0);
    return out;
  }();
  return path;
}

}  // namespace

TEST_CASE("the calibrate node calibrates through the real projection and simcam nodes within the documented bounds") {
  harness::ScratchDir dir("calibrate-node");
  const CalibrateConfig config = calibrate_config(dir / "calibration.json");
  const Run r = run_calibrate(config, empty_scenario(dir), kSetupSeed);
  INFO("status " << r.status << ", " << r.bus_us / 1000 << " ms of bus time");
  REQUIRE(r.finished);
  CHECK(r.exit_code == 0);
  CHECK(r.status == "ok");
  CHECK(r.errors == 0);
  // Six patterns, each once (no step timed out), then the projector back to the game.
  int shown = 0;
  for (const command_t& c : r.commands) shown += c.command == command_t::SHOW_PATTERN;
  CHECK(shown == 6);
  REQUIRE_FALSE(r.commands.empty());
  CHECK(r.commands.back().command == command_t::CLEAR_PATTERN);
  // Sequences: the bus clock at the first command, then counting.
  for (size_t i = 1; i < r.commands.size() && r.commands[i].command == command_t::SHOW_PATTERN; ++i)
    CHECK(r.commands[i].sequence == r.commands[i - 1].sequence + 1);

  REQUIRE_FALSE(r.file.empty());
  const calibration_t saved = board::load_calibration(config.output);
  INFO("reprojection error mean " << saved.reprojection_error_mean_px << " px, max " << saved.reprojection_error_max_px);
  CHECK(saved.reprojection_error_mean_px <= config.max_error_px);
  CHECK(saved.reprojection_error_max_px <= config.max_point_error_px);
  const double worst = max_mapping_error(saved, kSetupSeed);
  INFO("max mapping error against simcam's truth " << worst << " projector px");
  CHECK(worst < 1.5);
  // Published once, the same calibration as saved, stamped with the bus clock.
  REQUIRE(r.published.size() == 1);
  CHECK(r.published.front().utime == saved.utime);
  CHECK(saved.utime >= runtime::InProcessBus::kDefaultStartUtime);
  CHECK(saved.utime <= runtime::InProcessBus::kDefaultStartUtime + r.bus_us);
}

TEST_CASE("the same calibration run twice writes the same file byte for byte") {
  harness::ScratchDir a("calibrate-node-a"), b("calibrate-node-b");
  const Run first = run_calibrate(calibrate_config(a / "calibration.json"), empty_scenario(a), kSetupSeed);
  const Run second = run_calibrate(calibrate_config(b / "calibration.json"), empty_scenario(b), kSetupSeed);
  REQUIRE(first.exit_code == 0);
  REQUIRE(second.exit_code == 0);
  CHECK(first.bus_us == second.bus_us);
  CHECK(first.file == second.file);
  REQUIRE(first.published.size() == 1);
  REQUIRE(second.published.size() == 1);
  CHECK(runtime::encode(first.published.front()) == runtime::encode(second.published.front()));
}

TEST_CASE("a recorded calibration replayed on the log bus writes the live run's file byte for byte, every time") {
  harness::ScratchDir dir("calibrate-node-log");
  const std::string log = dir / "calibration.lcmlog";
  const Run live = run_calibrate(calibrate_config(dir / "live.json"), empty_scenario(dir), kSetupSeed, true, 120s, log);
  REQUIRE(live.exit_code == 0);
  const Run first = replay_calibrate(calibrate_config(dir / "replay-1.json"), log);
  const Run second = replay_calibrate(calibrate_config(dir / "replay-2.json"), log);
  INFO("replay status " << first.status);
  REQUIRE(first.finished);
  CHECK(first.exit_code == 0);
  CHECK(first.errors == 0);
  CHECK(first.file == second.file);
  CHECK(first.file == live.file);
  // The same commands (sequences from the recorded clock, so the recorded echoes match them).
  REQUIRE(first.commands.size() == live.commands.size());
  for (size_t i = 0; i < live.commands.size(); ++i) CHECK(runtime::encode(first.commands[i]) == runtime::encode(live.commands[i]));
  REQUIRE(first.published.size() == 1);
  REQUIRE(second.published.size() == 1);
  CHECK(runtime::encode(first.published.front()) == runtime::encode(live.published.front()));
  CHECK(runtime::encode(second.published.front()) == runtime::encode(live.published.front()));
}

TEST_CASE("the calibrate node's self-check on the empty board passes unmoved and reports a moved camera") {
  harness::ScratchDir dir("calibrate-node-check");
  const std::string scenario = empty_scenario(dir);
  CalibrateConfig config = calibrate_config(calibrated_file());
  config.self_check = true;
  const std::string before = harness::read_file(config.output);
  {
    harness::Rig rig(kStepUs);
    rig.add<simcam::SimcamNode>(camera_config(scenario, kSetupSeed));
    rig.add<projection::ProjectionNode>(projector_config());
    auto& node = rig.add<CalibrateNode>(config);
    REQUIRE(rig.run_until([&] { return node.finished(); }, 30s));
    INFO(node.status());
    CHECK(node.exit_code() == 0);
    CHECK(node.status() == "ok");
    const heartbeat_t hb = node.heartbeat();
    const std::optional<double> drift = harness::heartbeat_value(hb, "drift_px");
    REQUIRE(drift);
    INFO("drift " << *drift << " px");
    CHECK(*drift < 1.0);
  }
  {
    // Camera and projector mounted otherwise (simcam's setup 5): the check markers are seen far from
    // where the calibration expects them (exit 3).
    harness::Rig rig(kStepUs);
    simcam::SimcamConfig moved = camera_config(scenario, kSetupSeed);
    moved.setup_seed = 5;
    rig.add<simcam::SimcamNode>(moved);
    rig.add<projection::ProjectionNode>(projector_config());
    auto& node = rig.add<CalibrateNode>(config);
    REQUIRE(rig.run_until([&] { return node.finished(); }, 30s));
    INFO(node.status());
    CHECK(node.exit_code() == CalibrateNode::kExitDrift);
    CHECK(node.status() == "drift above threshold: recalibrate");
    const std::optional<double> drift = harness::heartbeat_value(node.heartbeat(), "drift_px");
    REQUIRE(drift);
    INFO("drift " << *drift << " px");  // measured 64 px
    CHECK(*drift > config.drift_threshold);
  }
  CHECK(harness::read_file(config.output) == before);  // a self-check never writes
}

TEST_CASE("the calibrate node corrects the board scale from blocks standing apart on the bottom row") {
  harness::ScratchDir dir("calibrate-node-scale");
  CalibrateConfig config = calibrate_config(dir / "calibration.json");
  std::filesystem::copy_file(calibrated_file(), config.output);
  config.scale_from_blocks = true;
  const calibration_t before = board::load_calibration(config.output);
  double worst_before = 0;
  for (double x : {-3.0, -1.0, 1.0, 3.0}) worst_before = std::max(worst_before, std::abs(calibrated_x(before, kSetupSeed, x) - x));
  INFO("bottom row board x off by up to " << worst_before << " block lengths as calibrated");
  const Run r = run_calibrate(config, blocks_scenario(dir), kSetupSeed, true, 30s);
  INFO("status " << r.status);
  REQUIRE(r.finished);
  REQUIRE(r.exit_code == 0);
  CHECK(r.errors == 0);
  const calibration_t after = board::load_calibration(config.output);
  REQUIRE(r.published.size() == 1);
  CHECK(runtime::encode(r.published.front()) == runtime::encode(after));
  CHECK(after.utime == runtime::InProcessBus::kDefaultStartUtime + r.bus_us);  // the bus clock when corrected
  double worst_after = 0;
  for (double x : {-3.0, -2.0, -1.0, 0.0, 1.0, 2.0, 3.0})
    worst_after = std::max(worst_after, std::abs(calibrated_x(after, kSetupSeed, x) - x));
  INFO("and up to " << worst_after << " after the correction");
  CHECK(worst_after < 0.01);  // measured 0.0069 (0.26 as calibrated)
  CHECK(worst_after < worst_before);

  // The corrected calibration states how far board x may still be off, and the truth is within it over the
  // whole board the camera sees (x -5..5 on rows 0, 3, 6 and 9), where the correction is extrapolated too.
  const double* a = after.board_x_accuracy;
  INFO("stated accuracy " << a[0] << " + " << a[1] << " |x| + " << a[2] << " y");
  CHECK(a[0] > 0);
  CHECK(a[1] > 0);
  CHECK(a[2] > 0);
  CHECK(before.board_x_accuracy[0] == 0);  // not stated before the scale step
  const simcam::CameraSetup camera = simcam::CameraSetup::random(kSetupSeed);
  const double h = camera.board.block_height_px / camera.board.block_length_px;
  int points = 0, covered = 0;
  double worst_ratio = 0;
  for (int row : {0, 3, 6, 9})
    for (double x = -5; x <= 5 + 1e-9; x += 0.5) {
      const double y = (row + 0.5) * h;
      const cv::Point2d p = simcam::rectified_to_camera(camera, {camera.board.to_px_x(x), camera.board.to_px_y(y)});
      if (p.x < 2 || p.y < 2 || p.x > camera.size.width - 3 || p.y > camera.size.height - 3) continue;
      const double error = std::abs(board::camera_to_board(after, p).x - x);
      const double bound = a[0] + a[1] * std::abs(x) + a[2] * y;
      ++points;
      covered += error <= bound;
      worst_ratio = std::max(worst_ratio, error / bound);
    }
  INFO(covered << " of " << points << " grid points within the stated bound; largest error / bound " << worst_ratio);
  CHECK(points > 40);
  CHECK(covered == points);
}

TEST_CASE("with towers of blocks on two bottom-row blocks the calibrate node's second pass measures every row: the whole board within 0.018, its stated bound covering it and narrower up the board, and without them the first pass stands") {
  // The scale step end to end as the operator runs it (the status page's "Correct the scale with blocks"):
  // the real simcam renders the blocks through mounting 4, standing still as they do on the exhibit, the real
  // projection node shows its light on them, CalibrateNode measures them. The towers reach row 9 (3.2 block
  // lengths up), where the first pass only extrapolates the vertical keystone from the bottom row's leans.
  // Measured: the whole board (x -5..5, rows 0/3/6/9) within 0.0169 with the towers and 0.0142 with the bottom
  // row alone: on this mounting the error left is the scale (0.2% small after the second pass) and the origin
  // (0.007), along the board, not up it; the bench's p99 for blocks standing still is 0.020 (README, Method 7).
  // What the towers change here is the stated bound: up the board it is the rows' (0.0055 per block length up
  // against 0.018), so at x 5 on row 9 it is 0.056 against 0.084.
  harness::ScratchDir dir("calibrate-node-towers");
  const std::string calibrated = harness::read_file(calibrated_file());
  const calibration_t before = board::load_calibration(calibrated_file());
  CalibrateConfig config = calibrate_config(dir / "calibration.json");
  config.scale_from_blocks = true;

  harness::write_file(config.output, calibrated);
  const Run towers = run_calibrate(config, ruler_scenario(dir, 9), kSetupSeed, true, 30s);
  INFO("with the towers: status " << towers.status);
  REQUIRE(towers.finished);
  REQUIRE(towers.exit_code == 0);
  CHECK(towers.errors == 0);
  CHECK(towers.status == "ok");
  // The second pass ran: blocks measured up to row 9.
  CHECK(harness::heartbeat_value(towers.heartbeat, "scale_highest_row") == 9.0);
  const calibration_t after = board::load_calibration(config.output);
  REQUIRE(towers.published.size() == 1);
  CHECK(runtime::encode(towers.published.front()) == runtime::encode(after));
  const WholeBoard w = whole_board(after, kSetupSeed);
  const double* a = after.board_x_accuracy;
  INFO("whole board: largest error " << w.worst << " (x +4..+5: " << w.worst_far << "), " << w.covered << " of " << w.points
                                     << " within the stated bound " << a[0] << " + " << a[1] << " |x| + " << a[2]
                                     << " y, largest error / bound " << w.ratio << "; as calibrated " << whole_board(before, kSetupSeed).worst);
  CHECK(whole_board(before, kSetupSeed).worst > 0.2);  // the mounting's projector is off square
  CHECK(w.points > 100);
  CHECK(w.worst < 0.018);  // measured 0.0169
  CHECK(w.covered == w.points);
  // The bound up the board is the rows' (the vertical keystone measured), tighter than from bottom-row leans.
  CHECK(a[2] > 0);
  CHECK(a[2] < calibration::kAccuracyLean);

  // The bottom row alone: no second pass (nothing up the board to measure), the first pass's correction is
  // accepted and saved with the wider bound of leans measured on the bottom row only.
  harness::write_file(config.output, calibrated);
  const Run bottom = run_calibrate(config, ruler_scenario(dir, 0), kSetupSeed, true, 30s);
  INFO("the bottom row alone: status " << bottom.status);
  REQUIRE(bottom.finished);
  REQUIRE(bottom.exit_code == 0);
  CHECK(bottom.errors == 0);
  CHECK(bottom.status == "ok");
  CHECK_FALSE(harness::heartbeat_value(bottom.heartbeat, "scale_highest_row").has_value());
  const calibration_t first = board::load_calibration(config.output);
  REQUIRE(bottom.published.size() == 1);
  const WholeBoard f = whole_board(first, kSetupSeed);
  INFO("bottom row alone: whole board largest error " << f.worst << ", " << f.covered << " of " << f.points << " within "
                                                      << first.board_x_accuracy[0] << " + " << first.board_x_accuracy[1]
                                                      << " |x| + " << first.board_x_accuracy[2] << " y");
  CHECK(first.board_x_accuracy[2] >= calibration::kAccuracyLean);
  CHECK(f.covered == f.points);
  CHECK(f.worst < 0.018);  // measured 0.0142
  // The bound where the knife edge is judged farthest from the ruler, x 5 on row 9: narrower with the towers.
  const double top = 9.5 * first.block_height;
  const double* b = first.board_x_accuracy;
  INFO("bound at x 5 row 9: " << a[0] + 5 * a[1] + top * a[2] << " with the towers, " << b[0] + 5 * b[1] + top * b[2] << " without");
  CHECK(a[0] + 5 * a[1] + top * a[2] < 0.8 * (b[0] + 5 * b[1] + top * b[2]));  // measured 0.056 against 0.084
}

TEST_CASE("the calibrate node serves its file and self-checks on command only while the board is empty") {
  harness::ScratchDir dir("calibrate-node-serve");
  CalibrateConfig config = calibrate_config(calibrated_file());
  config.serve = true;
  config.republish = 1;
  harness::Rig rig(kStepUs);
  rig.add<simcam::SimcamNode>(camera_config(empty_scenario(dir), kSetupSeed));
  rig.add<projection::ProjectionNode>(projector_config());
  auto& rec = rig.record({kCommands, kCalibrations});
  auto& node = rig.add<CalibrateNode>(config);
  // Published at once and every --republish second by the bus clock.
  rig.run_for(3500ms);
  CHECK(rec.count(kCalibrations) == 4);

  command_t check{};
  check.command = command_t::SELF_CHECK;
  check.sequence = 1;
  bricklayer::stack_t busy{};
  busy.status = bricklayer::stack_t::STATUS_OK;
  busy.num_blocks = 1;
  busy.blocks.resize(1);
  rig.publish(channel(kStackChannel), busy);
  rig.publish(kCommands, check);
  rig.run_for(1s);
  CHECK(node.status() == "self-check needs an empty board");
  auto shown = [&] {
    int n = 0;
    for (const command_t& c : rec.all<command_t>(kCommands)) n += c.command == command_t::SHOW_PATTERN;
    return n;
  };
  CHECK(shown() == 0);

  bricklayer::stack_t empty = busy;
  empty.num_blocks = 0;
  empty.blocks.clear();
  rig.publish(channel(kStackChannel), empty);
  rig.publish(kCommands, check);
  REQUIRE(rig.run_until([&] { return harness::heartbeat_value(node.heartbeat(), "drift_px").has_value(); }, 10s));
  CHECK(shown() == 1);
  CHECK(*harness::heartbeat_value(node.heartbeat(), "drift_px") < 1.0);
  CHECK(node.status() == "ok");
  CHECK_FALSE(node.finished());  // --serve never finishes by itself
}

namespace {
bricklayer::stack_t board_with(int blocks) {
  bricklayer::stack_t s{};
  s.status = bricklayer::stack_t::STATUS_OK;
  s.num_blocks = blocks;
  s.blocks.resize(blocks);
  return s;
}

command_t calibrate_command() {
  command_t c{};
  c.command = command_t::CALIBRATE;
  c.sequence = 1;
  c.argument = "bricklayer-status";
  return c;
}

int patterns_shown(const std::vector<command_t>& commands) {
  int n = 0;
  for (const command_t& c : commands) n += c.command == command_t::SHOW_PATTERN;
  return n;
}

// The latest heartbeat value of the calibrate node on the recorded heartbeats (what the status page reads).
std::optional<double> published_value(harness::Recorder& rec, const std::string& name) {
  const auto beats = rec.all<heartbeat_t>(kHeartbeats);
  for (auto it = beats.rbegin(); it != beats.rend(); ++it)
    if (it->module == "calibrate") return harness::heartbeat_value(*it, name);
  return std::nullopt;
}
}  // namespace

TEST_CASE("the serving calibrate node calibrates on CALIBRATE once the board has been empty --empty-for s, saves and serves the new one") {
  harness::ScratchDir dir("calibrate-node-serve-calibrate");
  CalibrateConfig config = calibrate_config(dir / "calibration.json");
  // Served until the command: the uncalibrated default (a projector mounted otherwise than assumed).
  board::save_calibration(config.output, board::default_calibration());
  const std::string old_file = harness::read_file(config.output);
  config.serve = true;
  config.republish = 1;
  config.empty_for = 1;
  config.calibrate_wait = 3;
  harness::Rig rig(kStepUs);
  rig.add<simcam::SimcamNode>(camera_config(empty_scenario(dir), kSetupSeed));
  rig.add<projection::ProjectionNode>(projector_config());
  auto& rec = rig.record({kCommands, kCalibrations, kHeartbeats});
  auto& node = rig.add<CalibrateNode>(config);
  const std::string stacks = channel(kStackChannel);
  rig.run_for(200ms);

  // Blocks on the board: the command waits; a second one is counted, not queued; after --calibrate-wait
  // it is dropped, said, and nothing was shown or written.
  rig.publish(stacks, board_with(2));
  rig.publish(kCommands, calibrate_command());
  rig.run_for(500ms);
  CHECK(node.status() == "calibration waits for an empty board: clear the board (at most 3 s)");
  rig.publish(kCommands, calibrate_command());
  rig.run_for(100ms);
  CHECK(node.calibrate_commands_ignored() == 1);
  rig.run_for(3s);
  CHECK(patterns_shown(rec.all<command_t>(kCommands)) == 0);
  CHECK(node.status() ==
        "calibration not started: the board was not empty for 1 s within 3 s; clear the board and ask again; still "
        "serving the previous calibration");
  CHECK(node.calibrations_failed() == 1);
  CHECK(harness::read_file(config.output) == old_file);

  // The board empty: the calibration starts only once it has been empty for --empty-for (1 s of bus time).
  rig.publish(stacks, board_with(0));
  rig.run_for(100ms);
  rig.publish(kCommands, calibrate_command());
  const int64_t asked = rig.now();
  rig.run_for(700ms);
  CHECK(patterns_shown(rec.all<command_t>(kCommands)) == 0);
  CHECK(node.status() == "calibration asked: waiting for the board to be empty for 1 s");
  REQUIRE(rig.run_until([&] { return patterns_shown(rec.all<command_t>(kCommands)) > 0; }, 1s));
  CHECK(rig.now() - asked <= 1'000'000);  // empty since 100 ms before the command
  CHECK(node.status().rfind("calibrating: step 1 of 6: ", 0) == 0);
  // Asked again while it runs: counted, not run twice.
  rig.publish(kCommands, calibrate_command());
  const int64_t started = rig.now();
  REQUIRE(rig.run_until([&] { return node.calibrations_done() + node.calibrations_failed() > 1; }, 60s));
  const int64_t took = rig.now() - started;
  INFO("status " << node.status() << "; the patterns took " << took / 1000 << " ms of bus time");
  CHECK(node.calibrations_done() == 1);
  CHECK(node.calibrate_commands_ignored() == 2);
  CHECK(node.status() == "ok");
  CHECK_FALSE(node.finished());
  const auto commands = rec.all<command_t>(kCommands);
  CHECK(patterns_shown(commands) == 6);  // the default mode's six patterns, once each
  CHECK(commands.back().command == command_t::CLEAR_PATTERN);

  // Saved, within the one-off run's bounds and simcam's truth, and served from then on.
  const std::string new_file = harness::read_file(config.output);
  REQUIRE(new_file != old_file);
  const calibration_t saved = board::load_calibration(config.output);
  INFO("reprojection error mean " << saved.reprojection_error_mean_px << " px, max " << saved.reprojection_error_max_px);
  CHECK(saved.reprojection_error_mean_px <= config.max_error_px);
  CHECK(saved.reprojection_error_max_px <= config.max_point_error_px);
  const double worst = max_mapping_error(saved, kSetupSeed);
  INFO("max mapping error against simcam's truth " << worst << " projector px");
  CHECK(worst < 1.5);
  CHECK(max_mapping_error(board::default_calibration(), kSetupSeed) > 1.5);  // the old one was off
  REQUIRE(node.calibration());
  CHECK(runtime::encode(*node.calibration()) == runtime::encode(saved));
  REQUIRE_FALSE(rec.all<calibration_t>(kCalibrations).empty());
  CHECK(runtime::encode(rec.all<calibration_t>(kCalibrations).back()) == runtime::encode(saved));
  rig.run_for(2100ms);  // republished (the file is its own write, not re-read as a change) and heartbeats
  CHECK(runtime::encode(rec.all<calibration_t>(kCalibrations).back()) == runtime::encode(saved));
  CHECK(harness::read_file(config.output) == new_file);
  CHECK(published_value(rec, "calibrations_done") == 1.0);
  CHECK(published_value(rec, "calibrate_commands_ignored") == 2.0);
  // The served calibration's age on the bus clock at the heartbeat.
  const auto beats = rec.all<heartbeat_t>(kHeartbeats);
  const auto last = std::find_if(beats.rbegin(), beats.rend(), [](const heartbeat_t& hb) { return hb.module == "calibrate"; });
  REQUIRE(last != beats.rend());
  const std::optional<double> age = harness::heartbeat_value(*last, "calibration_age_s");
  REQUIRE(age);
  CHECK(*age > 0);
  CHECK(*age == Approx(static_cast<double>(last->utime - saved.utime) / 1e6).margin(1e-6));
}

TEST_CASE("the serving calibrate node: a calibration on CALIBRATE that is rejected keeps serving the old one and says why") {
  harness::ScratchDir dir("calibrate-node-serve-rejected");
  CalibrateConfig config = calibrate_config(dir / "calibration.json");
  std::filesystem::copy_file(calibrated_file(), config.output);
  const std::string old_file = harness::read_file(config.output);
  const calibration_t old_calibration = board::load_calibration(config.output);
  config.serve = true;
  config.republish = 1;
  config.empty_for = 0.5;
  config.max_error_px = 0.01;  // no real fit is this good: the computation rejects it
  harness::Rig rig(kStepUs);
  rig.add<simcam::SimcamNode>(camera_config(empty_scenario(dir), kSetupSeed));
  rig.add<projection::ProjectionNode>(projector_config());
  auto& rec = rig.record({kCommands, kCalibrations});
  auto& node = rig.add<CalibrateNode>(config);
  rig.publish(channel(kStackChannel), board_with(0));
  rig.publish(kCommands, calibrate_command());
  REQUIRE(rig.run_until([&] { return node.calibrations_failed() > 0; }, 60s));
  INFO("status " << node.status());
  CHECK(node.calibrations_done() == 0);
  CHECK(patterns_shown(rec.all<command_t>(kCommands)) == 6);
  CHECK(node.status().rfind("calibration rejected (reprojection error too high): mean reprojection error ", 0) == 0);
  CHECK(node.status().find("; still serving the previous calibration") != std::string::npos);
  CHECK(node.counters().errors == 1);
  CHECK_FALSE(node.finished());
  rig.run_for(1100ms);
  CHECK(harness::read_file(config.output) == old_file);
  REQUIRE(node.calibration());
  CHECK(runtime::encode(*node.calibration()) == runtime::encode(old_calibration));
  CHECK(runtime::encode(rec.all<calibration_t>(kCalibrations).back()) == runtime::encode(old_calibration));
}

TEST_CASE("the serving calibrate node corrects the board scale on CALIBRATE scale-from-blocks, and serves the result") {
  harness::ScratchDir dir("calibrate-node-serve-scale");
  CalibrateConfig config = calibrate_config(dir / "calibration.json");
  std::filesystem::copy_file(calibrated_file(), config.output);
  const calibration_t before = board::load_calibration(config.output);
  config.serve = true;
  config.republish = 1;
  harness::Rig rig(kStepUs);
  rig.add<simcam::SimcamNode>(camera_config(blocks_scenario(dir), kSetupSeed));
  rig.add<projection::ProjectionNode>(projector_config());
  auto& rec = rig.record({kCommands, kCalibrations});
  auto& node = rig.add<CalibrateNode>(config);
  rig.run_for(200ms);
  command_t scale = calibrate_command();
  scale.argument = CalibrateNode::kScaleFromBlocks;
  rig.publish(kCommands, scale);  // blocks on the board: this step needs them, it starts at once
  rig.run_for(100ms);
  CHECK(node.status() == "measuring blocks on the bottom row");
  rig.publish(kCommands, scale);  // while it measures: counted, not run twice
  REQUIRE(rig.run_until([&] { return node.calibrations_done() + node.calibrations_failed() > 0; }, 30s));
  INFO("status " << node.status());
  CHECK(node.calibrations_done() == 1);
  CHECK(node.calibrate_commands_ignored() == 1);
  CHECK(node.status() == "ok");
  CHECK(node.counters().errors == 0);
  CHECK(patterns_shown(rec.all<command_t>(kCommands)) == 0);  // no patterns: the blocks are the ruler
  const calibration_t after = board::load_calibration(config.output);
  REQUIRE(node.calibration());
  CHECK(runtime::encode(*node.calibration()) == runtime::encode(after));
  CHECK(runtime::encode(rec.all<calibration_t>(kCalibrations).back()) == runtime::encode(after));
  double worst_before = 0, worst_after = 0;
  for (double x : {-3.0, -2.0, -1.0, 0.0, 1.0, 2.0, 3.0}) {
    worst_before = std::max(worst_before, std::abs(calibrated_x(before, kSetupSeed, x) - x));
    worst_after = std::max(worst_after, std::abs(calibrated_x(after, kSetupSeed, x) - x));
  }
  INFO("bottom row board x off by up to " << worst_before << " as calibrated, " << worst_after << " after");
  CHECK(worst_after < 0.01);  // as the one-off --scale-from-blocks
  CHECK(worst_after < worst_before);
  CHECK_FALSE(node.finished());
}

TEST_CASE("without a projector the calibrate node fails after twice --timeout of bus time with a counted error") {
  harness::ScratchDir dir("calibrate-node-noprojector");
  CalibrateConfig config = calibrate_config(dir / "never.json");
  config.timeout = 0.5;
  const Run r = run_calibrate(config, empty_scenario(dir), kSetupSeed, /*with_projector=*/false, 10s);
  INFO("status " << r.status);
  REQUIRE(r.finished);
  CHECK(r.exit_code == CalibrateNode::kExitRejected);
  CHECK(r.errors == 1);
  CHECK(r.status.find("the projector did not confirm step 1") != std::string::npos);
  CHECK(r.status.find("within 1 s): is bricklayer-projection running?") != std::string::npos);
  // Sent, sent again after --timeout, given up after another --timeout: 1 s of bus time (the rig's
  // clock moves in 2 ms steps).
  CHECK(r.bus_us >= 1'000'000);
  CHECK(r.bus_us <= 1'000'000 + 2 * kStepUs);
  REQUIRE(r.commands.size() == 3);
  CHECK(r.commands[0].command == command_t::SHOW_PATTERN);
  CHECK(r.commands[1].command == command_t::SHOW_PATTERN);
  CHECK(r.commands[1].sequence == r.commands[0].sequence + 1);
  CHECK(r.commands[2].command == command_t::CLEAR_PATTERN);
  CHECK(r.file.empty());
}

TEST_CASE("the calibrate node refuses a bad configuration built in code") {
  harness::Rig rig;
  CalibrateConfig c;
  c.projector_size = "huge";
  CHECK_THROWS_WITH(rig.add<CalibrateNode>(c), Catch::Contains("projector-size"));
  c = CalibrateConfig{};
  c.serve = c.self_check = true;
  CHECK_THROWS_WITH(rig.add<CalibrateNode>(c), Catch::Contains("exclude each other"));
  c = CalibrateConfig{};
  c.timeout = 0;
  CHECK_THROWS_AS(rig.add<CalibrateNode>(c), std::invalid_argument);
}
