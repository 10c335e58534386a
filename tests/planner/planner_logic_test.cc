// bricklayer-planner's logic without the bus: matching predictions to stacks, bad input.
#include "bricklayer/planner/planner_logic.h"

#include <catch2/catch.hpp>

#include <cmath>
#include <vector>

#include "bricklayer/core/predict.h"
#include "bricklayer/runtime/codec.h"

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
    v.accel = b.accel;
    v.alpha = b.alpha;
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

TEST_CASE("every way a block can end has its own code in the message") {
  CHECK(planner::end_state(planner::BlockEnd::kUntouched) == collapse_preview_t::END_UNTOUCHED);
  CHECK(planner::end_state(planner::BlockEnd::kAtRest) == collapse_preview_t::END_AT_REST);
  CHECK(planner::end_state(planner::BlockEnd::kSlidAway) == collapse_preview_t::END_SLID_AWAY);
  CHECK(planner::end_state(planner::BlockEnd::kFellOff) == collapse_preview_t::END_FELL_OFF);
  CHECK(planner::end_state(planner::BlockEnd::kMoving) == collapse_preview_t::END_STILL_MOVING);
  // to_message keeps the stack's order, through LCM encoding and back.
  planner::CollapsePreview preview;
  preview.times = {0.0};
  preview.end = {planner::BlockEnd::kFellOff, planner::BlockEnd::kUntouched, planner::BlockEnd::kMoving,
                 planner::BlockEnd::kSlidAway, planner::BlockEnd::kAtRest};
  preview.frames = {std::vector<planner::Pose>(5)};
  core::Stack stack;
  for (int i = 0; i < 5; ++i) stack.blocks.push_back({10 + i, i, -0.5});
  const collapse_preview_t msg = planner::to_message(preview, stack, 77, 7);
  const auto decoded = runtime::decode<collapse_preview_t>(runtime::encode(msg));
  REQUIRE(decoded);
  REQUIRE(decoded->num_blocks == 5);
  CHECK(decoded->block_ids == std::vector<int64_t>{10, 11, 12, 13, 14});
  CHECK(decoded->end_state == std::vector<int8_t>{collapse_preview_t::END_FELL_OFF, collapse_preview_t::END_UNTOUCHED,
                                                  collapse_preview_t::END_STILL_MOVING, collapse_preview_t::END_SLID_AWAY,
                                                  collapse_preview_t::END_AT_REST});
}

TEST_CASE("a pile whose top block tips off the edge: that block fell off, the one under it stays") {
  // The bottom block ends at the edge; the top one's centre is 0.2 beyond the bottom one's end: it turns about
  // that end and falls past the edge; the bottom one carries its push at the edge and stays.
  planner::PlannerLogic logic;
  const auto stack = message({{0, -1.0}, {1, -0.3}}, 3);
  logic.on_stack(stack);
  const prediction_t verdict = verdict_for(stack);
  REQUIRE_FALSE(verdict.balanced);
  REQUIRE(verdict.blocks[0].state == block_prediction_t::STATE_STABLE);
  REQUIRE(verdict.blocks[1].state == block_prediction_t::STATE_CAUSE);
  const auto preview = logic.preview_for(verdict);
  REQUIRE(preview);
  const auto decoded = runtime::decode<collapse_preview_t>(runtime::encode(*preview));
  REQUIRE(decoded);
  REQUIRE(decoded->end_state.size() == 2);
  CHECK(decoded->end_state == preview->end_state);
  CHECK(decoded->end_state[1] == collapse_preview_t::END_FELL_OFF);
  CHECK((decoded->end_state[0] == collapse_preview_t::END_UNTOUCHED ||
         decoded->end_state[0] == collapse_preview_t::END_AT_REST));
  CHECK(decoded->poses == preview->poses);
}

TEST_CASE("a block called stable starts the preview awake only when its acceleration is nonzero below the tolerance") {
  // A block standing alone far from a tipping one: at rest in every model. Called stable with an acceleration of
  // exactly zero it sleeps throughout; with 5e-7 (stable only within the annotator's 1e-6) it starts awake, as
  // starts_awake says, and its end tells so.
  CHECK_FALSE(planner::starts_awake(true, 0.0, 0.0));
  CHECK_FALSE(planner::starts_awake(true, -1e-14, 2e-14));
  CHECK(planner::starts_awake(true, 5e-7, 0.0));
  CHECK(planner::starts_awake(true, 0.0, -1e-8));
  CHECK(planner::starts_awake(false, 0.0, 0.0));
  planner::PlannerLogic logic;
  const auto stack = message({{0, -3.0}, {0, -0.2}}, 4);
  logic.on_stack(stack);
  prediction_t verdict = verdict_for(stack);
  REQUIRE(verdict.blocks[0].state == block_prediction_t::STATE_STABLE);
  REQUIRE(std::abs(verdict.blocks[0].accel) + std::abs(verdict.blocks[0].alpha) < 1e-9);
  const auto asleep = logic.preview_for(verdict);
  REQUIRE(asleep);
  CHECK(asleep->end_state[0] == collapse_preview_t::END_UNTOUCHED);
  verdict.blocks[0].accel = 5e-7;
  const auto awake = logic.preview_for(verdict);
  REQUIRE(awake);
  CHECK(awake->end_state[0] != collapse_preview_t::END_UNTOUCHED);
  CHECK(awake->end_state[1] == asleep->end_state[1]);
}
