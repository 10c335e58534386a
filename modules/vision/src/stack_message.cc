#include "bricklayer/vision/stack_message.h"

#include <stdexcept>
#include <string>

#include <nlohmann/json.hpp>

namespace bricklayer::vision {

using detection::BoardFrame;
using detection::DetectedBlock;
using detection::Detection;

double block_height_blocks(const BoardFrame& frame) {
  return frame.geometry().block_height_px / frame.geometry().block_length_px;
}

namespace {
stack_t empty_stack(const BoardFrame& frame, int64_t utime, int64_t frame_number, int8_t status) {
  stack_t s{};
  s.utime = utime;
  s.frame_number = frame_number;
  s.block_length = 1.0;
  s.block_height = block_height_blocks(frame);
  s.table_edge = 0.0;
  s.status = status;
  s.num_blocks = 0;
  return s;
}

block_t to_block(int64_t id, const DetectedBlock& b, double x_uncertainty) {
  block_t m{};
  m.id = id;
  m.row = b.row;
  m.x = b.x;
  for (int c = 0; c < 4; ++c) {
    m.corner_u[c] = b.corner_u[c];
    m.corner_v[c] = b.corner_v[c];
  }
  m.confidence = b.confidence;
  m.x_uncertainty = x_uncertainty;
  return m;
}

void check_count(const std::vector<double>& u, size_t blocks) {
  if (!u.empty() && u.size() != blocks)
    throw std::invalid_argument("stack message: " + std::to_string(u.size()) + " uncertainties for " +
                                std::to_string(blocks) + " blocks");
}
}  // namespace

stack_t no_frame_stack(const BoardFrame& frame, int64_t utime, int64_t frame_number) {
  return empty_stack(frame, utime, frame_number, stack_t::STATUS_NO_FRAME);
}

stack_t to_stack_message(const Detection& detection, const BoardFrame& frame, int64_t utime, int64_t frame_number,
                         const std::vector<double>& x_uncertainty) {
  check_count(x_uncertainty, detection.blocks.size());
  stack_t s = empty_stack(frame, utime, frame_number, static_cast<int8_t>(detection.status));
  for (size_t i = 0; i < detection.blocks.size(); ++i)
    s.blocks.push_back(to_block(static_cast<int64_t>(i), detection.blocks[i], x_uncertainty.empty() ? 0.0 : x_uncertainty[i]));
  s.num_blocks = static_cast<int32_t>(s.blocks.size());
  return s;
}

stack_t to_stack_message(const std::vector<FilteredBlock>& blocks, const BoardFrame& frame, int64_t utime,
                         int64_t frame_number, const std::vector<double>& x_uncertainty) {
  check_count(x_uncertainty, blocks.size());
  stack_t s = empty_stack(frame, utime, frame_number, stack_t::STATUS_OK);
  for (size_t i = 0; i < blocks.size(); ++i)
    s.blocks.push_back(to_block(blocks[i].id, blocks[i].block, x_uncertainty.empty() ? 0.0 : x_uncertainty[i]));
  s.num_blocks = static_cast<int32_t>(s.blocks.size());
  return s;
}

std::string to_predict_json(const Detection& detection, const BoardFrame& frame) {
  nlohmann::json j;
  j["block_length"] = 1.0;
  j["block_height"] = block_height_blocks(frame);
  j["table_edge"] = 0.0;
  j["blocks"] = nlohmann::json::array();
  // x unrounded: rounding two touching blocks independently can make them overlap by 1e-6, which the
  // predictor rejects.
  for (size_t i = 0; i < detection.blocks.size(); ++i) {
    const DetectedBlock& b = detection.blocks[i];
    j["blocks"].push_back({{"id", static_cast<int64_t>(i)}, {"row", b.row}, {"x", b.x}});
  }
  return j.dump();
}

}  // namespace bricklayer::vision
