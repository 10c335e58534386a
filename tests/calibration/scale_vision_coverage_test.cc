// Does vision's stated position uncertainty hold on a mounting whose scale was measured with blocks? The
// whole chain on the in-process rig, every piece the exhibit's own: CalibrateNode calibrates through the real
// SimcamNode (a random camera and a random, non-square projector mounting: scale, rotation and keystone off)
// and the real ProjectionNode, then corrects the board frame with --scale-from-blocks from four blocks
// standing apart on the bottom row (-3.4 .. 0.7). The corrected calibration goes to the real VisionNode on
// BL_CALIBRATION, which then sees a stepped overhang pile (simcam-rendered JPEG frames of the same mounting,
// mild nuisance) whose blocks reach far from that ruler: up to row 9 and x = +4.5 (right end 5.5), where the
// correction is extrapolated along the board and up it. Every block vision publishes must have its true board
// x within its published x_uncertainty, and that interval must stay narrow enough to be of use to the
// knife-edge verdict (the test fails both ways). With the calibration as it was before the scale step
// (board x off by 0.1-0.35 block lengths, nothing stated) the same frames are not covered: what
// the first check proves is the correction and the stated bound, not a wide interval.
#include <catch2/catch.hpp>

#include <algorithm>
#include <cstdio>

#include <nlohmann/json.hpp>
#include <opencv2/imgcodecs.hpp>

#include "bricklayer/board/calibration_file.h"
#include "bricklayer/calibration/calibrate_node.h"
#include "bricklayer/calibration_t.hpp"
#include "bricklayer/common/channels.h"
#include "bricklayer/frames/image_codec.h"
#include "bricklayer/projection/projection_node.h"
#include "bricklayer/simcam/render.h"
#include "bricklayer/simcam/simcam_node.h"
#include "bricklayer/stack_t.hpp"
#include "bricklayer/vision/vision_node.h"
#include "bricklayer/heartbeat_t.hpp"
#include "harness/recorder.h"
#include "harness/rig.h"
#include "harness/scratch.h"

using namespace bricklayer;
using namespace std::chrono_literals;
using calibration::CalibrateConfig;
using calibration::CalibrateNode;

namespace {

constexpr int64_t kStepUs = 2'000;  // the rig's step: simcam's 30 Hz frames land within 2 ms of their time

// A scenario of these blocks standing still for ten minutes, mild nuisance.
std::string scenario(const harness::ScratchDir& dir, const std::string& name,
                     const std::vector<std::tuple<int, int, double>>& blocks) {
  nlohmann::json list = nlohmann::json::array();
  for (auto [id, row, x] : blocks) list.push_back({{"id", id}, {"row", row}, {"x", x}});
  const std::string path = dir / (name + ".json");
  harness::write_file(path, nlohmann::json{{"description", name},
                                           {"nuisance", "mild"},
                                           {"seed", 7},
                                           {"duration_s", 600},
                                           {"keyframes", nlohmann::json::array({{{"t", 0}, {"blocks", list}}})}}
                                .dump());
  return path;
}

// CalibrateNode with the real simcam (mounting `setup_seed`) and projection nodes, to its finish; its last
// heartbeat.
heartbeat_t run_calibrate(const CalibrateConfig& config, const std::string& scenario_path, int64_t setup_seed) {
  harness::Rig rig(kStepUs);
  simcam::SimcamConfig camera;
  camera.scenario = scenario_path;
  camera.setup_seed = setup_seed;
  rig.add<simcam::SimcamNode>(camera);
  projection::ProjectionConfig projector;
  projector.headless = true;
  projector.mute = true;
  rig.add<projection::ProjectionNode>(projector);
  auto& node = rig.add<CalibrateNode>(config);
  REQUIRE(rig.run_until([&] { return node.finished(); }, 120s));
  rig.settle();
  INFO("calibrate status: " << node.status());
  REQUIRE(node.exit_code() == 0);
  return node.heartbeat();
}

// The scale step's ruler as the operator lays it: four blocks apart on the bottom row, each standing (its middle
// over the surface), and with `top` > 0 a tower on the blocks at -3.4 and -0.7 up to row `top`.
std::vector<std::tuple<int, int, double>> ruler(int top) {
  std::vector<std::tuple<int, int, double>> blocks = {{1, 0, -4.6}, {2, 0, -3.4}, {3, 0, -2.1}, {4, 0, -0.7}};
  int id = 5;
  for (int row = 1; row <= top; ++row) {
    const double jitter = 0.03 * ((row * 7) % 5 - 2) / 2.0;
    blocks.push_back({id++, row, -3.4 + jitter});
    blocks.push_back({id++, row, -0.7 - jitter});
  }
  return blocks;
}

// A stepped overhang pile: a column stepping out by half a block per row from the bottom row's -1.0 to
// row 9's +3.5 (x is a block's left end; the right end of the top one is at 4.5), and a second one stepping
// out from 0.0 to +4.5 on the rows above 1 (right end 5.5), next to it; blocks far left on rows 0 and 4
// for the other side. Vision needs no balance: the blocks are where the test says.
core::Stack stepped_pile() {
  core::Stack s;
  int64_t id = 1;
  for (int row = 0; row <= 9; ++row) s.blocks.push_back({id++, row, -1.0 + 0.5 * row});
  for (int row = 2; row <= 9; ++row) s.blocks.push_back({id++, row, 0.0 + 0.5 * row + 0.05});
  s.blocks.push_back({id++, 0, -4.2});
  s.blocks.push_back({id++, 4, -4.6});
  return s;
}

// As simcam publishes frames: JPEG at quality 90.
image_t jpeg_image(const cv::Mat& bgr, int64_t number) {
  return frames::encode_image(bgr, image_t::FORMAT_JPEG, 1000 + number * 33333, number, "test", 90);
}

struct Coverage {
  int blocks = 0, covered = 0, unmatched = 0, visible = 0;
  double worst_ratio = 0.0;   // largest |x - truth| / x_uncertainty
  double widest = 0.0;        // largest x_uncertainty
  double width_sum = 0.0;     // sum of the x_uncertainty of the blocks measured
  double worst_error = 0.0;   // largest |x - truth|
  double far_x = -1e9;        // the farthest true x (left end) among the blocks measured
  int top_row = 0;            // the highest row among the blocks measured
};

// VisionNode given `calibration`, on `frames` frames of the pile rendered through the mounting; every block
// published from the third frame on (the temporal filter has confirmed them) is compared with simcam's truth.
Coverage vision_coverage(const calibration_t& calibration, int64_t setup_seed, int frames) {
  const simcam::CameraSetup camera = simcam::CameraSetup::random(static_cast<uint64_t>(setup_seed));
  const simcam::ProjectorSetup projector = simcam::ProjectorSetup::random(static_cast<uint64_t>(setup_seed));
  const simcam::Renderer renderer(camera, projector);
  const core::Stack pile = stepped_pile();
  harness::Rig rig;
  rig.add<vision::VisionNode>(vision::VisionConfig{});
  const std::string images = channel(kImageChannel), stacks = channel(kStackChannel);
  auto& rec = rig.record({stacks});
  rig.publish(channel(kCalibrationChannel), calibration);
  Coverage c;
  for (int f = 0; f < frames; ++f) {
    simcam::Nuisance n = simcam::Nuisance::level(1);  // mild: blur, noise, a shadow, as the calibration saw
    n.layout_seed = 11;
    n.time_s = f / 30.0;
    const simcam::Rendered r = renderer.render(pile, n, nullptr, 5000 + static_cast<uint64_t>(f));
    rig.publish(images, jpeg_image(r.bgr, f));
    const auto s = rec.wait_for<stack_t>(stacks, [f](const stack_t& m) { return m.frame_number == f; }, 100ms);
    REQUIRE(s);
    if (f < 2) continue;
    for (const simcam::TrueBlock& t : r.truth) c.visible += t.visible;
    for (const block_t& b : s->blocks) {
      const simcam::TrueBlock* truth = nullptr;
      for (const simcam::TrueBlock& t : r.truth)
        if (t.row == b.row && (!truth || std::abs(b.x - t.x) < std::abs(b.x - truth->x))) truth = &t;
      if (!truth || std::abs(b.x - truth->x) > 0.6) {  // not a block simcam drew (0.6: half a block and more)
        ++c.unmatched;
        continue;
      }
      const double error = std::abs(b.x - truth->x);
      ++c.blocks;
      c.covered += error <= b.x_uncertainty;
      c.worst_ratio = std::max(c.worst_ratio, b.x_uncertainty > 0 ? error / b.x_uncertainty : 1e9);
      c.widest = std::max(c.widest, b.x_uncertainty);
      c.width_sum += b.x_uncertainty;
      c.worst_error = std::max(c.worst_error, error);
      c.far_x = std::max(c.far_x, truth->x);
      c.top_row = std::max(c.top_row, truth->row);
    }
  }
  return c;
}

}  // namespace

TEST_CASE("on a mounting scaled by --scale-from-blocks, vision's published x uncertainty covers every block of a stepped overhang pile far from the ruler") {
  // Simcam's random mountings 4 (the calibrate node test's), 7 and 11 (of 1-12 tried, the largest error /
  // x_uncertainty, 0.68, and the largest error, 0.078 at x 4.55 row 9): projectors off square by a few percent,
  // cameras that see the board out to x 5.5. Measured on 1-12: every block covered, largest ratio 0.68, widest
  // interval 0.115.
  for (const int64_t seed : {int64_t{4}, int64_t{7}, int64_t{11}}) {
    DYNAMIC_SECTION("mounting " << seed) {
      harness::ScratchDir dir("scale-vision-coverage");
      CalibrateConfig config;
      config.output = dir / "calibration.json";
      config.timeout = 2;
      run_calibrate(config, scenario(dir, "empty", {}), seed);
      const calibration_t before = board::load_calibration(config.output);
      config.scale_from_blocks = true;
      run_calibrate(config, scenario(dir, "ruler", {{1, 0, -3.4}, {2, 0, -1.9}, {3, 0, -0.6}, {4, 0, 0.7}}), seed);
      const calibration_t after = board::load_calibration(config.output);
      REQUIRE(after.board_x_accuracy[0] > 0);  // the scale step corrected the frame and stated its bound

      const int frames = 8;
      const Coverage c = vision_coverage(after, seed, frames);
      std::printf("mounting %lld, scaled: %d blocks, %d covered, largest |dx| %.4f, largest |dx| / x_uncertainty %.3f, "
                  "widest x_uncertainty %.4f (farthest x %.2f, top row %d)\n",
                  static_cast<long long>(seed), c.blocks, c.covered, c.worst_error, c.worst_ratio, c.widest, c.far_x,
                  c.top_row);
      INFO(c.covered << " of " << c.blocks << " covered; largest |dx| " << c.worst_error << ", largest ratio "
                     << c.worst_ratio << ", widest " << c.widest << ", " << c.unmatched << " unmatched");
      CHECK(c.visible >= static_cast<int>(stepped_pile().blocks.size()) * (frames - 2) * 9 / 10);  // in view
      CHECK(c.blocks >= c.visible * 9 / 10);  // (nearly) every visible block in every frame measured
      CHECK(c.unmatched == 0);
      CHECK(c.far_x >= 4.0);  // the blocks far from the ruler were measured
      CHECK(c.top_row == 9);
      CHECK(c.covered == c.blocks);
      // Narrow enough to judge a knife edge: the stated bound at x 5, row 9 is ~0.09 (the calibration README).
      CHECK(c.widest < 0.15);

      // The same frames through the calibration before the scale step: its error is not covered.
      const Coverage uncorrected = vision_coverage(before, seed, frames);
      // (Vision finds fewer blocks there too: with the scale a few percent off its line pairing misses some.)
      std::printf("mounting %lld, as calibrated: %d of %d visible blocks covered\n", static_cast<long long>(seed),
                  uncorrected.covered, uncorrected.visible);
      CHECK(uncorrected.covered < uncorrected.visible / 2);
    }
  }
}

TEST_CASE("with towers in the scale step's ruler, vision's x uncertainty still covers every block of the stepped pile and is narrower than with the bottom row alone") {
  // The same chain, the ruler as the status page asks for it: four blocks standing on the bottom row (-4.6 ..
  // -0.7) and towers on two of them up to row 9, standing still. The second pass measures every row, the
  // stated bound's vertical term is the rows' (board_x_accuracy.h), so vision's intervals on the pile's upper
  // rows (up to row 9, x 4.55) shrink. Measured (mountings 4 and 11; 7 alike, left out for the sanitizers'
  // time): every block covered both ways; largest error / x_uncertainty 0.55 and 0.21 with the towers; the
  // widest interval 0.055 and 0.066 against 0.084 and 0.166 with the bottom row alone, the mean 0.034 and 0.041
  // against 0.049 and 0.094.
  for (const int64_t seed : {int64_t{4}, int64_t{11}}) {
    DYNAMIC_SECTION("mounting " << seed) {
      harness::ScratchDir dir("scale-vision-towers");
      CalibrateConfig config;
      config.output = dir / "calibration.json";
      config.timeout = 2;
      run_calibrate(config, scenario(dir, "empty", {}), seed);
      const std::string calibrated = harness::read_file(config.output);
      config.scale_from_blocks = true;
      const heartbeat_t towers_beat = run_calibrate(config, scenario(dir, "towers", ruler(9)), seed);
      CHECK(harness::heartbeat_value(towers_beat, "scale_highest_row") == 9.0);  // the second pass ran
      const calibration_t towers = board::load_calibration(config.output);
      harness::write_file(config.output, calibrated);
      const heartbeat_t bottom_beat = run_calibrate(config, scenario(dir, "bottom", ruler(0)), seed);
      CHECK_FALSE(harness::heartbeat_value(bottom_beat, "scale_highest_row").has_value());  // the first pass alone
      const calibration_t bottom = board::load_calibration(config.output);
      REQUIRE(towers.board_x_accuracy[0] > 0);
      REQUIRE(bottom.board_x_accuracy[0] > 0);

      const int frames = 8;
      const Coverage t = vision_coverage(towers, seed, frames), b = vision_coverage(bottom, seed, frames);
      std::printf("mounting %lld, towers: %d of %d covered, largest |dx| %.4f, ratio %.3f, widest %.4f, mean %.4f; bottom row "
                  "alone: %d of %d, largest |dx| %.4f, ratio %.3f, widest %.4f, mean %.4f\n",
                  static_cast<long long>(seed), t.covered, t.blocks, t.worst_error, t.worst_ratio, t.widest,
                  t.width_sum / std::max(1, t.blocks), b.covered, b.blocks, b.worst_error, b.worst_ratio, b.widest,
                  b.width_sum / std::max(1, b.blocks));
      INFO("towers: " << t.covered << " of " << t.blocks << " covered, largest ratio " << t.worst_ratio << ", widest " << t.widest
                      << "; bottom row alone: " << b.covered << " of " << b.blocks << ", widest " << b.widest);
      CHECK(t.blocks >= t.visible * 9 / 10);
      CHECK(t.unmatched == 0);
      CHECK(t.far_x >= 4.0);
      CHECK(t.top_row == 9);
      CHECK(t.covered == t.blocks);
      CHECK(b.covered == b.blocks);
      CHECK(t.widest < 0.8 * b.widest);
      CHECK(t.width_sum / t.blocks < b.width_sum / std::max(1, b.blocks));
    }
  }
}
