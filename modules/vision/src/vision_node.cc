#include "bricklayer/vision/vision_node.h"

#include <algorithm>
#include <iostream>
#include <sstream>

#include <opencv2/imgcodecs.hpp>
#include <opencv2/imgproc.hpp>

#include "bricklayer/board/board_geometry.h"
#include "bricklayer/board/calibration_file.h"
#include "bricklayer/common/channels.h"
#include "bricklayer/common/log.h"
#include "bricklayer/frames/image_codec.h"
#include "bricklayer/messages/timing.h"
#include "bricklayer/runtime/codec.h"
#include "bricklayer/vision/stack_message.h"

namespace bricklayer::vision {
namespace {

using detection::DetectedBlock;
using detection::Detection;
using detection::Detector;

cv::Mat read_image_file(const std::filesystem::path& path) {
  try {
    return cv::imread(path.string(), cv::IMREAD_COLOR);
  } catch (const cv::Exception&) {
    return {};
  }
}

// The detector of a configuration: the board geometry, then the calibration file when one is given.
Detector make_detector(const VisionConfig& c, std::optional<calibration_t>* calibration) {
  BoardGeometry geometry;
  if (!c.board.empty()) geometry = load_board_geometry(c.board);
  Detector detector(geometry);
  if (!c.calibration.empty()) {
    // The strict loader bricklayer-calibrate's files are checked with; its errors name the file and key.
    const calibration_t loaded = board::load_calibration(c.calibration);
    try {
      detector.set_calibration(loaded);
    } catch (const std::invalid_argument& e) {
      throw std::runtime_error("--calibration " + c.calibration + ": " + e.what());
    }
    if (calibration) *calibration = loaded;
  }
  return detector;
}

std::unique_ptr<frames::FrameSource> open_source(const VisionConfig& c) {
  if (!c.camera.empty()) return frames::open_camera(c.camera, 0, 0);
  if (!c.video.empty()) return frames::open_video(c.video, c.rate, false);
  if (!c.images.empty()) return frames::open_folder(c.images, c.rate, false);
  return nullptr;
}

// "N/M" -> {N, M}; nullopt when it is not two integers around a slash.
std::optional<std::pair<int, int>> parse_confirm(const std::string& text) {
  int hits = 0, window = 0;
  char slash = 0;
  std::istringstream in(text);
  if (!(in >> hits >> slash >> window) || slash != '/' || in.peek() != EOF) return std::nullopt;
  return std::make_pair(hits, window);
}

}  // namespace

std::string VisionConfig::confirm_rule(const std::string& text) {
  const auto c = parse_confirm(text);
  if (!c) return "must be N/M, e.g. 2/3";
  if (c->first < 1 || c->first > c->second) return "must be N/M with 1 <= N <= M, got " + text;
  return "";
}

TemporalFilterConfig VisionConfig::filter() const {
  TemporalFilterConfig f;
  if (const std::string why = confirm_rule(confirm); !why.empty()) throw std::invalid_argument("--confirm " + why);
  const auto c = parse_confirm(confirm);
  f.confirm_hits = c->first;
  f.confirm_window = c->second;
  f.hold_frames = hold;
  f.deadband = deadband;
  TemporalFilter check(f);  // validates, throws with a fixable message
  return f;
}

void VisionNode::check(const Config& c) {
  const int sources = !c.camera.empty() + !c.video.empty() + !c.images.empty();
  if (sources > 1) throw std::invalid_argument("give at most one of --camera, --video, --images");
  if (c.json && c.images.empty()) throw std::invalid_argument("--json needs --images DIR");
  c.filter();
}

std::optional<int> VisionNode::before_bus(const Config& c) {
  if (!c.json) return std::nullopt;
  Detector detector = make_detector(c, nullptr);
  int failures = 0;
  for (const auto& path : frames::list_image_files(c.images)) {
    const cv::Mat frame = read_image_file(path);
    Detection d;
    if (frame.empty()) {
      d.status = Detection::kNoFrame;
    } else {
      d = detector.detect(frame);
      make_publishable(d.blocks, detector.frame(), frame.size());
    }
    if (d.status != Detection::kOk) {
      ++failures;
      log::warn(path.filename().string(), ": ",
                d.status == Detection::kNoFrame ? "unreadable or wrongly sized image" : "board not visible");
    }
    std::cout << to_predict_json(d, detector.frame()) << "\n";
  }
  std::cout.flush();
  return failures == 0 ? 0 : 1;
}

VisionNode::VisionNode(const Config& config, runtime::Bus& bus)
    : Node("vision", bus),
      detector_(make_detector(config, &calibration_)),
      filter_((check(config), config.filter())),
      use_filter_(!config.no_filter),
      source_(open_source(config)),
      require_calibration_(config.require_calibration),
      min_uncertainty_(config.min_uncertainty),
      stack_channel_(channel(kStackChannel)),
      timing_channel_(channel(kTimingChannel)) {
  if (require_calibration_ && !calibration_) {
    log::info("waiting for a calibration on ", channel(kCalibrationChannel),
              " (bricklayer-calibrate --serve) before publishing stacks");
    set_status("waiting for a calibration");
  }
  if (source_) {
    source_period_us_ = static_cast<int64_t>(1e6 / source_->rate());
    next_frame_utime_ = now();
    set_tick_ms(5);
  } else {
    const std::string images = channel(kImageChannel);
    subscribe<image_t>(images, runtime::QueuePolicy::newest(), [this](const image_t& m) { on_image(m); }, 64u << 20);
    watch_input(images, kStaleAfterS, "no frames");
  }
  subscribe<calibration_t>(channel(kCalibrationChannel), runtime::QueuePolicy::newest(),
                           [this](const calibration_t& m) { on_calibration(m); });
  subscribe<projector_state_t>(channel(kProjectorChannel), runtime::QueuePolicy::newest(),
                               [this](const projector_state_t& m) { on_projector(m); });
}

void VisionNode::on_image(const image_t& image) {
  const int64_t received = now();
  const messages::Stopwatch watch;  // the stage's time includes decoding the frame
  std::string error;
  const cv::Mat frame = frames::decode_image(image, &error);
  process(frame, image.utime, image.frame_number, received, error, watch.elapsed_us());
}

void VisionNode::on_calibration(const calibration_t& calibration) {
  // bricklayer-calibrate --serve republishes the same calibration every few seconds so that restarted
  // modules catch up: the one in use is kept as it is (remap tables, temporal filter).
  if (calibration_ && runtime::encode(*calibration_) == runtime::encode(calibration)) return;
  // Both throw on a bad calibration (a counted error; the previous calibration stays in use).
  board::validate_calibration(calibration);
  detector_.set_calibration(calibration);
  calibration_ = calibration;
  filter_.reset();
  if (status() == "waiting for a calibration") set_status("ok");
  log::info("calibration applied: board frame ", detector_.frame().size().width, "x", detector_.frame().size().height,
            ", ", detector_.frame().geometry().block_length_px, " px per block");
}

void VisionNode::on_projector(const projector_state_t& state) {
  std::string error;
  const cv::Mat image = frames::decode_image(state.image, &error);
  if (image.empty()) throw std::runtime_error("projector image: " + error);  // a counted error
  cv::Mat bgr = image;
  if (image.channels() == 1) cv::cvtColor(image, bgr, cv::COLOR_GRAY2BGR);
  const cv::Size projector_size = calibration_ ? cv::Size(calibration_->projector_width, calibration_->projector_height)
                                               : cv::Size(kDefaultProjectorWidth, kDefaultProjectorHeight);
  detector_.set_projector_image(bgr, projector_size);
}

void VisionNode::tick() {
  if (source_ && !source_done_) read_source();
}

void VisionNode::read_source() {
  // A live camera paces itself (next() waits for the newest frame); files are paced at their rate by
  // the bus clock.
  if (!source_->live()) {
    if (now() < next_frame_utime_) {
      wake_at(next_frame_utime_);
      return;
    }
    next_frame_utime_ += source_period_us_;
    wake_at(next_frame_utime_);
  }
  const messages::Stopwatch watch;
  cv::Mat frame;
  const bool got = source_->next(frame);
  own_counters().errors += source_->unreadable() - unreadable_seen_;  // skipped images are errors
  unreadable_seen_ = source_->unreadable();
  if (!got) {
    source_done_ = true;
    log::info(source_->describe(), " exhausted after ", frames_seen_, " frames");
    set_status("source exhausted");
    return;
  }
  count_received();
  // Files carry no capture time: their utime is the frame's place in the sequence at the source's rate,
  // so a replay of the same folder or video gives the same messages.
  const int64_t number = source_frames_++;
  const int64_t utime = source_->live() ? now() : static_cast<int64_t>(static_cast<double>(number) * 1e6 / source_->rate());
  process(frame, utime, number, now(), "", watch.elapsed_us());
}

double VisionNode::block_uncertainty(const DetectedBlock& b, double measured, double temporal, double lag) const {
  // The calibration's residual where the block stands (its left end, half way up its row).
  const double floor = calibration_ ? calibration_floor(*calibration_, b.x, (b.row + 0.5) * block_height_blocks(detector_.frame())) : 0.0;
  return published_uncertainty(measured, temporal, lag, floor, min_uncertainty_);
}

void VisionNode::process(const cv::Mat& frame, int64_t utime, int64_t frame_number, int64_t received_utime,
                         const std::string& decode_error, int64_t elapsed_before_us) {
  ++frames_seen_;
  // --require-calibration: stacks measured in the uncalibrated default frame would be wrong, so a
  // restarted vision publishes nothing until bricklayer-calibrate --serve's next publication.
  if (require_calibration_ && !calibration_) return;
  const messages::Stopwatch watch;
  Detection d;
  std::vector<double> uncertainties;  // per block of d.blocks: this frame's measurement
  if (frame.empty()) {
    d.status = Detection::kNoFrame;
  } else {
    d = detector_.detect(frame);
    // Each block's own measurement uncertainty, from the pixels it was measured in (before the publishing
    // rules move touching blocks: the lines are where the detector found them).
    const std::vector<BlockEvidence> evidence = measure_evidence(frame, detector_.frame(), d.blocks);
    struct Measured {
      DetectedBlock block;
      double uncertainty;
    };
    std::vector<Measured> measured;
    for (size_t i = 0; i < d.blocks.size(); ++i)
      measured.push_back({d.blocks[i], frame_uncertainty(evidence[i], detector_.frame().geometry().block_length_px)});
    published_ += make_publishable(measured, [](Measured& m) -> DetectedBlock& { return m.block; }, detector_.frame(),
                                   frame.size());
    d.blocks.clear();
    uncertainties.clear();
    for (const Measured& m : measured) d.blocks.push_back(m.block), uncertainties.push_back(m.uncertainty);
  }
  stack_t out;
  std::vector<double> published_u;
  if (d.status == Detection::kNoFrame) {
    error("bad frames", decode_error.empty()
                            ? "frame " + std::to_string(frame_number) + ": empty or wrongly sized for the calibration"
                            : decode_error);
    out = no_frame_stack(detector_.frame(), utime, frame_number);
  } else if (d.status == Detection::kNoBoard) {
    out = to_stack_message(d, detector_.frame(), utime, frame_number);
  } else if (use_filter_) {
    // The filter holds lost blocks and keeps positions inside its deadband: apply the publishing rules
    // again to what it returns.
    std::vector<FilteredBlock> blocks = filter_.update(d.blocks, uncertainties);
    published_ += make_publishable(blocks, [](FilteredBlock& b) -> DetectedBlock& { return b.block; },
                                   detector_.frame(), frame.size());
    for (const FilteredBlock& b : blocks)
      published_u.push_back(block_uncertainty(b.block, b.measured_uncertainty,
                                              temporal_uncertainty(b.spread, b.spread_samples), b.lag));
    out = to_stack_message(blocks, detector_.frame(), utime, frame_number, published_u);
  } else {
    for (size_t i = 0; i < d.blocks.size(); ++i) published_u.push_back(block_uncertainty(d.blocks[i], uncertainties[i], 0.0, 0.0));
    out = to_stack_message(d, detector_.frame(), utime, frame_number, published_u);
  }
  const int64_t elapsed = elapsed_before_us + watch.elapsed_us();
  publish(stack_channel_, out);
  publish_report(timing_channel_, messages::make_timing("vision", "detect", utime, frame_number, elapsed, received_utime));
  set_value("blocks", out.num_blocks);
  set_value("lines", d.lines);
  set_value("rejected_wide", d.rejected_wide);
  set_value("rejected_faint", d.rejected_faint);
  // Totals since start: what the publishing rules changed (publishable.h).
  set_value("moved_total", static_cast<double>(published_.moved));
  set_value("dropped_overlap_total", static_cast<double>(published_.dropped_overlap));
  set_value("dropped_border_total", static_cast<double>(published_.dropped_border));
  if (!published_u.empty()) {
    std::nth_element(published_u.begin(), published_u.begin() + static_cast<std::ptrdiff_t>(published_u.size() / 2),
                     published_u.end());
    set_value("uncertainty_median", published_u[published_u.size() / 2]);
  }
  set_value("detect_ms", static_cast<double>(elapsed) / 1000.0);
  if (!source_done_) set_status(d.status == Detection::kNoBoard ? "board not visible" : "ok");
}

}  // namespace bricklayer::vision
