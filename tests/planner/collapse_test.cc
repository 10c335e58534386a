// The collapse preview: a toppling tower falls, the balanced part stays where it is.
#include "bricklayer/planner/collapse.h"

#include <catch2/catch.hpp>

#include <cmath>

using namespace bricklayer::planner;

namespace {
// A tower of `rows` blocks at x = -0.5; the top `top` rows pushed right by `shift` (they topple over the edge).
CollapseInput toppling_tower(int rows, int top, double shift) {
  CollapseInput in;
  for (int r = 0; r < rows; ++r) {
    const bool moving = r >= rows - top;
    in.blocks.push_back({r, -0.5 + (moving ? shift : 0.0), moving});
  }
  return in;
}
}  // namespace

TEST_CASE("a toppling tower falls below its starting height and the balanced part is untouched") {
  const CollapseInput in = toppling_tower(12, 5, 0.7);
  const CollapsePreview p = simulate_collapse(in);
  REQUIRE(p.frames.size() >= 2);
  REQUIRE(p.frames.size() == p.times.size());
  const auto& first = p.frames.front();
  const auto& last = p.frames.back();
  for (size_t i = 0; i < in.blocks.size(); ++i) {
    INFO("block " << i);
    if (in.blocks[i].moving) {
      CHECK(last[i].y < first[i].y - 1.0);  // fell well below where it started
      CHECK(p.left_pile[i]);                // beyond the edge: off the surface
    } else {
      CHECK(last[i].x == first[i].x);  // asleep: not a hair moved
      CHECK(last[i].y == first[i].y);
      CHECK(last[i].angle == 0.0);
      CHECK_FALSE(p.left_pile[i]);
    }
  }
  // Key frames are in time order and the first is the starting pile.
  CHECK(p.times.front() == 0.0);
  for (size_t k = 1; k < p.times.size(); ++k) CHECK(p.times[k] > p.times[k - 1]);
  CHECK(first[0].y == Approx(1.0 / 6.0));
}

TEST_CASE("a block hanging past its balance point tips over the edge and leaves the pile") {
  CollapseInput in;
  in.blocks.push_back({0, -0.3, true});  // centre 0.2 beyond the edge
  const CollapsePreview p = simulate_collapse(in);
  CHECK(p.left_pile[0]);
  CHECK(p.frames.back()[0].y < -0.5);
  CHECK(p.frames.back()[0].angle < -0.3);  // turned clockwise about the edge before falling
}

TEST_CASE("a block marked moving that is in fact supported comes to rest where it is") {
  CollapseInput in;
  in.blocks.push_back({0, -1.5, false});
  in.blocks.push_back({1, -1.2, true});  // resting well inside its support
  const CollapsePreview p = simulate_collapse(in);
  CHECK(p.came_to_rest);
  CHECK_FALSE(p.left_pile[1]);
  CHECK(p.frames.back()[1].x == Approx(-0.7).margin(0.01));
  CHECK(p.frames.back()[1].y == Approx(0.5).margin(0.01));
  CHECK(std::abs(p.frames.back()[1].angle) < 0.01);
}

TEST_CASE("falling debris wakes a balanced block it strikes") {
  // Two stable blocks on the surface; a third block dropped from above onto the right end of the lower one
  // (simulated as a block in row 4 with nothing under it).
  CollapseInput in;
  in.blocks.push_back({0, -0.9, false});
  in.blocks.push_back({4, -0.2, true});
  const CollapsePreview p = simulate_collapse(in);
  // The block falls 3 rows onto the stable one: that one is woken (it moves, however little) and the pair
  // ends below the falling block's start.
  CHECK(p.frames.back()[1].y < p.frames.front()[1].y - 0.5);
}

TEST_CASE("bad input is an error") {
  CollapseInput in;
  in.blocks.push_back({0, std::nan(""), true});
  CHECK_THROWS_AS(simulate_collapse(in), std::invalid_argument);
  CollapseInput h;
  h.block_height = 0;
  CHECK_THROWS_AS(simulate_collapse(h), std::invalid_argument);
}
