#include "bricklayer/simcam/simcam_node.h"

#include <cmath>

#include <opencv2/imgcodecs.hpp>

#include "bricklayer/common/channels.h"
#include "bricklayer/common/log.h"
#include "bricklayer/image_t.hpp"
#include "bricklayer/stack_t.hpp"

namespace bricklayer::simcam {
namespace {

Scenario load_configured(const SimcamConfig& c) {
  runtime::validate(c);
  Scenario s = load_scenario(c.scenario);
  if (c.seed >= 0) s.seed = static_cast<uint64_t>(c.seed);
  if (!c.nuisance.empty()) s.nuisance = Nuisance::named(c.nuisance);
  return s;
}

std::string file_name(const std::string& path) {
  const auto slash = path.find_last_of('/');
  return slash == std::string::npos ? path : path.substr(slash + 1);
}

}  // namespace

stack_t to_truth_message(const core::Stack& stack, const std::vector<TrueBlock>& truth) {
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

SimcamNode::SimcamNode(const Config& config, runtime::Bus& bus)
    : Node("simcam", bus),
      config_(config),
      scenario_(load_configured(config)),
      scenario_name_(file_name(config.scenario)),
      renderer_(config.setup_seed ? CameraSetup::random(static_cast<uint64_t>(config.setup_seed)) : CameraSetup{},
                config.setup_seed ? ProjectorSetup::random(static_cast<uint64_t>(config.setup_seed)) : ProjectorSetup{}),
      image_channel_(channel(kImageChannel)),
      truth_channel_(channel(kTruthChannel)),
      start_utime_(now()) {
  if (!config_.no_projector)
    subscribe<projector_state_t>(channel(kProjectorChannel), runtime::QueuePolicy::newest(),
                                 [this](const projector_state_t& p) { on_projector(p); }, 32u << 20);
  set_tick_ms(2);
  log::info("playing ", scenario_name_, " (", scenario_.description, ") at ", config_.fps, " fps, nuisance ",
            scenario_.nuisance.name, config_.loop ? ", looping" : "");
}

void SimcamNode::on_projector(const projector_state_t& p) {
  const image_t& im = p.image;
  if (im.size <= 0 || im.size != static_cast<int32_t>(im.data.size()))
    return error("bad projector images", "projector image: size " + std::to_string(im.size) + " does not match its data");
  cv::Mat bgr = cv::imdecode(cv::Mat(1, im.size, CV_8UC1, const_cast<uint8_t*>(im.data.data())), cv::IMREAD_COLOR);
  if (bgr.empty() || bgr.cols > 8192 || bgr.rows > 8192)
    return error("bad projector images", "undecodable projector image (" + std::to_string(im.size) + " bytes)");
  projector_image_ = bgr;
}

void SimcamNode::tick() {
  if (finished_) return;
  const int64_t due = start_utime_ + static_cast<int64_t>(1e6 * static_cast<double>(frame_number_) / config_.fps);
  if (now() < due) return wake_at(due);
  double t = static_cast<double>(frame_number_) / config_.fps;
  if (t >= scenario_.duration_s) {
    if (!config_.loop) return finish("scenario finished");
    t = std::fmod(t, scenario_.duration_s);
  }
  if (config_.frames > 0 && frame_number_ >= config_.frames) return finish("frame limit reached");

  const core::Stack& stack = scenario_.stack_at(t);
  Nuisance nuisance = scenario_.nuisance;
  nuisance.layout_seed = scenario_.seed;
  nuisance.time_s = t;
  Rendered frame = renderer_.render(stack, nuisance, projector_image_.empty() ? nullptr : &projector_image_,
                                    scenario_.seed + static_cast<uint64_t>(frame_number_));
  std::vector<uint8_t> bytes;
  if (config_.format == "png") {
    cv::imencode(".png", frame.bgr, bytes);
  } else {
    cv::imencode(".jpg", frame.bgr, bytes, {cv::IMWRITE_JPEG_QUALITY, config_.jpeg_quality});
  }
  image_t im{};
  im.utime = now();
  im.frame_number = frame_number_;
  im.width = frame.bgr.cols;
  im.height = frame.bgr.rows;
  im.format = config_.format == "png" ? int32_t{image_t::FORMAT_PNG} : int32_t{image_t::FORMAT_JPEG};
  im.source = "simcam:" + scenario_name_;
  im.data = std::move(bytes);
  im.size = static_cast<int32_t>(im.data.size());
  stack_t truth = to_truth_message(stack, frame.truth);
  truth.utime = im.utime;
  truth.frame_number = im.frame_number;
  publish(image_channel_, im);
  publish_report(truth_channel_, truth);  // a test aid, not counted as output
  ++frame_number_;
  wake_at(start_utime_ + static_cast<int64_t>(1e6 * static_cast<double>(frame_number_) / config_.fps));
}

void SimcamNode::finish(const char* why) {
  finished_ = true;
  log::info(why, " after ", frame_number_, " frames");
  set_status(why);
  stop();
}

}  // namespace bricklayer::simcam
