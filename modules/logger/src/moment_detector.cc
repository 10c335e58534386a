#include "bricklayer/logger/moment_detector.h"

#include "bricklayer/command_t.hpp"
#include "bricklayer/prediction_t.hpp"
#include "bricklayer/round_t.hpp"
#include "bricklayer/runtime/codec.h"

namespace bricklayer::logger {

MomentDetector::MomentDetector(MomentChannels channels) : channels_(std::move(channels)) {}

std::optional<Moment> MomentDetector::observe(const std::string& channel, const uint8_t* data, size_t size,
                                              int64_t utime) {
  if (channel == channels_.prediction) {
    const auto p = runtime::decode<prediction_t>(data, size);
    if (!p || p->status != prediction_t::STATUS_OK) return std::nullopt;
    int causes = 0;
    for (const auto& b : p->blocks) causes += b.state == block_prediction_t::STATE_CAUSE;
    if (causes > 0 && !red_) {
      red_ = true;
      red_blocks_ = p->num_blocks;
      return Moment{utime, "red", "frame " + std::to_string(p->frame_number) + ", " + std::to_string(p->num_blocks) +
                                      " blocks, " + std::to_string(causes) + " red, score " + std::to_string(p->score)};
    }
    if (causes == 0 && red_) {
      red_ = false;
      if (p->num_blocks < red_blocks_)
        return Moment{utime, "collapse", "frame " + std::to_string(p->frame_number) + ", " + std::to_string(red_blocks_) +
                                             " -> " + std::to_string(p->num_blocks) + " blocks"};
    }
    return std::nullopt;
  }
  if (channel == channels_.round) {
    const auto r = runtime::decode<round_t>(data, size);
    if (!r) return std::nullopt;
    const bool running = r->state == round_t::STATE_RUNNING;
    const bool was = running_;
    running_ = running;
    if (running && !was) return Moment{utime, "round_start", ""};
    if (!running && was)
      return Moment{utime, "round_end", std::string(r->state == round_t::STATE_ENDED ? "time up" : "reset") +
                                            ", score " + std::to_string(r->score) + ", max " + std::to_string(r->max_score)};
    return std::nullopt;
  }
  if (channel == channels_.command) {
    const auto c = runtime::decode<command_t>(data, size);
    if (!c || c->command != command_t::MARK_MOMENT) return std::nullopt;
    return Moment{utime, "mark", c->argument};
  }
  return std::nullopt;
}

}  // namespace bricklayer::logger
