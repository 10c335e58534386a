#include "bricklayer/planner/planner_node.h"

#include "bricklayer/common/channels.h"
#include "bricklayer/messages/timing.h"

namespace bricklayer::planner {

PlannerNode::PlannerNode(const Config& config, runtime::Bus& bus)
    : Node("planner", bus), logic_(config), preview_channel_(channel(kPreviewChannel)), hint_channel_(channel(kHintChannel)) {
  runtime::validate(logic_.config());
  // Every stack is remembered (no newest-wins): a prediction names the stack it answers.
  subscribe<stack_t>(channel(kStackChannel), runtime::QueuePolicy::keep(64), [this](const stack_t& s) { on_stack(s); });
  subscribe<prediction_t>(channel(kPredictionChannel), runtime::QueuePolicy::newest(),
                          [this](const prediction_t& p) { on_prediction(p); });
  subscribe<command_t>(
      channel(kCommandChannel), runtime::QueuePolicy::keep(1000),
      [this](const command_t& c) {
        if (c.command == command_t::REQUEST_HINT) hint_requested_ = true;
      },
      1 << 16);
  watch_input(channel(kPredictionChannel), kStaleAfterS, "no predictions");
}

void PlannerNode::on_stack(const stack_t& s) {
  if (s.status != stack_t::STATUS_OK) return;  // nothing measured: nothing to plan
  try {
    logic_.on_stack(s);
  } catch (const std::exception& e) {
    error("invalid stacks", "stack frame " + std::to_string(s.frame_number) + " ignored: " + e.what());
  }
}

void PlannerNode::on_prediction(const prediction_t& p) {
  const messages::Stopwatch watch;
  try {
    if (auto preview = logic_.preview_for(p)) {
      publish(preview_channel_, *preview);
      set_value("last_preview_ms", watch.elapsed_ms());
    }
  } catch (const std::exception& e) {
    error("failed previews", "preview for frame " + std::to_string(p.frame_number) + " failed: " + e.what());
  }
}

void PlannerNode::tick() {
  if (!hint_requested_) return;
  const messages::Stopwatch watch;
  try {
    if (auto hint = logic_.hint_for_newest()) {
      hint_requested_ = false;
      publish(hint_channel_, *hint);
      set_value("last_hint_ms", watch.elapsed_ms());
    }
  } catch (const std::exception& e) {
    hint_requested_ = false;
    error("failed hints", std::string("hint failed: ") + e.what());
  }
}

}  // namespace bricklayer::planner
