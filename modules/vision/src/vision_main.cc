// bricklayer-vision: blocks from camera frames.
//
// Subscribes: BL_IMAGE (image_t: JPEG, PNG, GRAY8 or BGR8; newest wins) unless a direct source is given
//             (--camera N, --video FILE, --images DIR), BL_CALIBRATION (calibration_t: rectification,
//             colour mixing), BL_PROJECTOR (projector_state_t: what the projector shows, whose red/blue
//             leakage into green is subtracted).
// Publishes:  BL_STACK (stack_t, one per frame, carrying the frame's utime and frame_number;
//             STATUS_NO_FRAME for a corrupt, empty, truncated or wrongly sized frame; never a stack
//             bricklayer-prediction rejects: see publishable.h; none at all with --require-calibration
//             until a calibration is loaded or arrives), BL_TIMING (timing_t, stage "detect"),
//             BL_HEARTBEAT (counters; values: blocks, lines, rejected_wide, rejected_faint, and totals
//             moved_total, dropped_overlap_total, dropped_border_total).
// Offline:    --images DIR --json prints one bricklayer-predict input line per image (name order),
//             without the bus and without temporal filtering.
#include <algorithm>
#include <chrono>
#include <filesystem>
#include <iostream>
#include <memory>
#include <optional>
#include <string>
#include <vector>

#include <opencv2/imgcodecs.hpp>
#include <opencv2/imgproc.hpp>

#include "bricklayer/board/calibration_file.h"
#include "bricklayer/frames/frame_source.h"
#include "bricklayer/frames/image_codec.h"
#include "bricklayer/board/board_geometry.h"
#include "bricklayer/common/channels.h"
#include "bricklayer/common/flags.h"
#include "bricklayer/common/lcm_url.h"
#include "bricklayer/common/log.h"
#include "bricklayer/common/module.h"
#include "bricklayer/projector_state_t.hpp"
#include "bricklayer/timing_t.hpp"
#include "bricklayer/detection/detector.h"
#include "bricklayer/vision/publishable.h"
#include "bricklayer/vision/stack_message.h"
#include "bricklayer/vision/temporal_filter.h"

namespace bricklayer::vision {
namespace {

using detection::DetectedBlock;
using detection::Detection;
using detection::Detector;
using frames::decode_image;

constexpr const char* kModuleName = "vision";

cv::Mat read_image_file(const std::filesystem::path& path) {
  try {
    return cv::imread(path.string(), cv::IMREAD_COLOR);
  } catch (const cv::Exception&) {
    return {};
  }
}

// --images DIR --json: one predict-input line per image, no bus, no filter.
int run_offline(const std::string& dir, Detector& detector) {
  int failures = 0;
  for (const auto& path : frames::list_image_files(dir)) {
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
      log::warn(path.filename().string(), ": ", d.status == Detection::kNoFrame ? "unreadable or wrongly sized image"
                                                                                  : "board not visible");
    }
    std::cout << to_predict_json(d, detector.frame()) << "\n";
  }
  std::cout.flush();
  return failures == 0 ? 0 : 1;
}

class Vision {
 public:
  Vision(const std::string& url, Detector detector, const TemporalFilterConfig& filter_config, bool filter,
         std::unique_ptr<frames::FrameSource> source, std::optional<calibration_t> calibration, bool require_calibration)
      : module_(kModuleName, url),
        detector_(std::move(detector)),
        filter_(filter_config),
        use_filter_(filter),
        source_(std::move(source)),
        period_(std::chrono::microseconds(source_ ? static_cast<int64_t>(1e6 / source_->rate()) : 0)),
        frames_(module_.counters()),
        calibration_(std::move(calibration)),
        require_calibration_(require_calibration),
        stack_channel_(channel(kStackChannel)),
        timing_channel_(channel(kTimingChannel)) {
    if (require_calibration_ && !calibration_) {
      log::info("waiting for a calibration on ", channel(kCalibrationChannel),
                " (bricklayer-calibrate --serve) before publishing stacks");
      module_.set_status("waiting for a calibration");
    }
    if (!source_) {
      module_.subscribe<image_t>(channel(kImageChannel), [this](const image_t& m) { HandleImage(m); },
                                 64 << 20, 8);
    }
    module_.subscribe<calibration_t>(channel(kCalibrationChannel),
                                     [this](const calibration_t& m) { HandleCalibration(m); });
    module_.subscribe<projector_state_t>(channel(kProjectorChannel),
                                         [this](const projector_state_t& m) { HandleProjector(m); });
  }

  int Run() {
    next_frame_ = std::chrono::steady_clock::now();
    return module_.run([this] { Tick(); }, 5);
  }

 private:
  void HandleImage(const image_t& image) { frames_.put({image, wall_utime()}); }

  void HandleCalibration(const calibration_t& calibration) {
    // bricklayer-calibrate --serve republishes the same calibration every few seconds so that restarted
    // modules catch up: the one in use is kept as it is (remap tables, temporal filter).
    if (calibration_ && same_message(*calibration_, calibration)) return;
    // Both throw on a bad calibration (a counted error; the previous calibration stays in use).
    board::validate_calibration(calibration);
    detector_.set_calibration(calibration);
    calibration_ = calibration;
    filter_.reset();
    log::info("calibration applied: board frame ", detector_.frame().size().width, "x",
              detector_.frame().size().height, ", ", detector_.frame().geometry().block_length_px, " px per block");
  }

  void HandleProjector(const projector_state_t& state) {
    std::string error;
    const cv::Mat image = decode_image(state.image, &error);
    if (image.empty()) throw std::runtime_error("projector image: " + error);
    cv::Mat bgr = image;
    if (image.channels() == 1) cv::cvtColor(image, bgr, cv::COLOR_GRAY2BGR);
    const cv::Size projector_size = calibration_ ? cv::Size(calibration_->projector_width, calibration_->projector_height)
                                                 : cv::Size(kDefaultProjectorWidth, kDefaultProjectorHeight);
    detector_.set_projector_image(bgr, projector_size);
  }

  void Tick() {
    if (source_) {
      // A live camera paces itself (next() waits for the newest frame); files are paced at their rate.
      if (source_done_ || (!source_->live() && std::chrono::steady_clock::now() < next_frame_)) return;
      next_frame_ += period_;
      cv::Mat frame;
      const bool got = source_->next(frame);
      module_.counters().errors += source_->unreadable() - unreadable_seen_;  // skipped images are errors
      unreadable_seen_ = source_->unreadable();
      if (!got) {
        source_done_ = true;
        log::info(source_->describe(), " exhausted after ", frames_seen_, " frames");
        module_.set_status("source exhausted");
        return;
      }
      ++module_.counters().received;
      // Files carry no capture time: their utime is the frame's place in the sequence at the source's
      // rate, so a replay of the same folder or video gives the same messages.
      const int64_t number = source_frames_++;
      const int64_t utime = source_->live() ? wall_utime() : static_cast<int64_t>(number * 1e6 / source_->rate());
      Process(frame, utime, number, wall_utime(), "", std::chrono::steady_clock::now());
      return;
    }
    auto item = frames_.take();
    if (!item) return;
    std::string error;
    const auto start = std::chrono::steady_clock::now();  // the stage's time includes decoding the frame
    const cv::Mat frame = decode_image(item->image, &error);
    Process(frame, item->image.utime, item->image.frame_number, item->received_utime, error, start);
  }

  void Process(const cv::Mat& frame, int64_t utime, int64_t frame_number, int64_t received_utime,
               const std::string& decode_error, std::chrono::steady_clock::time_point start) {
    ++frames_seen_;
    // --require-calibration: stacks measured in the uncalibrated default frame would be wrong, so a
    // restarted vision publishes nothing until bricklayer-calibrate --serve's next publication.
    if (require_calibration_ && !calibration_) return;
    Detection d;
    if (frame.empty()) {
      d.status = Detection::kNoFrame;
    } else {
      d = detector_.detect(frame);
      published_ += make_publishable(d.blocks, detector_.frame(), frame.size());
    }
    stack_t out;
    if (d.status == Detection::kNoFrame) {
      ++module_.counters().errors;
      log::warn(decode_error.empty() ? "frame " + std::to_string(frame_number) + ": empty or wrongly sized for the calibration"
                                     : decode_error);
      out = no_frame_stack(detector_.frame(), utime, frame_number);
    } else if (d.status == Detection::kNoBoard) {
      out = to_stack_message(d, detector_.frame(), utime, frame_number);
    } else if (use_filter_) {
      // The filter holds lost blocks and keeps positions inside its deadband: apply the publishing rules
      // again to what it returns.
      std::vector<FilteredBlock> blocks = filter_.update(d.blocks);
      published_ += make_publishable(blocks, [](FilteredBlock& b) -> DetectedBlock& { return b.block; },
                                     detector_.frame(), frame.size());
      out = to_stack_message(blocks, detector_.frame(), utime, frame_number);
    } else {
      out = to_stack_message(d, detector_.frame(), utime, frame_number);
    }
    const int64_t elapsed =
        std::chrono::duration_cast<std::chrono::microseconds>(std::chrono::steady_clock::now() - start).count();
    module_.publish(stack_channel_, out);
    timing_t t{};
    t.utime = utime;
    t.frame_number = frame_number;
    t.module = kModuleName;
    t.stage = "detect";
    t.elapsed_us = elapsed;
    t.received_utime = received_utime;
    module_.lcm().publish(timing_channel_, &t);
    module_.set_value("blocks", out.num_blocks);
    module_.set_value("lines", d.lines);
    module_.set_value("rejected_wide", d.rejected_wide);
    module_.set_value("rejected_faint", d.rejected_faint);
    // Totals since start: what the publishing rules changed (publishable.h).
    module_.set_value("moved_total", published_.moved);
    module_.set_value("dropped_overlap_total", published_.dropped_overlap);
    module_.set_value("dropped_border_total", published_.dropped_border);
    module_.set_value("detect_ms", elapsed / 1000.0);
    module_.set_status(d.status == Detection::kNoBoard ? "board not visible" : "ok");
  }

  struct Frame {
    image_t image;
    int64_t received_utime;
  };
  Module module_;  // declared first: owns the bus the handlers below use
  Detector detector_;
  TemporalFilter filter_;
  bool use_filter_;
  std::unique_ptr<frames::FrameSource> source_;
  int64_t unreadable_seen_ = 0;
  bool source_done_ = false;
  int64_t source_frames_ = 0;
  std::chrono::steady_clock::duration period_;
  std::chrono::steady_clock::time_point next_frame_;
  Latest<Frame> frames_;
  std::optional<calibration_t> calibration_;
  bool require_calibration_;
  int64_t frames_seen_ = 0;
  PublishCounts published_;
  std::string stack_channel_, timing_channel_;
};

int Main(int argc, char** argv) {
  Flags flags("bricklayer-vision", "Blocks from camera frames: image_t on BL_IMAGE (or a camera, video or folder) -> stack_t on BL_STACK.");
  flags.add("lcm-url", "", "LCM URL (default: LCM_DEFAULT_URL, else host-only udpm ttl=0)");
  flags.add("log-level", "info", "debug, info, warn or error");
  flags.add("board", "", "board geometry JSON {edge_x_px, surface_y_px, block_length_px, block_height_px} used until a calibration arrives (default: the shared default setup)");
  flags.add("calibration", "", "calibration file written by bricklayer-calibrate (calibration.json, loaded strictly) to start with");
  flags.add_bool("require-calibration", "publish no stacks until a calibration is loaded (--calibration) or arrives on BL_CALIBRATION (the exhibit's profiles: bricklayer-calibrate --serve)");
  flags.add("camera", "", "read frames from this V4L2 camera (index or /dev/videoN) instead of BL_IMAGE");
  flags.add("video", "", "read frames from this video file instead of BL_IMAGE");
  flags.add("images", "", "read frames from the images in this folder (name order) instead of BL_IMAGE");
  flags.add("rate", "30", "frames per second for --video and --images");
  flags.add_bool("json", "with --images: print one bricklayer-predict input line per image and exit (no bus, no filter)");
  flags.add_bool("no-filter", "publish raw detections (no temporal filter)");
  flags.add("confirm", "2/3", "temporal filter: seen in N of the last M frames, as N/M");
  flags.add("hold", "3", "temporal filter: frames a lost block is held");
  flags.add("deadband", "0.01", "temporal filter: x changes smaller than this (block lengths) are not published");
  if (!flags.parse(argc, argv)) return 0;
  log::set_module(kModuleName);
  log::set_level(log::parse_level(flags.get("log-level")));

  BoardGeometry geometry;
  if (!flags.get("board").empty()) geometry = load_board_geometry(flags.get("board"));
  Detector detector(geometry);
  std::optional<calibration_t> calibration;
  if (!flags.get("calibration").empty()) {
    // The strict loader bricklayer-calibrate's files are checked with; its errors name the file and key.
    const calibration_t loaded = board::load_calibration(flags.get("calibration"));
    try {
      detector.set_calibration(loaded);
    } catch (const std::invalid_argument& e) {
      throw std::runtime_error("--calibration " + flags.get("calibration") + ": " + e.what());
    }
    calibration = loaded;
  }

  const int sources = !flags.get("camera").empty() + !flags.get("video").empty() + !flags.get("images").empty();
  if (sources > 1) throw FlagError("give at most one of --camera, --video, --images");
  if (flags.get_bool("json")) {
    if (flags.get("images").empty()) throw FlagError("--json needs --images DIR");
    return run_offline(flags.get("images"), detector);
  }

  TemporalFilterConfig filter_config;
  {
    const std::string confirm = flags.get("confirm");
    const auto slash = confirm.find('/');
    try {
      if (slash == std::string::npos) throw std::invalid_argument(confirm);
      filter_config.confirm_hits = std::stoi(confirm.substr(0, slash));
      filter_config.confirm_window = std::stoi(confirm.substr(slash + 1));
    } catch (const std::exception&) {
      throw FlagError("--confirm must be N/M, e.g. 2/3");
    }
    filter_config.hold_frames = static_cast<int>(flags.get_int("hold"));
    filter_config.deadband = flags.get_double("deadband");
    TemporalFilter check(filter_config);  // validates, throws with a fixable message
  }
  const double rate = flags.get_double("rate");
  if (!(rate > 0 && rate <= 1000)) throw FlagError("--rate must be in (0, 1000]");

  std::unique_ptr<frames::FrameSource> source;
  if (!flags.get("camera").empty()) {
    source = frames::open_camera(flags.get("camera"), 0, 0);
  } else if (!flags.get("video").empty()) {
    source = frames::open_video(flags.get("video"), rate, false);
  } else if (!flags.get("images").empty()) {
    source = frames::open_folder(flags.get("images"), rate, false);
  }

  const std::string url = resolve_lcm_url(flags.get("lcm-url"));
  check_lcm_url(url);
  Module::install_signal_handlers();
  Vision vision(url, std::move(detector), filter_config, !flags.get_bool("no-filter"), std::move(source), calibration,
                flags.get_bool("require-calibration"));
  return vision.Run();
}

}  // namespace
}  // namespace bricklayer::vision

int main(int argc, char** argv) { return bricklayer::run_main("bricklayer-vision", &bricklayer::vision::Main, argc, argv); }
