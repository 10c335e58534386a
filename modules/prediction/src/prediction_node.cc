#include "bricklayer/prediction/prediction_node.h"

#include "bricklayer/common/channels.h"
#include "bricklayer/messages/timing.h"

namespace bricklayer::prediction {

PredictionNode::PredictionNode(const Config& config, runtime::Bus& bus)
    : Node("prediction", bus),
      logic_(config),
      prediction_channel_(channel(kPredictionChannel)),
      timing_channel_(channel(kTimingChannel)) {
  const std::string stacks = channel(kStackChannel);
  subscribe<stack_t>(stacks, runtime::QueuePolicy::newest(), [this](const stack_t& s) { on_stack(s); },
                     max_stack_message_bytes(static_cast<size_t>(config.max_blocks)));
  watch_input(stacks, kStaleAfterS, "no stacks");
}

void PredictionNode::on_stack(const stack_t& stack) {
  const int64_t received = now();
  const messages::Stopwatch watch;
  prediction_t p = logic_.answer(stack);
  if (p.status == prediction_t::STATUS_OK) show(p, hysteresis_.update(p));
  const int64_t elapsed = watch.elapsed_us();
  if (p.status == prediction_t::STATUS_INVALID_STACK || p.status == prediction_t::STATUS_SOLVER_ERROR)
    error(p.status == prediction_t::STATUS_INVALID_STACK ? "invalid stacks" : "solver failures",
          "frame " + std::to_string(p.frame_number) + ": " + p.error);
  publish(prediction_channel_, p);
  publish_report(timing_channel_, messages::make_timing("prediction", "predict", p.utime, p.frame_number, elapsed, received));
  set_value("last_predict_us", static_cast<double>(elapsed));
}

}  // namespace bricklayer::prediction
