// Next-block hint: where one more block should go, or the fewest blocks (up to two) that rebalance a pile.
//
// Balance is judged by the core's predict() (exact annotator). Safety margin m (default 0.02 block lengths):
// a suggested block at x is "safe" when the pile is balanced with that block at x - m, x and x + m (each of
// the other suggested blocks at its own x). Candidate positions are the free places of every row (not
// overlapping a block of the row, resting on a block of the row below or on the surface), searched from the
// right on a grid of step 2m and refined by bisection, so the answer is at least as good as a grid search of
// step m (see rightmost_safe in hint.cc). Balance checks use the core's initial accelerations (the exact
// annotator's judge of motion). Rebalancing considers blocks that touch a cause (resting on it or under it);
// for two blocks, the first is one of the singles that leave the least motion (sum of a^2 + alpha^2/12).
#pragma once

#include <cstdint>
#include <vector>

#include "bricklayer/core/stack.h"

namespace bricklayer::planner {

struct HintOptions {
  double margin = 0.02;  // block lengths
  int max_added = 2;     // rebalancing: at most this many blocks (1 or 2)
  int pair_seeds = 6;    // rebalancing with two blocks: first blocks tried (the singles leaving the least motion)
};

struct SuggestedBlock {
  int32_t row = 0;
  double x = 0.0;  // left end, block lengths from the surface edge
};

struct Hint {
  enum class Kind { kExtend = 0, kRebalance = 1, kNone = 2 };  // hint_t::KIND_* values
  Kind kind = Kind::kNone;
  std::vector<SuggestedBlock> blocks;
  double overhang_after = 0.0;  // block lengths
  int32_t score_after = 0;
  double margin = 0.0;
  int evaluations = 0;  // predict() calls made
};

// Throws core::StackError on an invalid stack.
Hint next_block_hint(const core::Stack& stack, const HintOptions& options = {});

// The stack with the suggested blocks added (x converted back to the stack's units; fresh ids).
core::Stack with_blocks(const core::Stack& stack, const std::vector<SuggestedBlock>& blocks);

}  // namespace bricklayer::planner
