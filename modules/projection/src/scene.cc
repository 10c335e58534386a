#include "bricklayer/projection/scene.h"

#include <algorithm>
#include <cmath>
#include <stdexcept>

namespace bricklayer::projection {

int Scene::set_stack(const stack_t& stack) {
  if (!std::isfinite(stack.block_length) || stack.block_length <= 0)
    throw std::invalid_argument("stack block_length must be positive, got " + std::to_string(stack.block_length));
  if (!std::isfinite(stack.table_edge)) throw std::invalid_argument("stack table_edge is not finite");
  const double height = stack.block_height / stack.block_length;
  if (!std::isfinite(height) || height <= 0 || height > 10)
    throw std::invalid_argument("stack block_height must be positive, got " + std::to_string(stack.block_height));
  if (stack.num_blocks != static_cast<int32_t>(stack.blocks.size()))
    throw std::invalid_argument("stack num_blocks disagrees with its block list");

  stack_frame_ = stack.frame_number;
  stack_utime_ = stack.utime;
  block_height_ = height;
  blocks_.clear();
  int rejected = 0;
  if (stack.status != stack_t::STATUS_OK) return 0;
  blocks_.reserve(stack.blocks.size());
  for (const block_t& b : stack.blocks) {
    const double x = (b.x - stack.table_edge) / stack.block_length;
    if (!std::isfinite(x) || std::abs(x) > 1e6 || b.row < 0 || b.row > 100000) {
      ++rejected;
      continue;
    }
    blocks_.push_back(SceneBlock{b.id, b.row, x, b.row * height, height, BlockState::kUnknown});
  }
  recolour();
  return rejected;
}

void Scene::set_prediction(const prediction_t& prediction) {
  std::unordered_map<int64_t, BlockState> states;
  if (prediction.status == prediction_t::STATUS_OK) {
    for (const block_prediction_t& b : prediction.blocks) {
      switch (b.state) {
        case block_prediction_t::STATE_STABLE: states[b.id] = BlockState::kStable; break;
        case block_prediction_t::STATE_MOVING: states[b.id] = BlockState::kMoving; break;
        case block_prediction_t::STATE_CAUSE: states[b.id] = BlockState::kCause; break;
        default: throw std::invalid_argument("prediction has unknown block state " + std::to_string(b.state));
      }
    }
  }
  states_ = std::move(states);
  prediction_ = prediction;
  recolour();
}

void Scene::set_preview(const collapse_preview_t& preview) {
  if (preview.num_blocks < 0 || preview.num_frames < 0 ||
      preview.num_values != 3 * preview.num_frames * preview.num_blocks ||
      static_cast<int32_t>(preview.poses.size()) != preview.num_values ||
      static_cast<int32_t>(preview.block_ids.size()) != preview.num_blocks ||
      static_cast<int32_t>(preview.time_s.size()) != preview.num_frames)
    throw std::invalid_argument("collapse preview sizes disagree (num_values must be 3 * frames * blocks)");
  for (double v : preview.poses)
    if (!std::isfinite(v)) throw std::invalid_argument("collapse preview has a non-finite pose");
  preview_ = preview;
}

void Scene::set_hint(const hint_t& hint) {
  if (hint.num_blocks < 0 || static_cast<int32_t>(hint.rows.size()) != hint.num_blocks ||
      static_cast<int32_t>(hint.xs.size()) != hint.num_blocks)
    throw std::invalid_argument("hint sizes disagree");
  for (double x : hint.xs)
    if (!std::isfinite(x)) throw std::invalid_argument("hint has a non-finite x");
  hint_ = hint;
}

void Scene::recolour() {
  for (SceneBlock& b : blocks_) {
    auto it = states_.find(b.id);
    b.state = it == states_.end() ? BlockState::kUnknown : it->second;
  }
}

bool Scene::any_cause() const {
  return std::any_of(blocks_.begin(), blocks_.end(), [](const SceneBlock& b) { return b.state == BlockState::kCause; });
}

double Scene::overhang() const {
  if (blocks_.empty()) return 0;
  double right = -1e300;
  for (const SceneBlock& b : blocks_) right = std::max(right, b.x + 1.0);
  return right;
}

int Scene::score() const { return static_cast<int>(std::lround(100.0 * overhang())); }

const prediction_t* Scene::prediction_for_stack() const {
  if (!prediction_ || !stack_frame_ || prediction_->frame_number != *stack_frame_) return nullptr;
  return &*prediction_;
}

const collapse_preview_t* Scene::preview_for_stack() const {
  if (!preview_ || !stack_frame_ || preview_->frame_number != *stack_frame_) return nullptr;
  return &*preview_;
}

}  // namespace bricklayer::projection
