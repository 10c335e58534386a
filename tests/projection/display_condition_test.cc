// display_condition: the three conditions' names and indices (study_session_t::CONDITION_*), and how each
// one lights a falling pile, a standing pile, a knife edge, blocks without a verdict and a stale board.
#include "bricklayer/projection/display_condition.h"

#include <catch2/catch.hpp>

#include "bricklayer/study_session_t.hpp"

using namespace bricklayer;
using namespace bricklayer::projection;

namespace {

bool same(Rgb a, Rgb b) { return a.r == b.r && a.b == b.b; }

// Blocks 1..n in a tower; states[k] for block k+1 (-1: no verdict for it); verdict of the pile.
Scene scene_with(std::vector<int8_t> states, int8_t verdict = prediction_t::VERDICT_STABLE) {
  stack_t s{};
  s.frame_number = 4;
  s.block_length = 1;
  s.block_height = 1.0 / 3.0;
  s.status = stack_t::STATUS_OK;
  prediction_t p{};
  p.frame_number = 4;
  p.status = prediction_t::STATUS_OK;
  p.verdict = verdict;
  for (size_t k = 0; k < states.size(); ++k) {
    block_t b{};
    b.id = static_cast<int64_t>(k + 1);
    b.row = static_cast<int32_t>(k);
    b.x = -0.5 + 0.2 * static_cast<double>(k);
    s.blocks.push_back(b);
    if (states[k] < 0) continue;
    block_prediction_t bp{};
    bp.id = b.id;
    bp.state = states[k];
    bp.deciding = verdict != prediction_t::VERDICT_STABLE && k + 1 == states.size();
    p.blocks.push_back(bp);
  }
  s.num_blocks = static_cast<int32_t>(s.blocks.size());
  p.num_blocks = static_cast<int32_t>(p.blocks.size());
  Scene scene;
  scene.set_stack(s);
  scene.set_prediction(p);
  return scene;
}

constexpr int8_t kStable = block_prediction_t::STATE_STABLE;
constexpr int8_t kMoving = block_prediction_t::STATE_MOVING;
constexpr int8_t kCause = block_prediction_t::STATE_CAUSE;

}  // namespace

TEST_CASE("the conditions are study_session_t's, by index and by name, and anything else is none") {
  CHECK(condition_from_index(study_session_t::CONDITION_BLUE) == DisplayCondition::kBlue);
  CHECK(condition_from_index(study_session_t::CONDITION_RED) == DisplayCondition::kRed);
  CHECK(condition_from_index(study_session_t::CONDITION_PROPOSED) == DisplayCondition::kProposed);
  for (int64_t bad : {int64_t{0}, int64_t{4}, int64_t{-1}, int64_t{255}, int64_t{1} << 40}) CHECK_FALSE(condition_from_index(bad));
  for (auto c : {DisplayCondition::kBlue, DisplayCondition::kRed, DisplayCondition::kProposed})
    CHECK(condition_from_name(condition_name(c)) == c);
  CHECK(std::string(condition_name(DisplayCondition::kRed)) == "red");
  CHECK_FALSE(condition_from_name("Blue"));
  CHECK_FALSE(condition_from_name(""));
  CHECK(next_condition(DisplayCondition::kBlue) == DisplayCondition::kRed);
  CHECK(next_condition(DisplayCondition::kRed) == DisplayCondition::kProposed);
  CHECK(next_condition(DisplayCondition::kProposed) == DisplayCondition::kBlue);
}

TEST_CASE("a falling pile: blue all blue and silent, red all red, proposed only its cause red") {
  const Scene falling = scene_with({kStable, kCause, kMoving});
  const PileLook blue = pile_look(DisplayCondition::kBlue, falling, false);
  REQUIRE(blue.fill.size() == 3);
  for (Rgb c : blue.fill) CHECK(same(c, kStableBlue));
  CHECK_FALSE(blue.alarm);
  CHECK_FALSE(blue.ghost);
  CHECK_FALSE(blue.knife_edge);
  CHECK_FALSE(blue.margin_text);

  const PileLook red = pile_look(DisplayCondition::kRed, falling, false);
  for (Rgb c : red.fill) CHECK(same(c, kCauseRed));
  CHECK(red.alarm);
  CHECK_FALSE(red.ghost);  // the ghost would say which blocks fall
  CHECK_FALSE(red.knife_edge);
  CHECK_FALSE(red.margin_text);

  const PileLook proposed = pile_look(DisplayCondition::kProposed, falling, false);
  CHECK(same(proposed.fill[0], kStableBlue));
  CHECK(same(proposed.fill[1], kCauseRed));
  CHECK(same(proposed.fill[2], kMovingMagenta));
  CHECK(proposed.alarm);
  CHECK(proposed.ghost);
  CHECK(proposed.knife_edge);
  CHECK(proposed.margin_text);
}

TEST_CASE("a standing pile is all blue and silent in every condition") {
  const Scene standing = scene_with({kStable, kStable, kStable});
  for (auto c : {DisplayCondition::kBlue, DisplayCondition::kRed, DisplayCondition::kProposed}) {
    INFO(condition_name(c));
    const PileLook look = pile_look(c, standing, false);
    for (Rgb f : look.fill) CHECK(same(f, kStableBlue));
    CHECK_FALSE(look.alarm);
  }
}

TEST_CASE("a knife edge does not certainly fall: all blue under red and blue, its outline only under proposed") {
  const Scene edge = scene_with({kStable, kStable}, prediction_t::VERDICT_KNIFE_EDGE);
  for (auto c : {DisplayCondition::kBlue, DisplayCondition::kRed}) {
    INFO(condition_name(c));
    const PileLook look = pile_look(c, edge, false);
    for (Rgb f : look.fill) CHECK(same(f, kStableBlue));
    CHECK_FALSE(look.alarm);
    CHECK_FALSE(look.knife_edge);
    CHECK_FALSE(look.margin_text);
  }
  const PileLook proposed = pile_look(DisplayCondition::kProposed, edge, false);
  CHECK(proposed.knife_edge);
  CHECK(proposed.margin_text);
  CHECK_FALSE(proposed.alarm);
}

TEST_CASE("blocks without a verdict stay dim blue, except in a pile that falls under red") {
  const Scene standing = scene_with({kStable, -1});
  for (auto c : {DisplayCondition::kBlue, DisplayCondition::kRed, DisplayCondition::kProposed}) {
    INFO(condition_name(c));
    CHECK(same(pile_look(c, standing, false).fill[1], kUnknownDimBlue));
  }
  const Scene falling = scene_with({kCause, -1});
  CHECK(same(pile_look(DisplayCondition::kBlue, falling, false).fill[1], kUnknownDimBlue));
  CHECK(same(pile_look(DisplayCondition::kRed, falling, false).fill[1], kCauseRed));
  CHECK(same(pile_look(DisplayCondition::kProposed, falling, false).fill[1], kUnknownDimBlue));
}

TEST_CASE("a stale board is dim blue with nothing else in every condition") {
  const Scene falling = scene_with({kStable, kCause});
  for (auto c : {DisplayCondition::kBlue, DisplayCondition::kRed, DisplayCondition::kProposed}) {
    INFO(condition_name(c));
    const PileLook look = pile_look(c, falling, true);
    REQUIRE(look.fill.size() == 2);
    for (Rgb f : look.fill) CHECK(same(f, kUnknownDimBlue));
    CHECK_FALSE(look.alarm);
    CHECK_FALSE(look.ghost);
    CHECK_FALSE(look.knife_edge);
    CHECK_FALSE(look.margin_text);
  }
  CHECK(pile_look(DisplayCondition::kRed, Scene{}, false).fill.empty());
}
