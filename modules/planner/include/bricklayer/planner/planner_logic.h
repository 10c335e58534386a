// bricklayer-planner's logic without the bus: stacks in, collapse previews and hints out.
#pragma once

#include <cstdint>
#include <deque>
#include <optional>
#include <string>

#include "bricklayer/collapse_preview_t.hpp"
#include "bricklayer/core/stack.h"
#include "bricklayer/hint_t.hpp"
#include "bricklayer/planner/collapse.h"
#include "bricklayer/planner/hint.h"
#include "bricklayer/prediction_t.hpp"
#include "bricklayer/runtime/config.h"
#include "bricklayer/stack_t.hpp"

namespace bricklayer::planner {

struct PlannerConfig {
  HintOptions hint;
  CollapseOptions collapse;     // collapse.max_time is set from preview_seconds
  double preview_seconds = 0.7;   // longest simulated collapse, seconds of real time
  int max_blocks = 1000;          // larger stacks are ignored (counted as errors by the process)
  size_t remembered_stacks = 16;  // recent stacks kept to match predictions against

  template <typename Visitor>
  void visit(Visitor& v) {
    v(runtime::param("margin", hint.margin,
                     "hint safety margin, block lengths: suggested blocks stay balanced when shifted by +/- this")
          .open_range(0, 0.5));
    v(runtime::param("max-added", hint.max_added, "rebalancing hints add at most this many blocks (1 or 2)").range(1, 2));
    v(runtime::param("preview-seconds", preview_seconds, "longest simulated collapse, seconds of real time").above_up_to(0, 10));
    v(runtime::param("max-blocks", max_blocks, "larger stacks are ignored (counted errors)").range(1, 100000));
  }
};

// Converts a measured stack_t; throws core::StackError when it is not a valid stack or not STATUS_OK.
core::Stack to_core_stack(const stack_t& msg, size_t max_blocks = 1000);

class PlannerLogic {
 public:
  explicit PlannerLogic(PlannerConfig config = {});

  // Remembers a stack (the newest is the one hints are computed for). Throws core::StackError for an invalid one.
  void on_stack(const stack_t& msg);

  // The collapse preview for an unbalanced prediction whose stack (same utime and frame_number) was seen.
  // nullopt for balanced predictions, non-OK statuses, or an unknown stack.
  std::optional<collapse_preview_t> preview_for(const prediction_t& prediction) const;

  // The hint for the newest stack; nullopt when no stack has been seen yet.
  std::optional<hint_t> hint_for_newest() const;

  const PlannerConfig& config() const { return config_; }

 private:
  struct Seen {
    int64_t utime;
    int64_t frame_number;
    core::Stack stack;
  };
  PlannerConfig config_;
  std::deque<Seen> stacks_;
};

// The message's code for how a block ends (collapse_preview_t::END_*): the simulation's enum is the planner's
// own, the message's values are fixed by the schema.
int8_t end_state(BlockEnd end);

// The message for a preview of `stack` (its block ids in order); times in seconds of real blocks; end_state from
// preview.end (END_STILL_MOVING for a block the preview does not cover).
collapse_preview_t to_message(const CollapsePreview& preview, const core::Stack& stack, int64_t utime,
                              int64_t frame_number);

}  // namespace bricklayer::planner
