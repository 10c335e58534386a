// bricklayer-simcam: a simulated camera, so the whole exhibit runs without hardware.
//
// Plays a scenario (launch/scenarios/*.json: a scripted player's stacks over time) through the
// render library and publishes what a webcam behind the board would capture.
// Subscribes: BL_PROJECTOR (projector_state_t): what the projector shows now; its light is drawn into
//             every following frame, leaking into green through the colour mixing matrix (closed loop).
// Publishes:  BL_IMAGE (image_t, JPEG or PNG) at --fps, frame numbers from 0, capture utime = wall clock.
//             BL_TRUTH (stack_t) the scenario's true stack for each frame (same utime and frame number),
//             so end-to-end tests and benchmarks can compare what vision saw with what was there.
//             BL_HEARTBEAT once a second.
// Frames are a pure function of (scenario, seed, frame number, projector image): scenario time is
// frame_number / fps, and the wall clock only paces publication.
#include <chrono>
#include <cmath>

#include <opencv2/imgcodecs.hpp>

#include "bricklayer/common/channels.h"
#include "bricklayer/common/flags.h"
#include "bricklayer/common/lcm_url.h"
#include "bricklayer/common/log.h"
#include "bricklayer/common/module.h"
#include "bricklayer/image_t.hpp"
#include "bricklayer/projector_state_t.hpp"
#include "bricklayer/simcam/render.h"
#include "bricklayer/simcam/scenario.h"
#include "bricklayer/stack_t.hpp"

namespace {

using namespace bricklayer;

struct SimcamConfig {
  simcam::Scenario scenario;
  std::string scenario_name;
  double fps = 30.0;
  bool loop = false;
  bool use_projector = true;
  int64_t max_frames = 0;  // 0: until the scenario ends (or forever with loop)
  std::string format = "jpeg";
  int jpeg_quality = 90;
  uint64_t setup_seed = 0;
};

stack_t to_truth_message(const core::Stack& stack, const std::vector<simcam::TrueBlock>& truth) {
  stack_t s{};
  s.block_length = 1.0;
  s.block_height = stack.block_height / stack.block_length;
  s.table_edge = 0.0;
  s.status = stack_t::STATUS_OK;
  for (const auto& t : truth) {
    block_t b{};
    b.id = t.id;
    b.row = t.row;
    b.x = t.x;
    for (int i = 0; i < 4; ++i) {
      b.corner_u[i] = t.corners[i].x;
      b.corner_v[i] = t.corners[i].y;
    }
    b.confidence = 1.0;
    s.blocks.push_back(b);
  }
  s.num_blocks = static_cast<int32_t>(s.blocks.size());
  return s;
}

class SimcamProcess {
 public:
  SimcamProcess(const std::string& url, SimcamConfig config)
      : module_("simcam", url),
        config_(std::move(config)),
        renderer_(config_.setup_seed ? simcam::CameraSetup::random(config_.setup_seed) : simcam::CameraSetup{},
                  config_.setup_seed ? simcam::ProjectorSetup::random(config_.setup_seed) : simcam::ProjectorSetup{}),
        image_channel_(channel(kImageChannel)),
        truth_channel_(channel(kTruthChannel)) {
    if (config_.use_projector) {
      module_.subscribe<projector_state_t>(
          channel(kProjectorChannel), [this](const projector_state_t& p) { HandleProjector(p); }, 32 << 20);
    }
    log::info("playing ", config_.scenario_name, " (", config_.scenario.description, ") at ", config_.fps,
              " fps, nuisance ", config_.scenario.nuisance.name, config_.loop ? ", looping" : "");
  }

  int Run() {
    started_ = std::chrono::steady_clock::now();
    return module_.run([this] { Tick(); }, 2);
  }

 private:
  void HandleProjector(const projector_state_t& p) {
    const image_t& im = p.image;
    if (im.size <= 0 || im.size != static_cast<int32_t>(im.data.size())) {
      ++module_.counters().errors;
      return;
    }
    cv::Mat bgr = cv::imdecode(cv::Mat(1, im.size, CV_8UC1, const_cast<uint8_t*>(im.data.data())), cv::IMREAD_COLOR);
    if (bgr.empty() || bgr.cols > 8192 || bgr.rows > 8192) {
      ++module_.counters().errors;
      log::warn("undecodable projector image (", im.size, " bytes)");
      return;
    }
    projector_image_ = bgr;
  }

  void Tick() {
    auto due = started_ + std::chrono::microseconds(static_cast<int64_t>(1e6 * frame_number_ / config_.fps));
    if (std::chrono::steady_clock::now() < due) return;
    double t = frame_number_ / config_.fps;
    if (t >= config_.scenario.duration_s) {
      if (!config_.loop) return Finish("scenario finished");
      t = std::fmod(t, config_.scenario.duration_s);
    }
    if (config_.max_frames > 0 && frame_number_ >= config_.max_frames) return Finish("frame limit reached");

    const core::Stack& stack = config_.scenario.stack_at(t);
    simcam::Nuisance nuisance = config_.scenario.nuisance;
    nuisance.layout_seed = config_.scenario.seed;
    nuisance.time_s = t;
    simcam::Rendered frame = renderer_.render(stack, nuisance, projector_image_.empty() ? nullptr : &projector_image_,
                                              config_.scenario.seed + static_cast<uint64_t>(frame_number_));
    std::vector<uint8_t> bytes;
    if (config_.format == "png") {
      cv::imencode(".png", frame.bgr, bytes);
    } else {
      cv::imencode(".jpg", frame.bgr, bytes, {cv::IMWRITE_JPEG_QUALITY, config_.jpeg_quality});
    }
    image_t im{};
    im.utime = wall_utime();
    im.frame_number = frame_number_;
    im.width = frame.bgr.cols;
    im.height = frame.bgr.rows;
    im.format = config_.format == "png" ? int32_t{image_t::FORMAT_PNG} : int32_t{image_t::FORMAT_JPEG};
    im.source = "simcam:" + config_.scenario_name;
    im.data = std::move(bytes);
    im.size = static_cast<int32_t>(im.data.size());
    stack_t truth = to_truth_message(stack, frame.truth);
    truth.utime = im.utime;
    truth.frame_number = im.frame_number;
    module_.publish(image_channel_, im);
    module_.lcm().publish(truth_channel_, &truth);  // a test aid, not counted as output
    ++frame_number_;
  }

  void Finish(const char* why) {
    log::info(why, " after ", frame_number_, " frames");
    Module::request_stop();
  }

  Module module_;  // owns the LCM handle; declared before everything that subscribes through it
  SimcamConfig config_;
  simcam::Renderer renderer_;
  std::string image_channel_, truth_channel_;
  cv::Mat projector_image_;
  int64_t frame_number_ = 0;
  std::chrono::steady_clock::time_point started_;
};

int Main(int argc, char** argv) {
  Flags flags("bricklayer-simcam", "A simulated camera: renders a scenario's stacks into realistic frames on BL_IMAGE.");
  flags.add("scenario", "", "scenario file (launch/scenarios/*.json); required");
  flags.add("fps", "30", "frames per second (1..240)");
  flags.add_bool("loop", "start the scenario again when it ends (else exit)");
  flags.add("frames", "0", "stop after this many frames (0: no limit)");
  flags.add("format", "jpeg", "frame encoding: jpeg or png");
  flags.add("jpeg-quality", "90", "JPEG quality 1..100");
  flags.add("seed", "", "override the scenario's seed");
  flags.add("nuisance", "", "override the scenario's nuisance level: clean, mild, strong, harsh");
  flags.add("setup-seed", "0", "0: the default camera/projector setup; N: a random setup (for calibration)");
  flags.add_bool("no-projector", "ignore BL_PROJECTOR (no projected light in the frames)");
  flags.add("lcm-url", "", "LCM URL (default: LCM_DEFAULT_URL, else host-only udpm ttl=0)");
  flags.add("log-level", "info", "debug, info, warn or error");
  if (!flags.parse(argc, argv)) return 0;
  log::set_level(log::parse_level(flags.get("log-level")));

  if (flags.get("scenario").empty()) throw FlagError("--scenario FILE is required (see launch/scenarios/)");
  SimcamConfig config;
  config.scenario = simcam::load_scenario(flags.get("scenario"));
  config.scenario_name = flags.get("scenario");
  if (auto slash = config.scenario_name.find_last_of('/'); slash != std::string::npos)
    config.scenario_name = config.scenario_name.substr(slash + 1);
  config.fps = flags.get_double("fps");
  if (config.fps < 1 || config.fps > 240) throw FlagError("--fps must be between 1 and 240");
  config.loop = flags.get_bool("loop");
  config.max_frames = flags.get_int("frames");
  if (config.max_frames < 0) throw FlagError("--frames must be >= 0");
  config.format = flags.get("format");
  if (config.format != "jpeg" && config.format != "png") throw FlagError("--format must be jpeg or png");
  config.jpeg_quality = static_cast<int>(flags.get_int("jpeg-quality"));
  if (config.jpeg_quality < 1 || config.jpeg_quality > 100) throw FlagError("--jpeg-quality must be 1..100");
  if (flags.was_set("seed")) {
    int64_t seed = flags.get_int("seed");
    if (seed < 0) throw FlagError("--seed must be >= 0");
    config.scenario.seed = static_cast<uint64_t>(seed);
  }
  if (!flags.get("nuisance").empty()) config.scenario.nuisance = simcam::Nuisance::named(flags.get("nuisance"));
  int64_t setup_seed = flags.get_int("setup-seed");
  if (setup_seed < 0) throw FlagError("--setup-seed must be >= 0");
  config.setup_seed = static_cast<uint64_t>(setup_seed);
  config.use_projector = !flags.get_bool("no-projector");

  std::string url = resolve_lcm_url(flags.get("lcm-url"));
  check_lcm_url(url);
  SimcamProcess process(url, std::move(config));
  return process.Run();
}

}  // namespace

int main(int argc, char** argv) { return bricklayer::run_main("bricklayer-simcam", &Main, argc, argv); }
