// bricklayer-planner's logic without the bus: matching predictions to stacks, bad input.
#include "bricklayer/planner/planner_logic.h"

#include <catch2/catch.hpp>

#include <cmath>

#include "bricklayer/core/predict.h"

using namespace bricklayer;

namespace {

bricklayer::stack_t message(std::initializer_list<std::pair<int, double>> blocks, int64_t frame) {
  bricklayer::stack_t m{};
  m.utime = 5000 + frame;
  m.frame_number = frame;
  m.block_length = 1.0;
  m.block_height = 1.0 / 3.0;
  m.table_edge = 0.0;
  m.status = bricklayer::stack_t::STATUS_OK;
  int64_t id = 1;
  for (auto [row, x] : blocks) {
    block_t b{};
    b.id = id++;
    b.row = row;
    b.x = x;
    m.blocks.push_back(b);
  }
  m.num_blocks = static_cast<int32_t>(m.blocks.size());
  return m;
}

prediction_t verdict_for(const bricklayer::stack_t& s) {
  const core::Prediction p = core::predict(planner::to_core_stack(s));
  prediction_t m{};
  m.utime = s.utime;
  m.frame_number = s.frame_number;
  m.status = prediction_t::STATUS_OK;
  m.balanced = p.balanced;
  for (const auto& b : p.blocks) {
    block_prediction_t v{};
    v.id = b.id;
    v.state = static_cast<int8_t>(b.state);
    m.blocks.push_back(v);
  }
  m.num_blocks = static_cast<int32_t>(m.blocks.size());
  return m;
}

}  // namespace

TEST_CASE("previews answer unbalanced predictions of stacks that were seen, and nothing else") {
  planner::PlannerLogic logic;
  const auto tipping = message({{0, -0.2}}, 1);
  const auto standing = message({{0, -0.8}}, 2);
  logic.on_stack(tipping);
  logic.on_stack(standing);
  const auto preview = logic.preview_for(verdict_for(tipping));
  REQUIRE(preview);
  CHECK(preview->frame_number == 1);
  CHECK(preview->num_blocks == 1);
  CHECK(preview->num_values == 3 * preview->num_frames);
  CHECK(preview->time_s.back() > 0.0);
  CHECK_FALSE(logic.preview_for(verdict_for(standing)));  // balanced
  auto unknown = verdict_for(tipping);
  unknown.frame_number = 99;
  CHECK_FALSE(logic.preview_for(unknown));  // its stack was never seen
  auto failed = verdict_for(tipping);
  failed.status = prediction_t::STATUS_SOLVER_ERROR;
  CHECK_FALSE(logic.preview_for(failed));
}

TEST_CASE("hints are for the newest stack") {
  planner::PlannerLogic logic;
  CHECK_FALSE(logic.hint_for_newest());
  logic.on_stack(message({{0, -0.2}}, 1));
  logic.on_stack(message({{0, -0.8}}, 2));
  const auto hint = logic.hint_for_newest();
  REQUIRE(hint);
  CHECK(hint->frame_number == 2);
  CHECK(hint->kind == hint_t::KIND_EXTEND);
  CHECK(hint->num_blocks == 1);
  CHECK(hint->margin == 0.02);
}

TEST_CASE("invalid stacks are rejected with a StackError") {
  planner::PlannerLogic logic;
  CHECK_THROWS_AS(logic.on_stack(message({{0, std::nan("")}}, 1)), core::StackError);
  CHECK_THROWS_AS(logic.on_stack(message({{0, -0.5}, {0, -0.2}}, 2)), core::StackError);  // overlap in a row
  auto no_board = message({}, 3);
  no_board.status = bricklayer::stack_t::STATUS_NO_BOARD;
  CHECK_THROWS_AS(logic.on_stack(no_board), core::StackError);
  auto lying = message({{0, -0.5}}, 4);
  lying.num_blocks = 7;  // length field disagrees with the blocks
  CHECK_THROWS_AS(logic.on_stack(lying), core::StackError);
  CHECK_FALSE(logic.hint_for_newest());
}
