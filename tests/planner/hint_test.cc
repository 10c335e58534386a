// Next-block hints: balanced by the exact annotator with the margin, never worse than a brute-force grid,
// and constructed piles that need exactly one, exactly two, or more than two added blocks.
#include "bricklayer/planner/hint.h"

#include <catch2/catch.hpp>

#include <algorithm>
#include <cmath>

#include "bricklayer/core/predict.h"
#include "bricklayer/piles/walls.h"

using namespace bricklayer;
using planner::Hint;
using planner::SuggestedBlock;

namespace {

core::Stack pile(std::initializer_list<std::pair<int, double>> blocks) {
  core::Stack s;
  int64_t id = 1;
  for (auto [row, x] : blocks) s.blocks.push_back({id++, row, x});
  return s;
}

bool balanced_with(const core::Stack& s, const std::vector<SuggestedBlock>& added) {
  return core::predict(planner::with_blocks(s, added)).balanced;  // exact annotator (default)
}

// The hint's blocks are balanced at their place and when each is shifted by +/- margin.
void check_safe(const core::Stack& s, const Hint& h) {
  REQUIRE_FALSE(h.blocks.empty());
  CHECK(balanced_with(s, h.blocks));
  for (size_t j = 0; j < h.blocks.size(); ++j)
    for (double shift : {-h.margin, h.margin}) {
      auto moved = h.blocks;
      moved[j].x += shift;
      INFO("block " << j << " shifted by " << shift);
      CHECK(balanced_with(s, moved));
    }
}

// Best overhang of one added block over a grid of step 0.01 in every row, with the same margin test.
double brute_force_best(const core::Stack& s, double margin) {
  int top = -1;
  double end = -1e300;
  for (const auto& b : s.blocks) {
    top = std::max(top, static_cast<int>(b.row));
    end = std::max(end, b.x + 1.0);
  }
  double best = -1e300;
  for (int row = 0; row <= top + 1; ++row) {
    for (int k = 300; k >= -400; --k) {  // from the right: stop once nothing further left can do better
      const double x = 0.01 * k;
      if (std::max(end, x + 1.0) <= best) break;
      bool clear = true;
      for (const auto& b : s.blocks)
        if (b.row == row && std::abs(b.x - x) < 1.0 + margin) clear = false;  // shifted copies must fit too
      if (!clear) continue;
      if (balanced_with(s, {{row, x}}) && balanced_with(s, {{row, x - margin}}) && balanced_with(s, {{row, x + margin}}))
        best = std::max({best, end, x + 1.0});
    }
  }
  return best;
}

}  // namespace

TEST_CASE("extension hints are safe and never worse than a brute-force grid search") {
  const core::Stack piles[] = {
      pile({{0, -0.5}}),                                   // one block at its balance point
      pile({{0, -0.75}, {1, -0.25}}),                      // harmonic pair (knife edge)
      pile({{0, -0.6}, {1, -1.0}, {2, -0.8}}),             // a small tower
      pile({{0, -1.5}, {0, -0.5}, {1, -1.0}, {2, -0.9}}),  // a small wall
      piles::wall_pile(3, 2, 7),
  };
  for (const core::Stack& s : piles) {
    INFO("pile of " << s.blocks.size() << " blocks");
    REQUIRE(core::predict(s).balanced);
    const Hint h = planner::next_block_hint(s);
    REQUIRE(h.kind == Hint::Kind::kExtend);
    REQUIRE(h.blocks.size() == 1);
    check_safe(s, h);
    const double brute = brute_force_best(s, h.margin);
    CHECK(h.overhang_after >= brute - 1e-9);
    CHECK(h.score_after >= core::score_of(brute));
    CHECK(h.score_after == core::score_of(core::overhang(planner::with_blocks(s, h.blocks))));
  }
}

TEST_CASE("an empty board gets the single block with its margin") {
  const Hint h = planner::next_block_hint(core::Stack{});
  REQUIRE(h.kind == Hint::Kind::kExtend);
  REQUIRE(h.blocks.size() == 1);
  CHECK(h.blocks[0].row == 0);
  CHECK(h.blocks[0].x == Approx(-0.52).margin(1e-3));  // centre 0.02 inside the edge
}

TEST_CASE("a pile that needs exactly one counterweight") {
  const core::Stack s = pile({{0, -0.3}});  // centre 0.2 beyond the edge
  REQUIRE_FALSE(core::predict(s).balanced);
  planner::HintOptions one;
  one.max_added = 1;
  const Hint h = planner::next_block_hint(s, one);
  REQUIRE(h.kind == Hint::Kind::kRebalance);
  REQUIRE(h.blocks.size() == 1);
  CHECK(h.blocks[0].row == 1);
  check_safe(s, h);
}

TEST_CASE("a pile that needs exactly two blocks") {
  // Centre 0.3 beyond the edge: a single block on top would have to sit left of its own support.
  const core::Stack s = pile({{0, -0.2}});
  planner::HintOptions one;
  one.max_added = 1;
  CHECK(planner::next_block_hint(s, one).kind == Hint::Kind::kNone);
  const Hint h = planner::next_block_hint(s);
  REQUIRE(h.kind == Hint::Kind::kRebalance);
  REQUIRE(h.blocks.size() == 2);
  check_safe(s, h);
}

TEST_CASE("a pile that two blocks cannot save gets no hint") {
  const core::Stack s = pile({{0, -0.05}});  // centre 0.45 beyond the edge
  const Hint h = planner::next_block_hint(s);
  CHECK(h.kind == Hint::Kind::kNone);
  CHECK(h.blocks.empty());
}

TEST_CASE("invalid stacks and options are errors") {
  core::Stack s = pile({{0, -0.5}, {0, -0.2}});  // overlapping in one row
  CHECK_THROWS_AS(planner::next_block_hint(s), core::StackError);
  planner::HintOptions bad;
  bad.margin = 0.0;
  CHECK_THROWS_AS(planner::next_block_hint(pile({{0, -0.5}}), bad), std::invalid_argument);
}
