#include "bricklayer/calibration/calibrate_node.h"
#include "bricklayer/calibration/board_x_accuracy.h"
#include "bricklayer/calibration/board_frame_refit.h"

#include <opencv2/imgproc.hpp>

#include <algorithm>
#include <functional>
#include <map>
#include <sstream>
#include <stdexcept>

#include "bricklayer/board/board_geometry.h"
#include "bricklayer/board/calibration_file.h"
#include "bricklayer/common/channels.h"
#include "bricklayer/common/log.h"
#include "bricklayer/frames/image_codec.h"
#include "bricklayer/patterns/patterns.h"

namespace bricklayer::calibration {
namespace {

constexpr double kScaleCheckHalfWidth = 4.0;  // block lengths either side of the edge a correction is judged over
constexpr double kScaleCheckHeight = 3.0;     // and the heights (block lengths above the surface, ~9 rows)
constexpr int64_t kUs = 1'000'000;

int64_t seconds_us(double s) { return static_cast<int64_t>(s * 1e6); }

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

std::optional<cv::Size> parse_size(const std::string& text) {
  int w = 0, h = 0;
  char x = 0;
  std::istringstream in(text);
  if (!(in >> w >> x >> h) || (x != 'x' && x != 'X') || in.peek() != EOF || w < 16 || h < 16 || w > 16384 || h > 16384)
    return std::nullopt;
  return cv::Size{w, h};
}

std::string load_error(const std::string& what, const std::exception& e) { return what + e.what(); }

}  // namespace

std::string CalibrateConfig::projector_size_rule(const std::string& text) {
  if (parse_size(text)) return "";
  return "expected WIDTHxHEIGHT like 1024x768 (16..16384 each), got \"" + text + "\"";
}

CalibrationOptions CalibrateConfig::calibration_options() const {
  CalibrationOptions o;
  if (!board.empty()) o.board = load_board_geometry(board);
  const std::optional<cv::Size> size = parse_size(projector_size);
  if (!size) throw std::invalid_argument("projector-size " + projector_size_rule(projector_size));
  o.projector_size = *size;
  o.board_from_shelf = !no_shelf;
  o.max_error_px = max_error_px;
  o.max_point_error_px = max_point_error_px;
  o.colour_drive = colour_drive;
  return o;
}

// Shows a list of patterns one at a time and collects one camera frame per pattern. Time is the bus
// clock the node passes in.
class CalibrateNode::PatternCapture {
 public:
  // send: publish this command and show this status; error: a counted error (kind, message).
  using Send = std::function<void(const command_t&, const std::string& status)>;
  using Error = std::function<void(const std::string& kind, const std::string& message)>;

  PatternCapture(std::vector<CalibrationStep> steps, const CalibrateConfig& config, cv::Size projector_size,
                 std::function<int64_t()> next_sequence, Send send, Error error)
      : steps_(std::move(steps)),
        timeout_us_(seconds_us(config.timeout)),
        timeout_s_(config.timeout),
        skip_frames_(config.skip_frames),
        projector_size_(projector_size),
        next_sequence_(std::move(next_sequence)),
        send_(std::move(send)),
        error_(std::move(error)) {}

  bool done() const { return next_ >= steps_.size() && !waiting_; }
  bool failed() const { return !failure_.empty(); }
  const std::string& failure() const { return failure_; }
  std::vector<cv::Mat> take_frames() { return std::move(frames_); }
  // When the current step times out (bus clock), while one is waiting.
  std::optional<int64_t> deadline() const {
    if (!waiting_ || failed()) return std::nullopt;
    return sent_at_ + timeout_us_;
  }

  void on_projector_state(const projector_state_t& s) {
    if (waiting_ && !echoed_ && s.command_sequence == sequence_) {
      // Patterns come back at full size: a different size means the marker positions are wrong.
      if (s.mode == projector_state_t::MODE_PATTERN && s.image.width > 0 &&
          (s.image.width != projector_size_.width || s.image.height != projector_size_.height)) {
        failure_ = "the projector shows " + std::to_string(s.image.width) + "x" + std::to_string(s.image.height) +
                   " but --projector-size is " + std::to_string(projector_size_.width) + "x" +
                   std::to_string(projector_size_.height) + ": pass the projector's resolution";
        return;
      }
      echoed_ = true;
      frames_seen_ = 0;
      log::debug("projector shows sequence ", sequence_);
    }
  }

  void on_frame(const image_t& img) {
    if (!waiting_ || !echoed_ || failed()) return;
    if (++frames_seen_ <= skip_frames_) return;
    cv::Mat bgr = decode_frame(img);
    if (bgr.empty()) {
      error_("undecodable camera frames", "camera frame " + std::to_string(img.frame_number) +
                                              " could not be decoded (format " + std::to_string(img.format) + ", " +
                                              std::to_string(img.width) + "x" + std::to_string(img.height) +
                                              "); waiting for the next");
      return;
    }
    if (!frames_.empty() && bgr.size() != frames_.front().size()) {
      error_("camera frame size changes", "camera frame size changed during calibration; ignoring the frame");
      return;
    }
    frames_.push_back(std::move(bgr));
    waiting_ = false;
    ++next_;
  }

  // Sends the next command when idle, retries or fails on timeout.
  void tick(int64_t now) {
    if (failed() || done()) return;
    if (!waiting_) {
      send(now);
      return;
    }
    if (now - sent_at_ < timeout_us_) return;
    if (!retried_) {
      std::ostringstream what;
      what << "step " << next_ + 1 << ": " << (echoed_ ? "no camera frame on BL_IMAGE" : "no projector echo on BL_PROJECTOR")
           << " within " << timeout_s_ << " s; showing the pattern again";
      log::warn(what.str());
      retried_ = true;
      send(now);
      return;
    }
    failure_ = echoed_ ? "no camera frames on " + channel(kImageChannel) + " for " + runtime::config_detail::to_text(2 * timeout_s_) +
                             " s after the projector showed step " + std::to_string(next_ + 1) +
                             ": is the camera (bricklayer-camera or bricklayer-simcam) running?"
                       : "the projector did not confirm step " + std::to_string(next_ + 1) +
                             " (no projector_state_t with sequence " + std::to_string(sequence_) + " on " +
                             channel(kProjectorChannel) + " within " + runtime::config_detail::to_text(2 * timeout_s_) +
                             " s): is bricklayer-projection running?";
  }

  size_t step() const { return next_; }
  size_t steps() const { return steps_.size(); }

 private:
  void send(int64_t now) {
    command_t cmd = steps_[next_].command;
    cmd.utime = now;
    cmd.sequence = sequence_ = next_sequence_();
    cmd.argument = "bricklayer-calibrate";
    if (!retried_ || !waiting_) log::info("step ", next_ + 1, " of ", steps_.size(), ": ", steps_[next_].description);
    std::ostringstream status;
    status << "step " << next_ + 1 << " of " << steps_.size() << ": " << steps_[next_].description;
    if (!waiting_) retried_ = false;
    waiting_ = true;
    echoed_ = false;
    frames_seen_ = 0;
    sent_at_ = now;
    send_(cmd, status.str());
  }

  std::vector<CalibrationStep> steps_;
  int64_t timeout_us_;
  double timeout_s_;
  int skip_frames_;
  cv::Size projector_size_;
  std::function<int64_t()> next_sequence_;
  Send send_;
  Error error_;
  std::vector<cv::Mat> frames_;
  size_t next_ = 0;
  bool waiting_ = false;
  bool echoed_ = false;
  bool retried_ = false;
  int frames_seen_ = 0;
  int64_t sequence_ = 0;
  int64_t sent_at_ = 0;
  std::string failure_;
};

void CalibrateNode::check(const Config& c) {
  if (c.self_check + c.serve + c.scale_from_blocks > 1)
    throw std::invalid_argument("--self-check, --serve and --scale-from-blocks exclude each other");
}

std::optional<int> CalibrateNode::before_bus(const Config& c) {
  if (!c.write_default) return std::nullopt;
  board::save_calibration(c.output, board::default_calibration());
  log::info("wrote the uncalibrated default to ", c.output);
  return 0;
}

CalibrateNode::CalibrateNode(const Config& config, runtime::Bus& bus)
    : Node("calibrate", bus),
      config_(config),
      mode_(config.serve               ? Mode::kServe
            : config.self_check        ? Mode::kSelfCheck
            : config.scale_from_blocks ? Mode::kScale
                                       : Mode::kCalibrate),
      command_channel_(channel(kCommandChannel)),
      calibration_channel_(channel(kCalibrationChannel)) {
  runtime::validate(config_);
  check(config_);
  options_ = config_.calibration_options();
  if (mode_ == Mode::kServe) {
    // An exhibit's launcher starts --serve before anyone has calibrated, or with a file being rewritten:
    // it serves nothing until a good file is there, and never exits over it.
    file_time_ = file_time();
    try {
      calibration_ = board::load_calibration(config_.output);
      log::info("loaded ", config_.output, " (reprojection error mean ", calibration_->reprojection_error_mean_px, " px)");
    } catch (const std::exception& e) {
      const std::string message = "no usable calibration yet (" + std::string(e.what()) + "): serving nothing until " +
                                  config_.output + " is written; run bricklayer-calibrate";
      // A file that is there but does not load is an error; one not written yet is what --serve waits for.
      if (std::filesystem::exists(config_.output)) error("unusable calibration files", message);
      else log::warn(message);
      set_status("no calibration yet: run bricklayer-calibrate");
    }
  } else if (mode_ != Mode::kCalibrate) {
    // Not std::invalid_argument: a file that does not load is not a bad flag (exit 1, not 2).
    try {
      calibration_ = board::load_calibration(config_.output);
    } catch (const std::exception& e) {
      throw std::runtime_error(e.what());
    }
    log::info("loaded ", config_.output, " (reprojection error mean ", calibration_->reprojection_error_mean_px, " px)");
  }
  if (mode_ == Mode::kScale) start_scale();
  // Every echo and every frame counts (the frames after an echo are counted to skip those in flight):
  // queues hold a burst; the projector image (scale mode) is decoded only for the newest.
  subscribe<projector_state_t>(channel(kProjectorChannel), runtime::QueuePolicy::keep(16),
                               [this](const projector_state_t& s) { on_projector(s); }, 32u << 20);
  subscribe<image_t>(channel(kImageChannel), runtime::QueuePolicy::keep(16), [this](const image_t& m) { on_image(m); },
                     32u << 20);
  subscribe<command_t>(command_channel_, runtime::QueuePolicy::keep(100), [this](const command_t& c) { on_command(c); });
  subscribe<stack_t>(channel(kStackChannel), runtime::QueuePolicy::newest(), [this](const stack_t& s) { on_stack(s); });
  if (mode_ == Mode::kCalibrate) {
    start_calibration();
  } else if (mode_ == Mode::kSelfCheck) {
    start_self_check();
  }
}

CalibrateNode::~CalibrateNode() = default;

// Unique across runs and other senders: microseconds at the first command (the bus clock), then counting.
int64_t CalibrateNode::next_sequence() {
  if (last_sequence_ == 0) last_sequence_ = now();
  return ++last_sequence_;
}

void CalibrateNode::on_projector(const projector_state_t& s) {
  if (finished_) return;
  if (capture_) capture_->on_projector_state(s);
  // --scale-from-blocks with the game running: its red and blue light on the blocks leaks into green.
  if (scale_ && s.image.size > 0) {
    const cv::Mat shown = decode_frame(s.image);
    if (shown.empty()) {
      error("undecodable projector images", "projector image could not be decoded; measuring without its leakage subtracted");
      return;
    }
    scale_->set_projector_image(shown, {calibration_->projector_width, calibration_->projector_height});
    scale_projector_image_ = shown;
  }
}

void CalibrateNode::on_image(const image_t& m) {
  if (finished_) return;
  if (capture_) capture_->on_frame(m);
  if (scale_) measure_scale(m);
}

void CalibrateNode::on_stack(const stack_t& s) {
  stack_seen_ = true;
  const bool empty = s.status == stack_t::STATUS_OK && s.num_blocks == 0;
  if (empty && !board_empty_) empty_since_utime_ = now();
  board_empty_ = empty;
}

void CalibrateNode::on_command(const command_t& c) {
  if (mode_ != Mode::kServe) return;
  if (c.command == command_t::CALIBRATE) {
    on_calibrate_command(c);
    return;
  }
  if (c.command != command_t::SELF_CHECK) return;
  if (!calibration_) {
    log::warn("SELF_CHECK ignored: no calibration to check yet (", config_.output, "); run bricklayer-calibrate");
    return;
  }
  if (capture_ || scale_) {
    log::warn("SELF_CHECK ignored: a ", capture_ && !capture_calibrates_ ? "self-check" : "calibration", " is already running");
    return;
  }
  if (!board_empty_) {
    log::warn("SELF_CHECK postponed: the board is not empty (or no empty-board stack_t seen yet); clear the board and ask again");
    set_status("self-check needs an empty board");
    return;
  }
  start_self_check();
}

// A CALIBRATE command (--serve): it waits for the board to have been empty --empty-for seconds (tick);
// one already waiting or running is not asked for twice.
void CalibrateNode::on_calibrate_command(const command_t& c) {
  if ((capture_ && capture_calibrates_) || scale_) {
    ++calibrate_ignored_;
    log::warn("CALIBRATE ignored: a calibration is already running (", status(), ")");
    return;
  }
  if (c.argument == kScaleFromBlocks) {
    // The scale step needs blocks on the board, not an empty one: it starts at once.
    if (calibrate_asked_utime_ || capture_) {
      ++calibrate_ignored_;
      log::warn("CALIBRATE scale-from-blocks ignored: a ", capture_ ? "self-check runs" : "calibration waits", "; ask again after it");
      return;
    }
    if (!calibration_) {
      calibration_failed("scale not measured: no calibration to correct yet; calibrate first");
      return;
    }
    start_scale();
    return;
  }
  if (calibrate_asked_utime_) {
    ++calibrate_ignored_;
    log::warn("CALIBRATE ignored: a calibration already waits for the board to be empty");
    return;
  }
  calibrate_asked_utime_ = now();
  log::info("CALIBRATE: calibrating once the board has been empty for ", config_.empty_for, " s (waiting at most ",
            config_.calibrate_wait, " s)");
  set_status("calibration asked: waiting for the board to be empty for " + runtime::config_detail::to_text(config_.empty_for) +
             " s");
}

void CalibrateNode::serve_calibrate_request(int64_t t) {
  if (!calibrate_asked_utime_ || capture_) return;  // a self-check running finishes first
  const int64_t ready = empty_since_utime_ + seconds_us(config_.empty_for);
  if (board_empty_ && t >= ready) {
    calibrate_asked_utime_.reset();
    log::info("calibrating on command (board empty for ", config_.empty_for, " s)");
    start_calibration();
    return;
  }
  const int64_t give_up = *calibrate_asked_utime_ + seconds_us(config_.calibrate_wait);
  if (t >= give_up) {
    calibrate_asked_utime_.reset();
    const std::string wait = runtime::config_detail::to_text(config_.calibrate_wait);
    calibration_failed(
        !stack_seen_ ? "calibration not started: no board state (stack_t on " + channel(kStackChannel) + ") within " + wait +
                           " s, so the board is not known to be empty: is bricklayer-vision running with a calibration?"
                     : "calibration not started: the board was not empty for " +
                           runtime::config_detail::to_text(config_.empty_for) + " s within " + wait +
                           " s; clear the board and ask again");
    return;
  }
  if (!board_empty_)
    set_status("calibration waits for an empty board: clear the board (at most " +
               runtime::config_detail::to_text(config_.calibrate_wait) + " s)");
  wake_at(board_empty_ ? std::min(ready, give_up) : give_up);
}

void CalibrateNode::calibration_failed(const std::string& why) {
  ++calibrations_failed_;
  log::warn(why);
  set_status(why + (calibration_ ? "; still serving the previous calibration" : ""));
}

std::unique_ptr<CalibrateNode::PatternCapture> CalibrateNode::make_capture(std::vector<CalibrationStep> steps,
                                                                         std::string status_prefix) {
  return std::make_unique<PatternCapture>(
      std::move(steps), config_, options_.projector_size, [this] { return next_sequence(); },
      [this, status_prefix](const command_t& c, const std::string& status) {
        set_status(status_prefix + status);
        publish(command_channel_, c);
      },
      [this](const std::string& kind, const std::string& message) { error(kind, message); });
}

void CalibrateNode::start_calibration() {
  capture_calibrates_ = true;
  capture_ = make_capture(calibration_steps(options_), mode_ == Mode::kServe ? "calibrating: " : "");
}

void CalibrateNode::start_scale() {
  scale_ = std::make_unique<detection::BlockScaleMeter>(*calibration_);
  scale_projector_image_.release();
  scale_started_utime_ = now();
  scale_seen_ = scale_frames_ = 0;
  scale_by_frame_.clear();
  set_status("measuring blocks on the bottom row");
  log::info("measuring the board scale from blocks standing apart on the bottom row (", config_.scale_frames, " frames)");
}

// --scale-from-blocks ends the process with this code; --serve (CALIBRATE "scale-from-blocks") counts the
// run, serves the corrected calibration or keeps the old one, and serves on.
void CalibrateNode::end_scale(int code) {
  if (mode_ != Mode::kServe) {
    finish(code);
    return;
  }
  if (code != 0) {
    calibration_failed(status());
    return;
  }
  ++calibrations_done_;
  file_time_ = file_time();  // our own write, not a change to re-read
}

void CalibrateNode::start_self_check() {
  last_check_utime_ = now();
  log::info("self-check: projecting ", patterns::kMarkerSetSelfCheck == 2 ? "five" : "the", " check markers");
  capture_calibrates_ = false;
  capture_ = make_capture({{self_check_command(), "self-check markers"}}, "");
}

void CalibrateNode::clear_pattern() {
  command_t cmd{};
  cmd.utime = now();
  cmd.command = command_t::CLEAR_PATTERN;
  cmd.sequence = -1;
  cmd.argument = "bricklayer-calibrate";
  publish(command_channel_, cmd);
}

void CalibrateNode::publish_calibration() {
  if (!calibration_) return;
  publish(calibration_channel_, *calibration_);
  last_publish_utime_ = now();
}

void CalibrateNode::tick() {
  if (finished_) return;
  const int64_t t = now();
  if (mode_ == Mode::kServe) {
    if (t - last_publish_utime_ >= seconds_us(config_.republish)) {
      reload_if_changed();
      publish_calibration();
      last_publish_utime_ = t;  // also when there is nothing to publish: the file is looked at once a period
    }
    wake_at(last_publish_utime_ + seconds_us(config_.republish));
  }
  if (scale_ && scale_frames_ == 0) {
    if (t - scale_started_utime_ > 2 * seconds_us(config_.timeout)) {
      const std::string why = "no camera frames on " + channel(kImageChannel) + " within " +
                              runtime::config_detail::to_text(2 * config_.timeout) +
                              " s: is the camera (bricklayer-camera or bricklayer-simcam) running?";
      error("missing camera frames", why);
      set_status("scale not measured: no camera frames");
      scale_.reset();
      end_scale(kExitRejected);
      return;
    }
    wake_at(scale_started_utime_ + 2 * seconds_us(config_.timeout) + 1);
  }
  if (mode_ == Mode::kServe) serve_calibrate_request(t);
  if (mode_ == Mode::kServe && calibration_ && !capture_ && !scale_ && !calibrate_asked_utime_ && config_.self_check_every > 0 &&
      board_empty_) {
    const int64_t due = std::max(empty_since_utime_ + seconds_us(config_.empty_for),
                                 last_check_utime_ + seconds_us(config_.self_check_every));
    if (t >= due) {
      log::info("automatic self-check (board empty for ", config_.empty_for, " s)");
      start_self_check();
    } else {
      wake_at(due);
    }
  }
  if (!capture_) return;
  capture_->tick(t);
  if (capture_->failed()) {
    error("failed calibration steps", capture_->failure());
    set_status(capture_->failure());
    clear_pattern();
    capture_.reset();
    if (mode_ != Mode::kServe) finish(kExitRejected);
    else if (capture_calibrates_) calibration_failed("calibration failed: " + capture_->failure());
    return;
  }
  if (const std::optional<int64_t> deadline = capture_->deadline()) wake_at(*deadline);
  if (!capture_->done()) return;
  std::vector<cv::Mat> frames = capture_->take_frames();
  capture_.reset();
  clear_pattern();
  if (capture_calibrates_) {
    finish_calibration(frames);
  } else {
    finish_self_check(frames.front());
  }
}

void CalibrateNode::finish_calibration(const std::vector<cv::Mat>& frames) {
  set_status("computing");
  log::info("computing the calibration from ", frames.size(), " frames");
  const CalibrationResult result = compute_calibration(frames, options_, now());
  const bool serving = mode_ == Mode::kServe;
  if (result.status != CalibrationStatus::kOk) {
    error("rejected calibrations", result.message);
    if (serving) {
      // The computation's words say what to fix; they start "calibration rejected: " already.
      const std::string prefix = "calibration rejected: ";
      const bool has_prefix = result.message.rfind(prefix, 0) == 0;
      calibration_failed(std::string("calibration rejected (") + to_string(result.status) +
                         "): " + (has_prefix ? result.message.substr(prefix.size()) : result.message));
      return;
    }
    set_status(std::string("calibration rejected: ") + to_string(result.status));
    finish(kExitRejected);
    return;
  }
  log::info(result.message);
  try {
    board::save_calibration(config_.output, result.calibration);
  } catch (const std::exception& e) {
    error("unwritable calibration files", e.what());
    if (serving) {
      calibration_failed(std::string("calibration not saved: ") + e.what());
      return;
    }
    set_status(std::string("not saved: ") + e.what());
    finish(kExitRejected);
    return;
  }
  log::info("saved ", config_.output, "; publishing on ", calibration_channel_);
  calibration_ = result.calibration;
  if (serving) {
    // Our own write: the file is what is served already, not a change to re-read at the next republication.
    file_time_ = file_time();
    ++calibrations_done_;
  }
  publish_calibration();
  set_value("reprojection_error_mean_px", result.calibration.reprojection_error_mean_px);
  set_value("reprojection_error_max_px", result.calibration.reprojection_error_max_px);
  set_status("ok");
  if (!serving) finish(0);
}

void CalibrateNode::before_heartbeat() {
  if (mode_ != Mode::kServe) return;
  if (calibration_) {
    set_value("calibration_age_s", static_cast<double>(now() - calibration_->utime) / 1e6);
    set_value("reprojection_error_mean_px", calibration_->reprojection_error_mean_px);
  }
  set_value("calibrations_done", static_cast<double>(calibrations_done_));
  set_value("calibrations_failed", static_cast<double>(calibrations_failed_));
  set_value("calibrate_commands_ignored", static_cast<double>(calibrate_ignored_));
}

void CalibrateNode::finish_self_check(const cv::Mat& frame) {
  if (frame.cols != calibration_->camera_width || frame.rows != calibration_->camera_height) {
    log::warn("self-check: camera frames are ", frame.cols, "x", frame.rows, " but the calibration is for ",
              calibration_->camera_width, "x", calibration_->camera_height, ": recalibrate");
  }
  const SelfCheckResult r = self_check(*calibration_, frame);
  int code = 0;
  if (!r.measured) {
    log::warn(r.message);
    set_status("self-check: no markers seen");
    code = kExitRejected;
  } else {
    set_value("drift_px", r.drift_mean_px);
    set_value("drift_max_px", r.drift_max_px);
    if (r.drift_mean_px > config_.drift_threshold) {
      log::warn(r.message, ": above --drift-threshold ", config_.drift_threshold,
                " px; the camera or projector has moved: run bricklayer-calibrate");
      set_status("drift above threshold: recalibrate");
      code = kExitDrift;
    } else {
      log::info(r.message, ": ok");
      set_status("ok");
    }
  }
  if (mode_ == Mode::kSelfCheck) finish(code);
}

// --scale-from-blocks: one more frame measured; after --scale-frames, correct and save the board scale.
void CalibrateNode::measure_scale(const image_t& m) {
  if (++scale_seen_ <= config_.skip_frames) return;
  const cv::Mat bgr = decode_frame(m);
  if (bgr.empty() || bgr.cols != calibration_->camera_width || bgr.rows != calibration_->camera_height) {
    error("undecodable camera frames", "camera frame " + std::to_string(m.frame_number) + " could not be decoded or is not " +
                                           std::to_string(calibration_->camera_width) + "x" +
                                           std::to_string(calibration_->camera_height) +
                                           " (the calibration's camera size); skipped");
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
  frame.bgr = bgr;
  frame.projector_image = scale_projector_image_;
  for (size_t i = before; i < scale_->measured().size(); ++i) {
    frame.lines.push_back(scale_->measured()[i]);
    for (double x : {scale_->measured()[i].left, scale_->measured()[i].right})
      if (const auto lean = measure_line_lean(green, *calibration_, x, 0.2 * h, 0.75 * h)) frame.leans.push_back({x, *lean});
  }
  scale_by_frame_.push_back(std::move(frame));
  log::debug("frame ", m.frame_number, ": ", blocks, " bottom-row blocks standing apart measured");
  if (++scale_frames_ < config_.scale_frames) return;
  scale_.reset();
  finish_scale();
}

void CalibrateNode::finish_scale() {
  // Under blur and noise a frame now and then counts a block too many (a shadow edge paired with a line)
  // or one too few: only the frames that count the blocks placed (--scale-blocks), or else the count most
  // frames agree on, are measured.
  std::map<int, int> counts;
  for (const ScaleFrame& f : scale_by_frame_) ++counts[f.blocks];
  int expected = config_.scale_blocks;
  if (expected == 0) {
    int best = 0;
    for (const auto& [count, frames] : counts)
      if (frames > best) best = frames, expected = count;  // ties: the smaller count (map order)
  }
  std::vector<detection::EndLines> lines;
  std::vector<LineLean> leans;
  std::vector<RefitFrame> frames;
  int kept = 0;
  std::ostringstream seen;
  for (const auto& [count, frames_counted] : counts) seen << (seen.tellp() > 0 ? ", " : "") << count << " in " << frames_counted;
  for (const ScaleFrame& f : scale_by_frame_) {
    if (f.blocks != expected) continue;
    ++kept;
    lines.insert(lines.end(), f.lines.begin(), f.lines.end());
    leans.insert(leans.end(), f.leans.begin(), f.leans.end());
    frames.push_back({f.bgr, f.projector_image, {calibration_->projector_width, calibration_->projector_height}});
  }
  scale_by_frame_.clear();
  set_value("scale_frames_used", kept);
  if (kept * 2 < config_.scale_frames) {
    const std::string why = "blocks counted per frame: " + seen.str() + " frames; only " + std::to_string(kept) + " of " +
                            std::to_string(config_.scale_frames) + " frames count " + std::to_string(expected) +
                            (config_.scale_blocks > 0 ? " (--scale-blocks)" : "") +
                            ": are the blocks standing apart, whole in view, the camera steady?";
    log::error("board scale not measured: ", why);
    set_status("scale not measured: " + why);
    end_scale(kExitRejected);
    return;
  }
  if (kept < config_.scale_frames)
    log::info("blocks counted per frame: ", seen.str(), " frames; measuring the ", kept, " that count ", expected);

  // First pass: the bottom row's lengths and the lean of its end lines.
  std::string why;
  const std::optional<detection::BoardCorrection> fit = detection::fit_board_correction(
      lines, detection::DetectorConfig{}.line_width, 2 * kept, config_.scale_max_residual, &why);
  if (!fit) {
    log::error("board scale not measured: ", why);
    set_status("scale not measured: " + why);
    end_scale(kExitRejected);
    return;
  }
  std::string lean_why;
  const std::optional<FrameLean> lean = fit_frame_lean(leans, fit->scale, fit->keystone, 2 * kept, &lean_why);
  if (!lean) log::warn("the lean of the board's vertical not measured (", lean_why, "): corrected along the board only");
  FrameCorrection first;
  first.scale = fit->scale;
  first.keystone = fit->keystone;
  first.shear = lean ? lean->shear : 0.0;
  first.vertical_keystone = lean ? lean->vertical_keystone : 0.0;
  // Second pass: the same frames in the first pass's frame, every row (board_frame_refit.h). Refused (no
  // blocks on rows up the board, or too few agree), the first pass stands.
  FrameCorrection total = first;
  double length_residual = fit->residual, lean_residual = lean ? lean->residual : -1.0;
  bool vertical_from_rows = false;
  std::string refit_text = "second pass refused";
  std::string refit_why;
  if (const auto refit = refit_board_frame(first.apply(*calibration_), frames, config_.scale_max_row, 2 * kept,
                                           config_.scale_max_residual, &refit_why)) {
    total = refit->correction.after(first);
    length_residual = refit->lengths.residual;
    vertical_from_rows = refit->height_span >= detection::kMinHeightForVerticalKeystone;
    if (!refit->lean) log::warn("second pass: the lean of the board's vertical not measured (", refit->lean_why, "): no shear");
    lean_residual = refit->lean ? refit->lean->residual : -1.0;
    std::ostringstream t;
    t.precision(4);
    t << "second pass: " << refit->lengths.blocks << " blocks on rows up to " << refit->highest_row << " (residual "
      << 100 * refit->lengths.residual << "%" << (vertical_from_rows ? ", the vertical keystone from their lengths" : "") << ")";
    refit_text = t.str();
    set_value("scale_highest_row", refit->highest_row);
  } else {
    log::info("no second pass of the board scale (", refit_why, "): the first pass's correction stands");
  }
  const double change = std::max(detection::BoardCorrection{total.scale, total.keystone}.max_change(kScaleCheckHalfWidth),
                                 frame_correction_change(total.scale, total.keystone, total.shear, total.vertical_keystone,
                                                         kScaleCheckHalfWidth, kScaleCheckHeight));
  set_value("scale", total.scale);
  set_value("keystone", total.keystone);
  set_value("shear", total.shear);
  set_value("vertical_keystone", total.vertical_keystone);
  set_value("block_length", fit->length_at(0.0));
  set_value("blocks_measured", fit->blocks);
  set_value("correction_max_change", change);
  std::ostringstream text;
  text.precision(4);
  text << "blocks read " << fit->length_at(-2.0) << ", " << fit->length_at(0.0) << " and " << fit->length_at(2.0)
       << " block lengths long 2 lengths left of the edge, at it and 2 right of it (" << fit->blocks << " measurements, "
       << fit->outliers << " dropped, residual " << 100 * fit->residual << "%); end lines lean "
       << (lean ? std::to_string(lean->lines) + " measured: shear " + std::to_string(lean->shear) + ", vertical keystone " +
                      std::to_string(lean->vertical_keystone)
                : std::string("not measured"))
       << "; " << refit_text << "; scale " << total.scale << ", keystone " << total.keystone << ", shear " << total.shear
       << ", vertical keystone " << total.vertical_keystone << "; the correction moves points within " << kScaleCheckHalfWidth
       << " lengths of the edge and " << kScaleCheckHeight << " above the surface by up to " << change;
  if (change < config_.scale_min_change) {
    log::info(text.str(), ": below --scale-min-change ", config_.scale_min_change, ", ", config_.output, " left as it is");
    set_status("ok: scale already right");
    end_scale(0);
    return;
  }
  // What the correction leaves, stated with it for vision's uncertainty (board_x_accuracy.h).
  const BoardXAccuracy accuracy = board_x_accuracy(length_residual, lean_residual, vertical_from_rows);
  set_value("board_x_accuracy_base", accuracy.base);
  set_value("board_x_accuracy_per_x", accuracy.per_x);
  set_value("board_x_accuracy_per_y", accuracy.per_y);
  calibration_t corrected = with_board_x_accuracy(total.apply(*calibration_), accuracy);
  corrected.utime = now();
  try {
    board::save_calibration(config_.output, corrected);
  } catch (const std::exception& e) {
    error("unwritable calibration files", e.what());
    set_status(std::string("scale not saved: ") + e.what());
    end_scale(kExitRejected);
    return;
  }
  log::info(text.str(), ": board scale corrected, saved ", config_.output, "; publishing on ", calibration_channel_);
  calibration_ = corrected;
  publish_calibration();
  set_status("ok");
  end_scale(0);
}

std::filesystem::file_time_type CalibrateNode::file_time() const {
  std::error_code ec;
  const auto t = std::filesystem::last_write_time(config_.output, ec);
  return ec ? std::filesystem::file_time_type{} : t;
}

// --serve: the file was rewritten (a new calibration or --scale-from-blocks): serve the new one. A file
// that no longer loads is a counted error and the previous calibration stays.
void CalibrateNode::reload_if_changed() {
  const auto t = file_time();
  if (t == file_time_) return;
  file_time_ = t;
  if (!std::filesystem::exists(config_.output)) {
    log::warn(config_.output, " was removed; still serving the calibration read before");
    return;
  }
  try {
    calibration_ = board::load_calibration(config_.output);
    log::info("re-read ", config_.output, ": it changed");
    set_status("ok");
  } catch (const std::exception& e) {
    error("unusable calibration files", load_error("re-reading " + config_.output + ": ", e) +
                                            (calibration_ ? "; still serving the previous calibration" : ""));
  }
}

void CalibrateNode::finish(int code) {
  exit_code_ = code;
  finished_ = true;
  stop();  // run() returns after this step, with a last heartbeat carrying the final status
}

}  // namespace bricklayer::calibration
