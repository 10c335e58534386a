// bricklayer-vision's node: blocks from camera frames.
//
// Subscribes: BL_IMAGE (image_t: JPEG, PNG, GRAY8 or BGR8; newest wins) unless a direct source is given
//             (--camera N, --video FILE, --images DIR), BL_CALIBRATION (calibration_t: rectification,
//             colour mixing), BL_PROJECTOR (projector_state_t: what the projector shows, whose red/blue
//             leakage into green is subtracted).
// Publishes:  BL_STACK (stack_t, one per frame, carrying the frame's utime and frame_number;
//             STATUS_NO_FRAME for a corrupt, empty, truncated or wrongly sized frame; never a stack
//             bricklayer-prediction rejects: see publishable.h; none at all with --require-calibration
//             until a calibration is loaded or arrives), BL_TIMING (timing_t, stage "detect"),
//             Every block carries its position uncertainty (block_t.x_uncertainty, position_uncertainty.h).
//             BL_HEARTBEAT (counters; values: blocks, lines, rejected_wide, rejected_faint, detect_ms,
//             uncertainty_median (block lengths, over the published blocks of the last stack), and
//             totals moved_total, dropped_overlap_total, dropped_border_total; status "no frames for N s"
//             when BL_IMAGE falls silent).
// Offline:    --images DIR --json prints one bricklayer-predict input line per image (name order),
//             without the bus and without temporal filtering.
#pragma once

#include <memory>
#include <optional>
#include <string>

#include "bricklayer/calibration_t.hpp"
#include "bricklayer/detection/detector.h"
#include "bricklayer/frames/frame_source.h"
#include "bricklayer/image_t.hpp"
#include "bricklayer/projector_state_t.hpp"
#include "bricklayer/runtime/config.h"
#include "bricklayer/runtime/node.h"
#include "bricklayer/vision/position_uncertainty.h"
#include "bricklayer/vision/publishable.h"
#include "bricklayer/vision/temporal_filter.h"

namespace bricklayer::vision {

struct VisionConfig {
  std::string board;        // board geometry JSON used until a calibration arrives
  std::string calibration;  // calibration file to start with
  bool require_calibration = false;
  std::string camera, video, images;  // at most one direct source
  double rate = 30;
  bool json = false;
  bool no_filter = false;
  std::string confirm = "2/3";
  int hold = 3;
  double deadband = 0.01;
  double min_uncertainty = 0.0;

  template <typename Visitor>
  void visit(Visitor& v) {
    v(runtime::param("board", board,
                     "board geometry JSON {edge_x_px, surface_y_px, block_length_px, block_height_px} used until a "
                     "calibration arrives (default: the shared default setup)")
          .existing_file());
    v(runtime::param("calibration", calibration,
                     "calibration file written by bricklayer-calibrate (calibration.json, loaded strictly) to start with")
          .existing_file());
    v(runtime::param("require-calibration", require_calibration,
                     "publish no stacks until a calibration is loaded (--calibration) or arrives on BL_CALIBRATION "
                     "(the exhibit's profiles: bricklayer-calibrate --serve)"));
    v(runtime::param("camera", camera, "read frames from this V4L2 camera (index or /dev/videoN) instead of BL_IMAGE"));
    v(runtime::param("video", video, "read frames from this video file instead of BL_IMAGE").existing_file());
    v(runtime::param("images", images, "read frames from the images in this folder (name order) instead of BL_IMAGE")
          .existing_folder());
    v(runtime::param("rate", rate, "frames per second for --video and --images").above_up_to(0, 1000));
    v(runtime::param("json", json,
                     "with --images: print one bricklayer-predict input line per image and exit (no bus, no filter)"));
    v(runtime::param("no-filter", no_filter, "publish raw detections (no temporal filter)"));
    v(runtime::param("confirm", confirm, "temporal filter: seen in N of the last M frames, as N/M").must(confirm_rule));
    v(runtime::param("hold", hold, "temporal filter: frames a lost block is held").range(0, 1000));
    v(runtime::param("deadband", deadband, "temporal filter: x changes smaller than this (block lengths) are not published")
          .range(0, 1));
    v(runtime::param("min-uncertainty", min_uncertainty,
                     "smallest position uncertainty (block lengths, half-width) any published block carries: for what "
                     "vision cannot see in one camera's frames (e.g. a board that is not flat); the calibration's "
                     "residual is a floor already")
          .range(0, 0.05));
  }

  // "N/M" with 1 <= N <= M; "" when it is one, else why not.
  static std::string confirm_rule(const std::string& text);
  // The temporal filter these settings describe; throws std::invalid_argument when it would not work.
  TemporalFilterConfig filter() const;
};

class VisionNode final : public runtime::Node {
 public:
  using Config = VisionConfig;
  static constexpr const char* kProgram = "bricklayer-vision";
  static constexpr const char* kSummary =
      "Blocks from camera frames: image_t on BL_IMAGE (or a camera, video or folder) -> stack_t on BL_STACK.";
  // An image channel silent this long turns the status to "no frames for N s".
  static constexpr double kStaleAfterS = 3.0;

  // Throws std::invalid_argument for a bad configuration, std::runtime_error for a calibration file or
  // a direct source that cannot be read.
  VisionNode(const Config& config, runtime::Bus& bus);

  // Rules across fields (at most one direct source, --json needs --images, the filter's settings).
  static void check(const Config& config);
  // --images DIR --json: the offline mode, without a bus.
  static std::optional<int> before_bus(const Config& config);

 private:
  void on_image(const image_t& image);
  void on_calibration(const calibration_t& calibration);
  void on_projector(const projector_state_t& state);
  void tick() override;
  void read_source();
  // Each block's published half-width: its measurement, the filter's spread and lag, the two floors.
  double block_uncertainty(const detection::DetectedBlock& block, double measured, double temporal, double lag) const;
  void process(const cv::Mat& frame, int64_t utime, int64_t frame_number, int64_t received_utime,
               const std::string& decode_error, int64_t elapsed_before_us);

  std::optional<calibration_t> calibration_;  // before detector_: the calibration file fills both
  detection::Detector detector_;
  TemporalFilter filter_;
  bool use_filter_;
  std::unique_ptr<frames::FrameSource> source_;
  int64_t source_period_us_ = 0;
  int64_t next_frame_utime_ = 0;
  int64_t source_frames_ = 0;
  int64_t unreadable_seen_ = 0;
  bool source_done_ = false;
  bool require_calibration_;
  double min_uncertainty_;
  int64_t frames_seen_ = 0;
  PublishCounts published_;
  std::string stack_channel_, timing_channel_;
};

}  // namespace bricklayer::vision
