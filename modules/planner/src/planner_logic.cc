#include "bricklayer/planner/planner_logic.h"

#include <algorithm>
#include <cmath>

#include "bricklayer/core/predict.h"

namespace bricklayer::planner {

core::Stack to_core_stack(const stack_t& msg, size_t max_blocks) {
  if (msg.status != stack_t::STATUS_OK) throw core::StackError("stack_t carries no measurement (status " +
                                                               std::to_string(msg.status) + ")");
  if (msg.num_blocks < 0 || static_cast<size_t>(msg.num_blocks) != msg.blocks.size())
    throw core::StackError("stack_t num_blocks does not match its blocks");
  core::Stack s;
  s.block_length = msg.block_length;
  s.block_height = msg.block_height;
  s.table_edge = msg.table_edge;
  for (const block_t& b : msg.blocks) s.blocks.push_back({b.id, b.row, b.x});
  core::StackLimits limits;
  limits.max_blocks = max_blocks;
  core::validate(s, limits);
  return s;
}

PlannerLogic::PlannerLogic(PlannerConfig config) : config_(std::move(config)) {
  config_.collapse.max_time = config_.preview_seconds / seconds_per_time_unit();
}

void PlannerLogic::on_stack(const stack_t& msg) {
  Seen seen{msg.utime, msg.frame_number, to_core_stack(msg, static_cast<size_t>(config_.max_blocks))};
  stacks_.push_back(std::move(seen));
  while (stacks_.size() > std::max<size_t>(config_.remembered_stacks, 1)) stacks_.pop_front();
}

int8_t end_state(BlockEnd end) {
  switch (end) {
    case BlockEnd::kUntouched: return collapse_preview_t::END_UNTOUCHED;
    case BlockEnd::kAtRest: return collapse_preview_t::END_AT_REST;
    case BlockEnd::kSlidAway: return collapse_preview_t::END_SLID_AWAY;
    case BlockEnd::kFellOff: return collapse_preview_t::END_FELL_OFF;
    case BlockEnd::kMoving: return collapse_preview_t::END_STILL_MOVING;
  }
  return collapse_preview_t::END_STILL_MOVING;  // not a BlockEnd: claim nothing about where the block ended
}

collapse_preview_t to_message(const CollapsePreview& preview, const core::Stack& stack, int64_t utime,
                              int64_t frame_number) {
  collapse_preview_t msg{};
  msg.utime = utime;
  msg.frame_number = frame_number;
  msg.num_blocks = static_cast<int32_t>(stack.blocks.size());
  for (const core::Block& b : stack.blocks) msg.block_ids.push_back(b.id);
  for (size_t i = 0; i < stack.blocks.size(); ++i)
    msg.end_state.push_back(i < preview.end.size() ? end_state(preview.end[i]) : collapse_preview_t::END_STILL_MOVING);
  msg.num_frames = static_cast<int32_t>(preview.times.size());
  const double seconds = seconds_per_time_unit();  // real blocks: 7.5 cm
  for (double t : preview.times) msg.time_s.push_back(t * seconds);
  for (const auto& frame : preview.frames)
    for (const Pose& p : frame) {
      msg.poses.push_back(p.x);
      msg.poses.push_back(p.y);
      msg.poses.push_back(p.angle);
    }
  msg.num_values = static_cast<int32_t>(msg.poses.size());
  return msg;
}

std::optional<collapse_preview_t> PlannerLogic::preview_for(const prediction_t& prediction) const {
  if (prediction.status != prediction_t::STATUS_OK || prediction.balanced) return std::nullopt;
  auto it = std::find_if(stacks_.rbegin(), stacks_.rend(), [&](const Seen& s) {
    return s.utime == prediction.utime && s.frame_number == prediction.frame_number;
  });
  if (it == stacks_.rend()) return std::nullopt;
  const core::Stack& stack = it->stack;
  CollapseInput input;
  input.block_height = stack.block_height / stack.block_length;
  input.table_edge = 0.0;
  for (const core::Block& b : stack.blocks) {
    bool moving = true;  // blocks the prediction does not mention are simulated
    for (const block_prediction_t& v : prediction.blocks)
      if (v.id == b.id) moving = starts_awake(v.state == block_prediction_t::STATE_STABLE, v.accel, v.alpha);
    input.blocks.push_back({b.row, (b.x - stack.table_edge) / stack.block_length, moving});
  }
  return to_message(simulate_collapse(input, config_.collapse), stack, prediction.utime, prediction.frame_number);
}

std::optional<hint_t> PlannerLogic::hint_for_newest() const {
  if (stacks_.empty()) return std::nullopt;
  const Seen& seen = stacks_.back();
  const Hint hint = next_block_hint(seen.stack, config_.hint);
  hint_t msg{};
  msg.utime = seen.utime;
  msg.frame_number = seen.frame_number;
  msg.kind = static_cast<int8_t>(hint.kind);
  msg.num_blocks = static_cast<int32_t>(hint.blocks.size());
  for (const SuggestedBlock& b : hint.blocks) {
    msg.rows.push_back(b.row);
    msg.xs.push_back(b.x);
  }
  msg.score_after = hint.score_after;
  msg.margin = hint.margin;
  return msg;
}

}  // namespace bricklayer::planner
