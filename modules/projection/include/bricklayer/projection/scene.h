// What the game display shows, as plain data: the newest stack, each block's predicted state, the
// collapse preview and the hint. Pure (no SDL, no bus), so tests drive it directly.
//
// Matching a prediction to a stack (by frame_number): the newest stack is always the one drawn. A
// prediction colours the blocks of its own frame; when the newest prediction answers an older frame,
// blocks whose ids it knows keep those (older) colours and new ids stay kUnknown until their
// prediction arrives.
#pragma once

#include <cstdint>
#include <optional>
#include <string>
#include <unordered_map>
#include <vector>

#include "bricklayer/collapse_preview_t.hpp"
#include "bricklayer/hint_t.hpp"
#include "bricklayer/prediction_t.hpp"
#include "bricklayer/projection/palette.h"
#include "bricklayer/stack_t.hpp"

namespace bricklayer::projection {

// One block in board coordinates (block lengths; x right from the surface edge, y up from the surface).
struct SceneBlock {
  int64_t id = 0;
  int row = 0;
  double x = 0;       // left end
  double y = 0;       // bottom = row * height
  double height = 0;  // block height in block lengths
  BlockState state = BlockState::kUnknown;
};

class Scene {
 public:
  // Replaces the drawn stack. Returns the number of blocks rejected (non-finite x, negative row);
  // throws std::invalid_argument for a stack that cannot be drawn at all (bad block_length / height /
  // table_edge). A stack whose status is not OK is drawn as an empty board.
  int set_stack(const stack_t& stack);
  // Takes the states of a prediction (status OK) for its block ids; a prediction whose status is not
  // OK forgets all states (blocks become kUnknown). Throws std::invalid_argument for an unknown state.
  void set_prediction(const prediction_t& prediction);
  void set_preview(const collapse_preview_t& preview);
  void set_hint(const hint_t& hint);
  void clear_hint() { hint_.reset(); }

  bool has_stack() const { return stack_frame_.has_value(); }
  int64_t stack_frame() const { return stack_frame_.value_or(-1); }
  int64_t stack_utime() const { return stack_utime_; }
  const std::vector<SceneBlock>& blocks() const { return blocks_; }
  bool any_cause() const;
  // 100 x (rightmost block end beyond the edge), rounded; 0 for an empty board.
  int score() const;
  double overhang() const;  // block lengths; 0 for an empty board

  // The newest prediction when it answers the drawn stack's frame.
  const prediction_t* prediction_for_stack() const;
  // The collapse preview when it answers the drawn stack's frame (else nullptr).
  const collapse_preview_t* preview_for_stack() const;
  const hint_t* hint() const { return hint_ ? &*hint_ : nullptr; }
  double block_height() const { return block_height_; }

 private:
  void recolour();

  std::optional<int64_t> stack_frame_;
  int64_t stack_utime_ = 0;
  double block_height_ = 1.0 / 3.0;
  std::vector<SceneBlock> blocks_;
  std::unordered_map<int64_t, BlockState> states_;
  std::optional<prediction_t> prediction_;
  std::optional<collapse_preview_t> preview_;
  std::optional<hint_t> hint_;
};

}  // namespace bricklayer::projection
