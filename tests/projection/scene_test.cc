#include "bricklayer/projection/scene.h"

#include <catch2/catch.hpp>

#include <cmath>

using namespace bricklayer;
using namespace bricklayer::projection;

namespace {
stack_t make_stack(int64_t frame, std::vector<std::tuple<int64_t, int, double>> blocks, double length = 1.0,
                   double edge = 0.0) {
  stack_t s{};
  s.frame_number = frame;
  s.utime = frame * 1000;
  s.block_length = length;
  s.block_height = length / 3.0;
  s.table_edge = edge;
  s.status = stack_t::STATUS_OK;
  for (auto [id, row, x] : blocks) {
    block_t b{};
    b.id = id;
    b.row = row;
    b.x = x;
    s.blocks.push_back(b);
  }
  s.num_blocks = static_cast<int32_t>(s.blocks.size());
  return s;
}

prediction_t make_prediction(int64_t frame, std::vector<std::pair<int64_t, int8_t>> states, bool balanced = false) {
  prediction_t p{};
  p.frame_number = frame;
  p.status = prediction_t::STATUS_OK;
  p.balanced = balanced;
  for (auto [id, state] : states) {
    block_prediction_t b{};
    b.id = id;
    b.state = state;
    p.blocks.push_back(b);
  }
  p.num_blocks = static_cast<int32_t>(p.blocks.size());
  return p;
}

BlockState state_of(const Scene& s, int64_t id) {
  for (const SceneBlock& b : s.blocks())
    if (b.id == id) return b.state;
  FAIL("no block " << id);
  return BlockState::kUnknown;
}
}  // namespace

TEST_CASE("a prediction for the drawn frame colours every block by id") {
  Scene s;
  s.set_stack(make_stack(5, {{1, 0, -0.5}, {2, 1, 0.0}, {3, 2, 0.6}}));
  CHECK(state_of(s, 1) == BlockState::kUnknown);
  s.set_prediction(make_prediction(5, {{1, 0}, {2, 1}, {3, 2}}));
  CHECK(state_of(s, 1) == BlockState::kStable);
  CHECK(state_of(s, 2) == BlockState::kMoving);
  CHECK(state_of(s, 3) == BlockState::kCause);
  CHECK(s.any_cause());
  REQUIRE(s.prediction_for_stack() != nullptr);
}

TEST_CASE("the newest stack is drawn with the older prediction's colours for the ids it knows") {
  Scene s;
  s.set_stack(make_stack(5, {{1, 0, -0.5}, {2, 1, 0.0}}));
  s.set_prediction(make_prediction(5, {{1, 0}, {2, 2}}));
  s.set_stack(make_stack(6, {{1, 0, -0.5}, {2, 1, 0.01}, {3, 2, 0.4}}));
  CHECK(s.stack_frame() == 6);
  CHECK(s.blocks().size() == 3);
  CHECK(state_of(s, 1) == BlockState::kStable);
  CHECK(state_of(s, 2) == BlockState::kCause);
  CHECK(state_of(s, 3) == BlockState::kUnknown);
  CHECK(s.prediction_for_stack() == nullptr);  // not for this frame: MAX must not take it
  // The prediction for frame 6 arrives.
  s.set_prediction(make_prediction(6, {{1, 0}, {2, 0}, {3, 0}}, true));
  CHECK(state_of(s, 2) == BlockState::kStable);
  CHECK(state_of(s, 3) == BlockState::kStable);
  CHECK_FALSE(s.any_cause());
}

TEST_CASE("board coordinates come from block_length, table_edge and block_height") {
  Scene s;
  // x in centimetres: 7.5 cm blocks, the edge at 30 cm.
  s.set_stack(make_stack(1, {{1, 0, 30.0 - 3.75}, {2, 2, 30.0}}, 7.5, 30.0));
  REQUIRE(s.blocks().size() == 2);
  CHECK(s.blocks()[0].x == Approx(-0.5));
  CHECK(s.blocks()[1].x == Approx(0.0));
  CHECK(s.blocks()[1].y == Approx(2.0 / 3.0));
  CHECK(s.block_height() == Approx(1.0 / 3.0));
  CHECK(s.overhang() == Approx(1.0));
  CHECK(s.score() == 100);
}

TEST_CASE("bad input is rejected or counted, never drawn") {
  Scene s;
  stack_t bad = make_stack(1, {{1, 0, 0}});
  bad.block_length = 0;
  CHECK_THROWS_WITH(s.set_stack(bad), Catch::Contains("block_length"));
  stack_t nan_block = make_stack(2, {{1, 0, NAN}, {2, -1, 0}, {3, 0, 0.25}});
  CHECK(s.set_stack(nan_block) == 2);
  CHECK(s.blocks().size() == 1);
  stack_t no_board = make_stack(3, {});
  no_board.status = stack_t::STATUS_NO_BOARD;
  CHECK(s.set_stack(no_board) == 0);
  CHECK(s.blocks().empty());
  CHECK(s.score() == 0);
  prediction_t weird = make_prediction(3, {{1, 9}});
  CHECK_THROWS(s.set_prediction(weird));
  collapse_preview_t preview{};
  preview.num_blocks = 1;
  preview.num_frames = 1;
  preview.num_values = 2;  // should be 3
  CHECK_THROWS(s.set_preview(preview));
}

TEST_CASE("a failed prediction forgets the colours") {
  Scene s;
  s.set_stack(make_stack(1, {{1, 0, 0}}));
  s.set_prediction(make_prediction(1, {{1, 2}}));
  CHECK(s.any_cause());
  prediction_t failed = make_prediction(1, {});
  failed.status = prediction_t::STATUS_SOLVER_ERROR;
  s.set_prediction(failed);
  CHECK(state_of(s, 1) == BlockState::kUnknown);
}

TEST_CASE("the collapse preview shows only for the drawn frame, the hint stays until cleared") {
  Scene s;
  s.set_stack(make_stack(4, {{1, 0, 0.6}}));
  collapse_preview_t preview{};
  preview.frame_number = 3;
  preview.num_blocks = 1;
  preview.block_ids = {1};
  preview.end_state = {collapse_preview_t::END_FELL_OFF};
  preview.num_frames = 1;
  preview.time_s = {0};
  preview.num_values = 3;
  preview.poses = {1.1, 1.0 / 6.0, 0};
  s.set_preview(preview);
  CHECK(s.preview_for_stack() == nullptr);
  preview.frame_number = 4;
  s.set_preview(preview);
  CHECK(s.preview_for_stack() != nullptr);

  hint_t hint{};
  hint.num_blocks = 1;
  hint.rows = {1};
  hint.xs = {0.2};
  s.set_hint(hint);
  s.set_stack(make_stack(5, {{1, 0, 0.6}}));
  CHECK(s.hint() != nullptr);
  s.clear_hint();
  CHECK(s.hint() == nullptr);
}
