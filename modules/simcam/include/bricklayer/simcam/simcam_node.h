// bricklayer-simcam's node: a simulated camera, so the whole exhibit runs without hardware.
//
// Plays a scenario (launch/scenarios/*.json: a scripted player's stacks over time) through the render
// library and publishes what a webcam behind the board would capture.
// Subscribes: BL_PROJECTOR (projector_state_t): what the projector shows now; its light is drawn into
//             every following frame, leaking into green through the colour mixing matrix (closed loop).
// Publishes:  BL_IMAGE (image_t, JPEG or PNG) at --fps, frame numbers from 0, capture utime = the bus
//             clock (the wall clock on the live bus).
//             BL_TRUTH (stack_t) the scenario's true stack for each frame (same utime and frame number),
//             so end-to-end tests and benchmarks can compare what vision saw with what was there.
//             BL_HEARTBEAT once a second.
// Frames are a pure function of (scenario, seed, frame number, projector image): scenario time is
// frame_number / fps, and the bus clock only paces publication. When the scenario (or --frames) ends
// the node stops: its run() returns 0.
#pragma once

#include <cstdint>
#include <string>

#include <opencv2/core.hpp>

#include "bricklayer/projector_state_t.hpp"
#include "bricklayer/runtime/config.h"
#include "bricklayer/runtime/node.h"
#include "bricklayer/simcam/render.h"
#include "bricklayer/simcam/scenario.h"
#include "bricklayer/stack_t.hpp"

namespace bricklayer::simcam {

struct SimcamConfig {
  std::string scenario;
  double fps = 30.0;
  bool loop = false;
  int64_t frames = 0;
  std::string format = "jpeg";
  int jpeg_quality = 90;
  int64_t seed = -1;
  std::string nuisance;
  int64_t setup_seed = 0;
  bool no_projector = false;

  template <typename Visitor>
  void visit(Visitor& v) {
    v(runtime::param("scenario", scenario, "scenario file (launch/scenarios/*.json); required")
          .existing_file()
          .must([](const std::string& s) { return s.empty() ? std::string("is required (see launch/scenarios/)") : std::string(); }));
    v(runtime::param("fps", fps, "frames per second").range(1, 240));
    v(runtime::param("loop", loop, "start the scenario again when it ends (else exit)"));
    v(runtime::param("frames", frames, "stop after this many frames (0: no limit)").at_least(0));
    v(runtime::param("format", format, "frame encoding").one_of({"jpeg", "png"}));
    v(runtime::param("jpeg-quality", jpeg_quality, "JPEG quality").range(1, 100));
    v(runtime::param("seed", seed, "override the scenario's seed (-1: the scenario's own)").at_least(-1));
    v(runtime::param("nuisance", nuisance, "override the scenario's nuisance level (empty: the scenario's own)")
          .one_of({"", "clean", "mild", "strong", "harsh"}));
    v(runtime::param("setup-seed", setup_seed, "0: the default camera/projector setup; N: a random setup (for calibration)")
          .at_least(0));
    v(runtime::param("no-projector", no_projector, "ignore BL_PROJECTOR (no projected light in the frames)"));
  }
};

// The scenario's true stack as a stack_t (block lengths, the true corners in camera pixels).
stack_t to_truth_message(const core::Stack& stack, const std::vector<TrueBlock>& truth);

class SimcamNode final : public runtime::Node {
 public:
  using Config = SimcamConfig;
  static constexpr const char* kProgram = "bricklayer-simcam";
  static constexpr const char* kSummary =
      "A simulated camera: renders a scenario's stacks into realistic frames on BL_IMAGE.";

  // Throws std::invalid_argument for a bad configuration, std::runtime_error for a scenario file that
  // does not load (naming the file, key frame and problem).
  SimcamNode(const Config& config, runtime::Bus& bus);

  int64_t frames_published() const { return frame_number_; }

 private:
  void on_projector(const projector_state_t& p);
  void tick() override;
  void finish(const char* why);

  Config config_;
  Scenario scenario_;
  std::string scenario_name_;
  Renderer renderer_;
  std::string image_channel_, truth_channel_;
  cv::Mat projector_image_;
  int64_t frame_number_ = 0;
  int64_t start_utime_ = 0;
  bool finished_ = false;  // the scenario or the frame limit ended: nothing more to publish
};

}  // namespace bricklayer::simcam
