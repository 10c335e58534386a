// bricklayer-calibrate's node: automatic camera-to-projector registration, colour mixing, drift check
// and board scale from blocks, on the runtime (runtime/node.h), so the same node runs live (LcmBus)
// and on the in-process rig, and reads the time only from its bus's clock (step timeouts, the
// republication period, the self-check schedule).
//
// Subscribes: BL_PROJECTOR (projector_state_t: which command the projector shows now),
//             BL_IMAGE (image_t: camera frames), BL_STACK (stack_t: is the board empty, --serve),
//             BL_COMMAND (command_t SELF_CHECK and CALIBRATE, --serve).
// Publishes:  BL_COMMAND (command_t SHOW_PATTERN / CLEAR_PATTERN, each with a fresh sequence number),
//             BL_CALIBRATION (calibration_t), BL_HEARTBEAT (status "step k of n: ...", values drift_px,
//             drift_max_px, reprojection_error_*, and the --scale-from-blocks figures; with --serve also
//             calibration_age_s, calibrations_done, calibrations_failed, calibrate_commands_ignored).
//
// Modes:
//   (default)     show every calibration pattern, compute, reject (exit 1) or save --output and
//                 publish on BL_CALIBRATION (exit 0).
//   --self-check  load --output, project the self-check markers once, report the drift (exit 0, or
//                 3 when it exceeds --drift-threshold).
//   --write-default  write the uncalibrated default setup to --output and exit (no bus).
//   --scale-from-blocks  load --output, measure how long blocks standing apart on the bottom row read in
//                 its board frame over --scale-frames camera frames (detection/block_scale.h: the board's
//                 scale comes from the projector and is off when the projector is not mounted square),
//                 correct the board frame (scale and keystone along the board, and from the lean of the
//                 blocks' end lines its shear and vertical keystone: calibration/line_lean.h), then measure
//                 the same frames again in the corrected frame on every row up to --scale-max-row (blocks
//                 standing in towers on them give the vertical keystone from their lengths:
//                 calibration/board_frame_refit.h) and correct it once more, save and publish (exit 0), or
//                 say what to fix (exit 1). Only frames that count --scale-blocks bottom-row blocks
//                 (default: the count most frames agree on) are measured.
//   --serve       load --output, publish it (again every --republish seconds, so late starters catch
//                 up; re-read when the file changes, e.g. after --scale-from-blocks; a missing or bad
//                 file is waited for, not fatal: the launcher starts --serve before anyone calibrated),
//                 and run the self-check on every SELF_CHECK command while the board is empty (and
//                 every --self-check-every seconds once the board has been empty --empty-for seconds).
//                 On CALIBRATE (the operator's status page) it runs the default mode's calibration, the same
//                 steps and computation, once the board has been empty --empty-for seconds (waiting at most
//                 --calibrate-wait seconds for that); accepted, it saves --output and serves the new one;
//                 rejected, it keeps serving the old one and says why in its status. A CALIBRATE while one
//                 waits or runs is counted (calibrate_commands_ignored) and said, not queued again. CALIBRATE
//                 with argument "scale-from-blocks" runs the --scale-from-blocks step on the served
//                 calibration instead, at once (it needs the blocks on the board), and serves the result.
// For every pattern: send SHOW_PATTERN, wait for projector_state_t echoing its sequence, then use the
// camera frame received --skip-frames frames after the echo (frames already in flight show the
// previous pattern). A step without echo or frame within --timeout seconds (bus clock) is sent once
// more, then the run fails with a counted error naming what is missing.
#pragma once

#include <cstdint>
#include <filesystem>
#include <memory>
#include <optional>
#include <string>
#include <vector>

#include "bricklayer/calibration/calibrator.h"
#include "bricklayer/calibration/line_lean.h"
#include "bricklayer/calibration_t.hpp"
#include "bricklayer/command_t.hpp"
#include "bricklayer/detection/block_scale.h"
#include "bricklayer/image_t.hpp"
#include "bricklayer/projector_state_t.hpp"
#include "bricklayer/runtime/config.h"
#include "bricklayer/runtime/node.h"
#include "bricklayer/stack_t.hpp"

namespace bricklayer::calibration {

struct CalibrateConfig {
  std::string output = "calibration.json";
  std::string board;
  std::string projector_size = "1024x768";
  double max_error_px = 1.0;
  double max_point_error_px = 1.25;
  double timeout = 5;
  int skip_frames = 3;
  int colour_drive = 80;
  double drift_threshold = 2.0;
  double republish = 5;
  bool no_shelf = false;
  bool self_check = false;
  bool serve = false;
  double self_check_every = 0;
  double empty_for = 5;
  double calibrate_wait = 60;
  bool write_default = false;
  bool scale_from_blocks = false;
  int scale_frames = 10;
  int scale_blocks = 0;
  double scale_max_residual = 0.01;
  double scale_min_change = 0.025;  // the vertical keystone from bottom-row leans: up to 0.002 / block length (bench)
  int scale_max_row = 12;

  template <typename Visitor>
  void visit(Visitor& v) {
    v(runtime::param("output", output, "calibration file to write (or to read with --self-check / --serve)")
          .must([](const std::string& s) { return s.empty() ? std::string("must name a file") : std::string(); }));
    v(runtime::param("board", board, "BoardGeometry JSON in rectified pixels (default: the built-in default board)")
          .existing_file());
    v(runtime::param("projector-size", projector_size,
                     "projector resolution, WIDTHxHEIGHT (as bricklayer-projection --width/--height)")
          .must(projector_size_rule));
    v(runtime::param("max-error-px", max_error_px,
                     "reject a calibration whose mean reprojection error exceeds this, projector pixels")
          .above(0));
    v(runtime::param("max-point-error-px", max_point_error_px,
                     "reject a calibration whose largest reprojection error (one marker) exceeds this, projector pixels")
          .above(0));
    v(runtime::param("timeout", timeout,
                     "seconds to wait for the projector's echo or a camera frame before retrying a step once")
          .above_up_to(0, 3600));
    v(runtime::param("skip-frames", skip_frames, "camera frames to discard after the projector confirms a pattern")
          .range(0, 100));
    v(runtime::param("colour-drive", colour_drive,
                     "projector level for the red, green and blue frames (lower if the camera saturates)")
          .range(1, 255));
    v(runtime::param("drift-threshold", drift_threshold, "self-check: warn above this mean drift, projector pixels")
          .above(0));
    v(runtime::param("republish", republish, "--serve: seconds between re-publications of the calibration").above(0));
    v(runtime::param("no-shelf", no_shelf,
                     "do not anchor the board frame on the detected shelf; use --board exactly as given"));
    v(runtime::param("self-check", self_check,
                     "check the saved calibration for drift once and exit (3 = drift above threshold)"));
    v(runtime::param("serve", serve,
                     "publish the saved calibration and self-check on command SELF_CHECK when the board is empty"));
    v(runtime::param("self-check-every", self_check_every,
                     "--serve: also self-check automatically this often, seconds, once the board has been empty "
                     "--empty-for seconds (0 = only on command)")
          .at_least(0));
    v(runtime::param("empty-for", empty_for,
                     "--serve: seconds of empty board before an automatic self-check or a commanded calibration")
          .at_least(0));
    v(runtime::param("calibrate-wait", calibrate_wait,
                     "--serve: a CALIBRATE command waits at most this long, seconds, for the board to have been empty "
                     "--empty-for seconds; then it is dropped and the status says why")
          .above(0));
    v(runtime::param("write-default", write_default,
                     "write the uncalibrated default setup (modules/board) to --output and exit"));
    v(runtime::param("scale-from-blocks", scale_from_blocks,
                     "correct the saved calibration's board scale from 3+ blocks standing apart on the bottom row "
                     "(best with a tower of blocks on two of them, up to row 9 or higher), save, publish and exit"));
    v(runtime::param("scale-frames", scale_frames, "--scale-from-blocks: camera frames to measure").range(1, 1000));
    v(runtime::param("scale-blocks", scale_blocks,
                     "--scale-from-blocks: how many blocks stand apart on the bottom row (frames counting otherwise "
                     "are left out); 0 = the count most frames agree on")
          .range(0, 100));
    v(runtime::param("scale-max-residual", scale_max_residual,
                     "--scale-from-blocks: refuse when the block lengths disagree with the fitted correction by more "
                     "than this fraction (RMS)")
          .open_range(0, 1));
    auto min_change = runtime::param("scale-min-change", scale_min_change,
                                     "--scale-from-blocks: leave the calibration as it is when the correction moves no "
                                     "point within 4 block lengths of the edge by more than this, block lengths")
                          .range(0, 1);
    min_change.max_open = true;  // [0, 1)
    v(min_change);
    v(runtime::param("scale-max-row", scale_max_row,
                     "--scale-from-blocks: the second pass measures blocks standing apart in their row on rows 0..this "
                     "(towers of blocks on the bottom row's blocks: the scale up the board measured, not extrapolated)")
          .range(0, 30));
  }

  // "WIDTHxHEIGHT" with both in 16..16384: "" when it is one, else why not.
  static std::string projector_size_rule(const std::string& text);
  // The calibration computation's options these settings describe (loads --board); throws
  // std::runtime_error for a board file that does not load.
  CalibrationOptions calibration_options() const;
};

class CalibrateNode final : public runtime::Node {
 public:
  using Config = CalibrateConfig;
  static constexpr const char* kProgram = "bricklayer-calibrate";
  static constexpr const char* kSummary =
      "Registers camera and projector automatically (patterns via bricklayer-projection, frames from the camera), "
      "measures the colour mixing, saves and publishes the calibration; or checks it for drift.";
  static constexpr int kExitRejected = 1;
  static constexpr int kExitDrift = 3;

  enum class Mode { kCalibrate, kSelfCheck, kServe, kScale };
  // CALIBRATE's argument for the scale step (--scale-from-blocks) instead of a full calibration.
  static constexpr const char* kScaleFromBlocks = "scale-from-blocks";

  // Rules across fields (the modes exclude each other).
  static void check(const Config& config);
  // --write-default: writes the default calibration without a bus; exit code 0.
  static std::optional<int> before_bus(const Config& config);

  // Throws std::invalid_argument for a bad configuration, std::runtime_error for a board file or (but
  // with --serve, which waits for it) a calibration file that does not load.
  CalibrateNode(const Config& config, runtime::Bus& bus);
  ~CalibrateNode() override;

  Mode mode() const { return mode_; }
  // Whether the run is over (a calibration saved or rejected, a self-check done, ...): the node has
  // stopped and exit_code() is the program's exit code. --serve never finishes by itself.
  bool finished() const { return finished_; }
  int exit_code() const { return exit_code_; }
  // The calibration being served or checked (the one just computed after a calibration run).
  const std::optional<calibration_t>& calibration() const { return calibration_; }
  // --serve: calibrations run on CALIBRATE and accepted; not done (rejected, failed, never started for
  // want of an empty board); commands not obeyed because one was already waiting or running. The
  // heartbeat carries them as calibrations_done, calibrations_failed, calibrate_commands_ignored.
  int64_t calibrations_done() const { return calibrations_done_; }
  int64_t calibrations_failed() const { return calibrations_failed_; }
  int64_t calibrate_commands_ignored() const { return calibrate_ignored_; }

 protected:
  void tick() override;

 private:
  class PatternCapture;
  struct ScaleFrame {
    int blocks = 0;
    std::vector<detection::EndLines> lines;
    std::vector<LineLean> leans;
    cv::Mat bgr, projector_image;  // kept for the second pass (board_frame_refit.h)
  };

  void on_projector(const projector_state_t& s);
  void on_image(const image_t& m);
  void on_stack(const stack_t& s);
  void on_command(const command_t& c);
  void start_self_check();
  // The calibration's patterns, as the default mode shows them (calibration_steps).
  void start_calibration();
  std::unique_ptr<PatternCapture> make_capture(std::vector<CalibrationStep> steps, std::string status_prefix);
  void on_calibrate_command(const command_t& c);
  void start_scale();
  void end_scale(int code);
  // --serve: a waiting CALIBRATE starts, or is dropped after --calibrate-wait.
  void serve_calibrate_request(int64_t t);
  // --serve: a calibration that did not happen or was rejected: counted, said, the old one kept.
  void calibration_failed(const std::string& why);
  void before_heartbeat() override;
  void clear_pattern();
  void publish_calibration();
  void finish_calibration(const std::vector<cv::Mat>& frames);
  void finish_self_check(const cv::Mat& frame);
  void measure_scale(const image_t& m);
  void finish_scale();
  std::filesystem::file_time_type file_time() const;
  void reload_if_changed();
  void finish(int code);
  int64_t next_sequence();

  Config config_;
  CalibrationOptions options_;
  Mode mode_;
  std::string command_channel_, calibration_channel_;
  std::unique_ptr<PatternCapture> capture_;
  bool capture_calibrates_ = false;  // capture_ is a calibration's patterns (else the self-check's)
  std::optional<int64_t> calibrate_asked_utime_;  // --serve: a CALIBRATE waiting for the empty board
  bool stack_seen_ = false;
  int64_t calibrations_done_ = 0, calibrations_failed_ = 0, calibrate_ignored_ = 0;
  std::optional<calibration_t> calibration_;
  bool board_empty_ = false;
  int64_t empty_since_utime_ = 0;
  int64_t last_check_utime_ = INT64_MIN / 2;
  int64_t last_publish_utime_ = INT64_MIN / 2;
  int64_t last_sequence_ = 0;
  std::filesystem::file_time_type file_time_{};
  std::unique_ptr<detection::BlockScaleMeter> scale_;
  cv::Mat scale_projector_image_;  // what the projector shows now (--scale-from-blocks with the game running)
  int64_t scale_started_utime_ = 0;
  int scale_seen_ = 0;    // frames received in --scale-from-blocks
  int scale_frames_ = 0;  // frames measured
  std::vector<ScaleFrame> scale_by_frame_;  // what each frame measured (end lines and their leans)
  bool finished_ = false;
  int exit_code_ = 0;
};

}  // namespace bricklayer::calibration
