// bricklayer-calibrate: automatic camera-to-projector registration, colour mixing and drift check.
//
// Subscribes: BL_PROJECTOR (projector_state_t: which command the projector shows now),
//             BL_IMAGE (image_t: camera frames), BL_STACK (stack_t: is the board empty, --serve),
//             BL_COMMAND (command_t SELF_CHECK, --serve).
// Publishes:  BL_COMMAND (command_t SHOW_PATTERN / CLEAR_PATTERN, each with a fresh sequence number),
//             BL_CALIBRATION (calibration_t), BL_HEARTBEAT (status "step k of n: ...", value drift_px).
//
// Modes:
//   (default)     show every calibration pattern, compute, reject (exit 1) or save --output and
//                 publish on BL_CALIBRATION (exit 0).
//   --self-check  load --output, project the self-check markers once, report the drift (exit 0, or
//                 3 when it exceeds --drift-threshold).
//   --write-default  write the uncalibrated default setup to --output and exit.
//   --scale-from-blocks  load --output, measure how long blocks standing apart on the bottom row read in
//                 its board frame over --scale-frames camera frames (detection/block_scale.h: the board's
//                 scale comes from the projector and is off when the projector is not mounted square),
//                 correct the board frame (scale and keystone along the board, and from the lean of the
//                 blocks' end lines its shear and vertical keystone: calibration/line_lean.h), save and
//                 publish (exit 0), or say what to fix (exit 1). Only frames that count --scale-blocks
//                 blocks (default: the count most frames agree on) are measured.
//   --serve       load --output, publish it (again every --republish seconds, so late starters catch
//                 up; re-read when the file changes, e.g. after --scale-from-blocks; a missing or bad
//                 file is waited for, not fatal: the launcher starts --serve before anyone calibrated), and run the
//                 self-check on every SELF_CHECK command while the board is empty
//                 (and every --self-check-every seconds once the board has been empty --empty-for seconds).
// For every pattern: send SHOW_PATTERN, wait for projector_state_t echoing its sequence, then use the
// camera frame received --skip-frames frames after the echo (frames already in flight show the
// previous pattern). A step without echo or frame within --timeout seconds is sent once more, then
// the run fails with a message naming what is missing.
#include <opencv2/imgproc.hpp>

#include <cmath>
#include <deque>
#include <filesystem>
#include <map>
#include <memory>
#include <optional>
#include <sstream>
#include <string>
#include <vector>

#include "bricklayer/board/calibration_file.h"
#include "bricklayer/calibration/calibrator.h"
#include "bricklayer/patterns/patterns.h"
#include "bricklayer/calibration_t.hpp"
#include "bricklayer/command_t.hpp"
#include "bricklayer/board/board_geometry.h"
#include "bricklayer/common/channels.h"
#include "bricklayer/common/flags.h"
#include "bricklayer/common/lcm_url.h"
#include "bricklayer/common/log.h"
#include "bricklayer/common/module.h"
#include "bricklayer/image_t.hpp"
#include "bricklayer/projector_state_t.hpp"
#include "bricklayer/stack_t.hpp"
#include "bricklayer/calibration/line_lean.h"
#include "bricklayer/detection/block_scale.h"
#include "bricklayer/frames/image_codec.h"

namespace bricklayer {
namespace {

namespace cal = calibration;

constexpr int kExitRejected = 1;
constexpr int kExitDrift = 3;
constexpr double kScaleCheckHalfWidth = 4.0;  // block lengths either side of the edge a correction is judged over
constexpr double kScaleCheckHeight = 3.0;     // and the heights (block lengths above the surface, ~9 rows)

// A camera (or projector) frame as BGR, or empty when it cannot be decoded (counted as an error by the
// caller). Vision's decoder: it checks the sizes the message and the JPEG/PNG header declare before
// decoding (a 300-byte PNG declaring 30000x30000 is refused, not a 2.7 GB allocation) and is fuzzed.
cv::Mat decode_frame(const image_t& img) {
  std::string error;
  cv::Mat out = frames::decode_image(img, &error);
  if (!out.empty() && out.channels() == 1) cv::cvtColor(out, out, cv::COLOR_GRAY2BGR);
  if (!error.empty()) log::debug(error);
  return out;
}

cv::Size parse_size(const std::string& text) {
  int w = 0, h = 0;
  char x = 0;
  std::istringstream in(text);
  if (!(in >> w >> x >> h) || (x != 'x' && x != 'X') || w < 16 || h < 16 || w > 16384 || h > 16384) {
    throw FlagError("--projector-size: expected WIDTHxHEIGHT like 1024x768, got \"" + text + "\"");
  }
  return {w, h};
}

struct Options {
  std::string lcm_url;
  std::string output;
  cal::CalibrationOptions calibration;
  double timeout_s = 5.0;
  int skip_frames = 3;
  double drift_threshold_px = 2.0;
  double republish_s = 5.0;
  double self_check_every_s = 0.0;  // --serve: automatic self-check period (0 = only on command)
  double empty_for_s = 5.0;         // the board must have been empty this long for an automatic check
  int scale_frames = 10;            // --scale-from-blocks: camera frames measured
  int scale_blocks = 0;             // --scale-from-blocks: blocks placed (frames that count otherwise are left out); 0: the count most frames agree on
  double scale_max_residual = 0.01;  // --scale-from-blocks: largest RMS relative error of the fitted block lengths
  double scale_min_change = 0.02;    // --scale-from-blocks: corrections moving no point within 4 block lengths of
                                     // the edge by more than this are within the measurement's own bias
                                     // (blur: lengths up to 0.5% short) and are not applied
};

// Shows a list of patterns one at a time and collects one camera frame per pattern.
class PatternCapture {
 public:
  PatternCapture(Module& module, std::vector<cal::CalibrationStep> steps, const Options& options)
      : module_(module), steps_(std::move(steps)), options_(options) {}

  bool done() const { return next_ >= steps_.size() && !waiting_; }
  bool failed() const { return !failure_.empty(); }
  const std::string& failure() const { return failure_; }
  std::vector<cv::Mat> take_frames() { return std::move(frames_); }

  void on_projector_state(const projector_state_t& s) {
    if (waiting_ && !echoed_ && s.command_sequence == sequence_) {
      // Patterns come back at full size: a different size means the marker positions are wrong.
      const cv::Size expected = options_.calibration.projector_size;
      if (s.mode == projector_state_t::MODE_PATTERN && s.image.width > 0 &&
          (s.image.width != expected.width || s.image.height != expected.height)) {
        failure_ = "the projector shows " + std::to_string(s.image.width) + "x" + std::to_string(s.image.height) +
                   " but --projector-size is " + std::to_string(expected.width) + "x" + std::to_string(expected.height) +
                   ": pass the projector's resolution";
        return;
      }
      echoed_ = true;
      frames_seen_ = 0;
      log::debug("projector shows sequence ", sequence_);
    }
  }

  void on_frame(const image_t& img) {
    if (!waiting_ || !echoed_) return;
    if (++frames_seen_ <= options_.skip_frames) return;
    cv::Mat bgr = decode_frame(img);
    if (bgr.empty()) {
      ++module_.counters().errors;
      log::warn("camera frame ", img.frame_number, " could not be decoded (format ", img.format, ", ", img.width, "x",
                img.height, "); waiting for the next");
      return;
    }
    if (!frames_.empty() && bgr.size() != frames_.front().size()) {
      ++module_.counters().errors;
      log::warn("camera frame size changed during calibration; ignoring the frame");
      return;
    }
    frames_.push_back(std::move(bgr));
    waiting_ = false;
    ++next_;
  }

  // Sends the next command when idle, retries or fails on timeout. now_s: monotonic seconds.
  void tick(double now_s) {
    if (failed() || done()) return;
    if (!waiting_) {
      send(now_s);
      return;
    }
    if (now_s - sent_at_s_ < options_.timeout_s) return;
    if (!retried_) {
      log::warn("step ", next_ + 1, ": ", echoed_ ? "no camera frame on BL_IMAGE" : "no projector echo on BL_PROJECTOR",
                " within ", options_.timeout_s, " s; showing the pattern again");
      retried_ = true;
      send(now_s);
      return;
    }
    failure_ = echoed_ ? "no camera frames on " + channel(kImageChannel) + " for " + std::to_string(2 * options_.timeout_s) +
                             " s after the projector showed step " + std::to_string(next_ + 1) + ": is the camera (bricklayer-camera or bricklayer-simcam) running?"
                       : "the projector did not confirm step " + std::to_string(next_ + 1) + " (no projector_state_t with sequence " +
                             std::to_string(sequence_) + " on " + channel(kProjectorChannel) + " within " +
                             std::to_string(2 * options_.timeout_s) + " s): is bricklayer-projection running?";
  }

  size_t step() const { return next_; }
  size_t steps() const { return steps_.size(); }

 private:
  void send(double now_s) {
    command_t cmd = steps_[next_].command;
    cmd.utime = wall_utime();
    cmd.sequence = sequence_ = next_sequence();
    cmd.argument = "bricklayer-calibrate";
    if (!retried_ || !waiting_) {
      log::info("step ", next_ + 1, " of ", steps_.size(), ": ", steps_[next_].description);
    }
    std::ostringstream status;
    status << "step " << next_ + 1 << " of " << steps_.size() << ": " << steps_[next_].description;
    module_.set_status(status.str());
    if (!waiting_) retried_ = false;
    waiting_ = true;
    echoed_ = false;
    frames_seen_ = 0;
    sent_at_s_ = now_s;
    module_.publish(channel(kCommandChannel), cmd);
  }

  // Unique across runs and other senders: microseconds at start, then counting.
  int64_t next_sequence() {
    if (last_sequence_ == 0) last_sequence_ = wall_utime();
    return ++last_sequence_;
  }

  Module& module_;
  std::vector<cal::CalibrationStep> steps_;
  const Options& options_;
  std::vector<cv::Mat> frames_;
  size_t next_ = 0;
  bool waiting_ = false;
  bool echoed_ = false;
  bool retried_ = false;
  int frames_seen_ = 0;
  int64_t sequence_ = 0;
  int64_t last_sequence_ = 0;
  double sent_at_s_ = 0;
  std::string failure_;
};

double monotonic_s() {
  return std::chrono::duration<double>(std::chrono::steady_clock::now().time_since_epoch()).count();
}

class Calibrate {
 public:
  enum class Mode { kCalibrate, kSelfCheck, kServe, kScale };

  Calibrate(const Options& options, Mode mode) : options_(options), mode_(mode), module_("calibrate", options.lcm_url) {
    if (mode_ == Mode::kServe) {
      // An exhibit's launcher starts --serve before anyone has calibrated, or with a file being rewritten:
      // it serves nothing until a good file is there, and never exits over it.
      file_time_ = file_time();
      try {
        calibration_ = board::load_calibration(options_.output);
        log::info("loaded ", options_.output, " (reprojection error mean ", calibration_->reprojection_error_mean_px, " px)");
      } catch (const std::exception& e) {
        if (std::filesystem::exists(options_.output)) ++module_.counters().errors;
        log::warn("no usable calibration yet (", e.what(), "): serving nothing until ", options_.output,
                  " is written; run bricklayer-calibrate");
        module_.set_status("no calibration yet: run bricklayer-calibrate");
      }
    } else if (mode_ != Mode::kCalibrate) {
      calibration_ = board::load_calibration(options_.output);
      log::info("loaded ", options_.output, " (reprojection error mean ", calibration_->reprojection_error_mean_px, " px)");
    }
    if (mode_ == Mode::kScale) {
      scale_ = std::make_unique<detection::BlockScaleMeter>(*calibration_);
      scale_started_s_ = monotonic_s();
      module_.set_status("measuring blocks on the bottom row");
      log::info("measuring the board scale from blocks standing apart on the bottom row (", options_.scale_frames, " frames)");
    }
    module_.subscribe<projector_state_t>(channel(kProjectorChannel), [this](const projector_state_t& s) { HandleProjector(s); });
    module_.subscribe<image_t>(channel(kImageChannel), [this](const image_t& m) { HandleImage(m); });
    module_.subscribe<command_t>(channel(kCommandChannel), [this](const command_t& c) { HandleCommand(c); });
    module_.subscribe<stack_t>(channel(kStackChannel), [this](const stack_t& s) { HandleStack(s); });
    if (mode_ == Mode::kCalibrate) {
      capture_ = std::make_unique<PatternCapture>(module_, cal::calibration_steps(options_.calibration), options_);
    } else if (mode_ == Mode::kSelfCheck) {
      start_self_check();
    }
  }

  int Run() {
    Module::install_signal_handlers();
    const int code = module_.run([this] { Tick(); });
    if (code != 0) return code;
    return exit_code_;
  }

 private:
  void HandleProjector(const projector_state_t& s) {
    if (capture_) capture_->on_projector_state(s);
    // --scale-from-blocks with the game running: its red and blue light on the blocks leaks into green.
    if (scale_ && s.image.size > 0) {
      const cv::Mat shown = decode_frame(s.image);
      if (shown.empty()) {
        ++module_.counters().errors;
        log::warn("projector image could not be decoded; measuring without its leakage subtracted");
        return;
      }
      scale_->set_projector_image(shown, {calibration_->projector_width, calibration_->projector_height});
    }
  }
  void HandleImage(const image_t& m) {
    if (capture_) capture_->on_frame(m);
    if (scale_) measure_scale(m);
  }
  void HandleStack(const stack_t& s) {
    const bool empty = s.status == stack_t::STATUS_OK && s.num_blocks == 0;
    if (empty && !board_empty_) empty_since_s_ = monotonic_s();
    board_empty_ = empty;
  }
  void HandleCommand(const command_t& c) {
    if (c.command != command_t::SELF_CHECK || mode_ != Mode::kServe) return;
    if (!calibration_) {
      log::warn("SELF_CHECK ignored: no calibration to check yet (", options_.output, "); run bricklayer-calibrate");
      return;
    }
    if (capture_) {
      log::warn("SELF_CHECK ignored: a self-check is already running");
      return;
    }
    if (!board_empty_) {
      log::warn("SELF_CHECK postponed: the board is not empty (or no empty-board stack_t seen yet); clear the board and ask again");
      module_.set_status("self-check needs an empty board");
      return;
    }
    start_self_check();
  }

  void start_self_check() {
    last_check_s_ = monotonic_s();
    log::info("self-check: projecting ", patterns::kMarkerSetSelfCheck == 2 ? "five" : "the", " check markers");
    capture_ = std::make_unique<PatternCapture>(
        module_, std::vector<cal::CalibrationStep>{{cal::self_check_command(), "self-check markers"}}, options_);
  }

  void clear_pattern() {
    command_t cmd{};
    cmd.utime = wall_utime();
    cmd.command = command_t::CLEAR_PATTERN;
    cmd.sequence = -1;
    cmd.argument = "bricklayer-calibrate";
    module_.publish(channel(kCommandChannel), cmd);
  }

  void publish_calibration() {
    if (!calibration_) return;
    module_.publish(channel(kCalibrationChannel), *calibration_);
    last_publish_s_ = monotonic_s();
  }

  void Tick() {
    const double now = monotonic_s();
    if (mode_ == Mode::kServe && now - last_publish_s_ >= options_.republish_s) {
      reload_if_changed();
      publish_calibration();
      last_publish_s_ = now;  // also when there is nothing to publish: the file is looked at once a period
    }
    if (scale_ && scale_frames_ == 0 && now - scale_started_s_ > 2 * options_.timeout_s) {
      log::error("no camera frames on ", channel(kImageChannel), " within ", 2 * options_.timeout_s,
                 " s: is the camera (bricklayer-camera or bricklayer-simcam) running?");
      module_.set_status("no camera frames");
      scale_.reset();
      finish(kExitRejected);
      return;
    }
    if (mode_ == Mode::kServe && calibration_ && !capture_ && options_.self_check_every_s > 0 && board_empty_ &&
        now - empty_since_s_ >= options_.empty_for_s && now - last_check_s_ >= options_.self_check_every_s) {
      log::info("automatic self-check (board empty for ", options_.empty_for_s, " s)");
      start_self_check();
    }
    if (!capture_) return;
    capture_->tick(now);
    if (capture_->failed()) {
      log::error(capture_->failure());
      module_.set_status(capture_->failure());
      clear_pattern();
      capture_.reset();
      if (mode_ != Mode::kServe) finish(kExitRejected);
      return;
    }
    if (!capture_->done()) return;
    std::vector<cv::Mat> frames = capture_->take_frames();
    capture_.reset();
    clear_pattern();
    if (mode_ == Mode::kCalibrate) {
      finish_calibration(frames);
    } else {
      finish_self_check(frames.front());
    }
  }

  void finish_calibration(const std::vector<cv::Mat>& frames) {
    module_.set_status("computing");
    log::info("computing the calibration from ", frames.size(), " frames");
    const cal::CalibrationResult result = cal::compute_calibration(frames, options_.calibration, wall_utime());
    if (result.status != cal::CalibrationStatus::kOk) {
      log::error(result.message);
      module_.set_status(std::string("calibration rejected: ") + cal::to_string(result.status));
      finish(kExitRejected);
      return;
    }
    log::info(result.message);
    try {
      board::save_calibration(options_.output, result.calibration);
    } catch (const std::exception& e) {
      log::error(e.what());
      finish(kExitRejected);
      return;
    }
    log::info("saved ", options_.output, "; publishing on ", channel(kCalibrationChannel));
    calibration_ = result.calibration;
    publish_calibration();
    module_.set_value("reprojection_error_mean_px", result.calibration.reprojection_error_mean_px);
    module_.set_value("reprojection_error_max_px", result.calibration.reprojection_error_max_px);
    module_.set_status("ok");
    finish(0);
  }

  void finish_self_check(const cv::Mat& frame) {
    if (frame.cols != calibration_->camera_width || frame.rows != calibration_->camera_height) {
      log::warn("self-check: camera frames are ", frame.cols, "x", frame.rows, " but the calibration is for ",
                calibration_->camera_width, "x", calibration_->camera_height, ": recalibrate");
    }
    const cal::SelfCheckResult r = cal::self_check(*calibration_, frame);
    int code = 0;
    if (!r.measured) {
      log::warn(r.message);
      module_.set_status("self-check: no markers seen");
      code = kExitRejected;
    } else {
      module_.set_value("drift_px", r.drift_mean_px);
      module_.set_value("drift_max_px", r.drift_max_px);
      if (r.drift_mean_px > options_.drift_threshold_px) {
        log::warn(r.message, ": above --drift-threshold ", options_.drift_threshold_px,
                  " px; the camera or projector has moved: run bricklayer-calibrate");
        module_.set_status("drift above threshold: recalibrate");
        code = kExitDrift;
      } else {
        log::info(r.message, ": ok");
        module_.set_status("ok");
      }
    }
    if (mode_ == Mode::kSelfCheck) finish(code);
  }

  // --scale-from-blocks: one more frame measured; after --scale-frames, correct and save the board scale.
  void measure_scale(const image_t& m) {
    if (++scale_seen_ <= options_.skip_frames) return;
    const cv::Mat bgr = decode_frame(m);
    if (bgr.empty() || bgr.cols != calibration_->camera_width || bgr.rows != calibration_->camera_height) {
      ++module_.counters().errors;
      log::warn("camera frame ", m.frame_number, " could not be decoded or is not ", calibration_->camera_width, "x",
                calibration_->camera_height, " (the calibration's camera size); skipped");
      return;
    }
    const size_t before = scale_->measured().size();
    const int blocks = scale_->add(bgr);
    // The lean of the measured blocks' end lines (calibration/line_lean.h), in the green channel, where
    // the game's red and blue light on the blocks leaks least.
    cv::Mat green;
    cv::extractChannel(bgr, green, 1);
    const double h = calibration_->block_height;
    ScaleFrame frame;
    frame.blocks = blocks;
    for (size_t i = before; i < scale_->measured().size(); ++i) {
      frame.lines.push_back(scale_->measured()[i]);
      for (double x : {scale_->measured()[i].left, scale_->measured()[i].right})
        if (const auto lean = calibration::measure_line_lean(green, *calibration_, x, 0.2 * h, 0.75 * h)) frame.leans.push_back({x, *lean});
    }
    scale_by_frame_.push_back(std::move(frame));
    log::debug("frame ", m.frame_number, ": ", blocks, " bottom-row blocks standing apart measured");
    if (++scale_frames_ < options_.scale_frames) return;
    scale_.reset();

    // Under blur and noise a frame now and then counts a block too many (a shadow edge paired with a line)
    // or one too few: only the frames that count the blocks placed (--scale-blocks), or else the count most
    // frames agree on, are measured.
    std::map<int, int> counts;
    for (const ScaleFrame& f : scale_by_frame_) ++counts[f.blocks];
    int expected = options_.scale_blocks;
    if (expected == 0) {
      int best = 0;
      for (const auto& [count, frames] : counts)
        if (frames > best) best = frames, expected = count;  // ties: the smaller count (map order)
    }
    std::vector<detection::EndLines> lines;
    std::vector<calibration::LineLean> leans;
    int kept = 0;
    std::ostringstream seen;
    for (const auto& [count, frames] : counts) seen << (seen.tellp() > 0 ? ", " : "") << count << " in " << frames;
    for (const ScaleFrame& f : scale_by_frame_) {
      if (f.blocks != expected) continue;
      ++kept;
      lines.insert(lines.end(), f.lines.begin(), f.lines.end());
      leans.insert(leans.end(), f.leans.begin(), f.leans.end());
    }
    scale_by_frame_.clear();
    module_.set_value("scale_frames_used", kept);
    if (kept * 2 < options_.scale_frames) {
      const std::string why = "blocks counted per frame: " + seen.str() + " frames; only " + std::to_string(kept) + " of " +
                              std::to_string(options_.scale_frames) + " frames count " + std::to_string(expected) +
                              (options_.scale_blocks > 0 ? " (--scale-blocks)" : "") +
                              ": are the blocks standing apart, whole in view, the camera steady?";
      log::error("board scale not measured: ", why);
      module_.set_status("scale not measured: " + why);
      finish(kExitRejected);
      return;
    }
    if (kept < options_.scale_frames) log::info("blocks counted per frame: ", seen.str(), " frames; measuring the ", kept, " that count ", expected);

    std::string why;
    const std::optional<detection::BoardCorrection> fit = detection::fit_board_correction(
        lines, detection::DetectorConfig{}.line_width, 2 * kept, options_.scale_max_residual, &why);
    if (!fit) {
      log::error("board scale not measured: ", why);
      module_.set_status("scale not measured: " + why);
      finish(kExitRejected);
      return;
    }
    std::string lean_why;
    const std::optional<calibration::FrameLean> lean =
        calibration::fit_frame_lean(leans, fit->scale, fit->keystone, 2 * kept, &lean_why);
    const double shear = lean ? lean->shear : 0.0;
    const double vertical_keystone = lean ? lean->vertical_keystone : 0.0;
    if (!lean) log::warn("the lean of the board's vertical not measured (", lean_why, "): corrected along the board only");
    const double change = std::max(fit->max_change(kScaleCheckHalfWidth),
                                   calibration::frame_correction_change(fit->scale, fit->keystone, shear, vertical_keystone,
                                                                        kScaleCheckHalfWidth, kScaleCheckHeight));
    module_.set_value("scale", fit->scale);
    module_.set_value("keystone", fit->keystone);
    module_.set_value("shear", shear);
    module_.set_value("vertical_keystone", vertical_keystone);
    module_.set_value("block_length", fit->length_at(0.0));
    module_.set_value("blocks_measured", fit->blocks);
    module_.set_value("correction_max_change", change);
    std::ostringstream text;
    text.precision(4);
    text << "blocks read " << fit->length_at(-2.0) << ", " << fit->length_at(0.0) << " and " << fit->length_at(2.0)
         << " block lengths long 2 lengths left of the edge, at it and 2 right of it (" << fit->blocks
         << " measurements, " << fit->outliers << " dropped, residual " << 100 * fit->residual
         << "%); end lines lean " << (lean ? std::to_string(lean->lines) + " measured: shear " + std::to_string(shear) +
                                                  ", vertical keystone " + std::to_string(vertical_keystone)
                                            : std::string("not measured"))
         << "; the correction moves points within " << kScaleCheckHalfWidth << " lengths of the edge and "
         << kScaleCheckHeight << " above the surface by up to " << change;
    if (change < options_.scale_min_change) {
      log::info(text.str(), ": below --scale-min-change ", options_.scale_min_change, ", ", options_.output,
                " left as it is");
      module_.set_status("ok: scale already right");
      finish(0);
      return;
    }
    calibration_t corrected =
        calibration::apply_frame_correction(*calibration_, fit->scale, fit->keystone, shear, vertical_keystone);
    corrected.utime = wall_utime();
    try {
      board::save_calibration(options_.output, corrected);
    } catch (const std::exception& e) {
      log::error(e.what());
      finish(kExitRejected);
      return;
    }
    log::info(text.str(), ": board scale corrected, saved ", options_.output, "; publishing on ", channel(kCalibrationChannel));
    calibration_ = corrected;
    publish_calibration();
    module_.set_status("ok");
    finish(0);
  }

  std::filesystem::file_time_type file_time() const {
    std::error_code ec;
    const auto t = std::filesystem::last_write_time(options_.output, ec);
    return ec ? std::filesystem::file_time_type{} : t;
  }

  // --serve: the file was rewritten (a new calibration or --scale-from-blocks): serve the new one. A file
  // that no longer loads is a counted error and the previous calibration stays.
  void reload_if_changed() {
    const auto t = file_time();
    if (t == file_time_) return;
    file_time_ = t;
    if (!std::filesystem::exists(options_.output)) {
      log::warn(options_.output, " was removed; still serving the calibration read before");
      return;
    }
    try {
      calibration_ = board::load_calibration(options_.output);
      log::info("re-read ", options_.output, ": it changed");
      module_.set_status("ok");
    } catch (const std::exception& e) {
      ++module_.counters().errors;
      log::error("re-reading ", options_.output, ": ", e.what(), calibration_ ? "; still serving the previous calibration" : "");
    }
  }

  void finish(int code) {
    exit_code_ = code;
    module_.publish_heartbeat();  // the final status reaches the operator before exit
    Module::request_stop();
  }

  Options options_;
  Mode mode_;
  Module module_;
  std::unique_ptr<PatternCapture> capture_;
  std::optional<calibration_t> calibration_;
  bool board_empty_ = false;
  double empty_since_s_ = 0;
  double last_check_s_ = -1e9;
  double last_publish_s_ = -1e9;
  std::filesystem::file_time_type file_time_{};
  std::unique_ptr<detection::BlockScaleMeter> scale_;
  double scale_started_s_ = 0;
  int scale_seen_ = 0;    // frames received in --scale-from-blocks
  int scale_frames_ = 0;  // frames measured
  // --scale-from-blocks: what each frame measured (the blocks' end lines and their leans).
  struct ScaleFrame {
    int blocks = 0;
    std::vector<detection::EndLines> lines;
    std::vector<calibration::LineLean> leans;
  };
  std::vector<ScaleFrame> scale_by_frame_;
  int exit_code_ = 0;
};

int Main(int argc, char** argv) {
  Flags flags("bricklayer-calibrate",
              "Registers camera and projector automatically (patterns via bricklayer-projection, frames from the camera), "
              "measures the colour mixing, saves and publishes the calibration; or checks it for drift.");
  flags.add("lcm-url", "", "LCM URL (default: $LCM_DEFAULT_URL, else host-only udpm ttl=0)");
  flags.add("log-level", "info", "debug, info, warn or error");
  flags.add("output", "calibration.json", "calibration file to write (or to read with --self-check / --serve)");
  flags.add("board", "", "BoardGeometry JSON in rectified pixels (default: the built-in default board)");
  flags.add("projector-size", "1024x768", "projector resolution, WIDTHxHEIGHT (as bricklayer-projection --width/--height)");
  flags.add("max-error-px", "1.0", "reject a calibration whose mean reprojection error exceeds this, projector pixels");
  flags.add("max-point-error-px", "1.25", "reject a calibration whose largest reprojection error (one marker) exceeds this, projector pixels");
  flags.add("timeout", "5", "seconds to wait for the projector's echo or a camera frame before retrying a step once");
  flags.add("skip-frames", "3", "camera frames to discard after the projector confirms a pattern");
  flags.add("colour-drive", "80", "projector level 1..255 for the red, green and blue frames (lower if the camera saturates)");
  flags.add("drift-threshold", "2.0", "self-check: warn above this mean drift, projector pixels");
  flags.add("republish", "5", "--serve: seconds between re-publications of the calibration");
  flags.add_bool("no-shelf", "do not anchor the board frame on the detected shelf; use --board exactly as given");
  flags.add_bool("self-check", "check the saved calibration for drift once and exit (3 = drift above threshold)");
  flags.add_bool("serve", "publish the saved calibration and self-check on command SELF_CHECK when the board is empty");
  flags.add("self-check-every", "0", "--serve: also self-check automatically this often, seconds, once the board has been empty --empty-for seconds (0 = only on command)");
  flags.add("empty-for", "5", "--serve: seconds of empty board before an automatic self-check");
  flags.add_bool("write-default", "write the uncalibrated default setup (modules/board) to --output and exit");
  flags.add_bool("scale-from-blocks", "correct the saved calibration's board scale from 3+ blocks standing apart on the bottom row, save, publish and exit");
  flags.add("scale-frames", "10", "--scale-from-blocks: camera frames to measure");
  flags.add("scale-blocks", "0", "--scale-from-blocks: how many blocks stand apart on the bottom row (frames counting otherwise are left out); 0 = the count most frames agree on");
  flags.add("scale-max-residual", "0.01", "--scale-from-blocks: refuse when the block lengths disagree with the fitted correction by more than this fraction (RMS)");
  flags.add("scale-min-change", "0.02", "--scale-from-blocks: leave the calibration as it is when the correction moves no point within 4 block lengths of the edge by more than this, block lengths");
  if (!flags.parse(argc, argv)) return 0;
  log::set_module("calibrate");
  log::set_level(log::parse_level(flags.get("log-level")));

  Options options;
  options.lcm_url = resolve_lcm_url(flags.get("lcm-url"));
  check_lcm_url(options.lcm_url);
  options.output = flags.get("output");
  if (options.output.empty()) throw FlagError("--output must name a file");
  if (!flags.get("board").empty()) options.calibration.board = load_board_geometry(flags.get("board"));
  options.calibration.projector_size = parse_size(flags.get("projector-size"));
  options.calibration.board_from_shelf = !flags.get_bool("no-shelf");
  options.calibration.max_error_px = flags.get_double("max-error-px");
  if (options.calibration.max_error_px <= 0) throw FlagError("--max-error-px must be positive");
  options.calibration.max_point_error_px = flags.get_double("max-point-error-px");
  if (!(options.calibration.max_point_error_px > 0)) throw FlagError("--max-point-error-px must be positive");
  options.timeout_s = flags.get_double("timeout");
  if (options.timeout_s <= 0 || options.timeout_s > 3600) throw FlagError("--timeout must be in (0, 3600] seconds");
  options.skip_frames = static_cast<int>(flags.get_int("skip-frames"));
  if (options.skip_frames < 0 || options.skip_frames > 100) throw FlagError("--skip-frames must be 0..100");
  options.calibration.colour_drive = static_cast<int>(flags.get_int("colour-drive"));
  if (options.calibration.colour_drive < 1 || options.calibration.colour_drive > 255) throw FlagError("--colour-drive must be 1..255");
  options.drift_threshold_px = flags.get_double("drift-threshold");
  if (options.drift_threshold_px <= 0) throw FlagError("--drift-threshold must be positive");
  options.republish_s = flags.get_double("republish");
  if (options.republish_s <= 0) throw FlagError("--republish must be positive");
  options.self_check_every_s = flags.get_double("self-check-every");
  if (options.self_check_every_s < 0) throw FlagError("--self-check-every must be 0 (off) or positive seconds");
  options.empty_for_s = flags.get_double("empty-for");
  if (options.empty_for_s < 0) throw FlagError("--empty-for must not be negative");
  options.scale_frames = static_cast<int>(flags.get_int("scale-frames"));
  if (options.scale_frames < 1 || options.scale_frames > 1000) throw FlagError("--scale-frames must be 1..1000");
  options.scale_blocks = static_cast<int>(flags.get_int("scale-blocks"));
  if (options.scale_blocks < 0 || options.scale_blocks > 100) throw FlagError("--scale-blocks must be 0..100");
  options.scale_max_residual = flags.get_double("scale-max-residual");
  if (!(options.scale_max_residual > 0 && options.scale_max_residual < 1)) throw FlagError("--scale-max-residual must be in (0, 1)");
  options.scale_min_change = flags.get_double("scale-min-change");
  if (!(options.scale_min_change >= 0 && options.scale_min_change < 1)) throw FlagError("--scale-min-change must be in [0, 1) block lengths");
  if (flags.get_bool("self-check") + flags.get_bool("serve") + flags.get_bool("scale-from-blocks") > 1)
    throw FlagError("--self-check, --serve and --scale-from-blocks exclude each other");

  if (flags.get_bool("write-default")) {
    board::save_calibration(options.output, board::default_calibration());
    log::info("wrote the uncalibrated default to ", options.output);
    return 0;
  }

  const Calibrate::Mode mode = flags.get_bool("serve")               ? Calibrate::Mode::kServe
                               : flags.get_bool("self-check")        ? Calibrate::Mode::kSelfCheck
                               : flags.get_bool("scale-from-blocks") ? Calibrate::Mode::kScale
                                                                     : Calibrate::Mode::kCalibrate;
  Calibrate app(options, mode);
  return app.Run();
}

}  // namespace
}  // namespace bricklayer

int main(int argc, char** argv) { return bricklayer::run_main("bricklayer-calibrate", &bricklayer::Main, argc, argv); }
