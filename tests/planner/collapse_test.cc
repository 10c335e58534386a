// The collapse preview: a toppling tower falls, the balanced part stays where it is, and the preview ends
// (every block at rest or gone) well before max_time; the same input gives the same preview.
#include "bricklayer/planner/collapse.h"

#include <catch2/catch.hpp>

#include <cmath>
#include <limits>

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

// 12 staggered rows of 5 blocks ending at the edge (the bench's wall, without jitter); the top 4 rows pushed
// 1.5 beyond the edge and marked moving, the rest asleep.
CollapseInput toppling_wall() {
  CollapseInput in;
  for (int r = 0; r < 12; ++r) {
    const bool pushed = r >= 8;
    for (int k = 0; k < 5; ++k) in.blocks.push_back({r, -1.0 - (r % 2 ? 0.3 : 0.0) - k + (pushed ? 1.5 : 0.0), pushed});
  }
  return in;
}

int count(const CollapsePreview& p, BlockEnd e) {
  int n = 0;
  for (BlockEnd x : p.end) n += x == e;
  return n;
}
}  // namespace

TEST_CASE("a toppling tower falls below its starting height and the balanced part is untouched") {
  const CollapseInput in = toppling_tower(12, 5, 0.7);
  const CollapseOptions options;
  const CollapsePreview p = simulate_collapse(in, options);
  REQUIRE(p.frames.size() >= 2);
  REQUIRE(p.frames.size() == p.times.size());
  REQUIRE(p.end.size() == in.blocks.size());
  const auto& first = p.frames.front();
  const auto& last = p.frames.back();
  for (size_t i = 0; i < in.blocks.size(); ++i) {
    INFO("block " << i);
    if (in.blocks[i].moving) {
      CHECK(last[i].y < first[i].y - 1.0);  // fell well below where it started
      CHECK(p.left_pile[i]);                // beyond the edge: off the surface
      CHECK(p.end[i] == BlockEnd::kFellOff);
      CHECK(last[i].y < -options.fall_depth);  // followed until out of the picture
    } else {
      CHECK(last[i].x == first[i].x);  // asleep: not a hair moved
      CHECK(last[i].y == first[i].y);
      CHECK(last[i].angle == 0.0);
      CHECK_FALSE(p.left_pile[i]);
      CHECK(p.end[i] == BlockEnd::kUntouched);
    }
  }
  // Key frames are in time order and the first is the starting pile.
  CHECK(p.times.front() == 0.0);
  for (size_t k = 1; k < p.times.size(); ++k) CHECK(p.times[k] > p.times[k - 1]);
  CHECK(first[0].y == Approx(1.0 / 6.0));
  // Ended because everything had left, long before max_time.
  CHECK(p.came_to_rest);
  CHECK(p.times.back() < 0.6 * options.max_time);
  CHECK(p.steps <= std::lround(p.times.back() / options.dt));  // some steps are double steps
}

TEST_CASE("a block hanging past its balance point tips over the edge and leaves the pile") {
  CollapseInput in;
  in.blocks.push_back({0, -0.3, true});  // centre 0.2 beyond the edge
  const CollapsePreview p = simulate_collapse(in);
  CHECK(p.left_pile[0]);
  CHECK(p.end[0] == BlockEnd::kFellOff);
  CHECK(p.came_to_rest);
  CHECK(p.frames.back()[0].y < -1.0);
  CHECK(p.frames.back()[0].angle < -0.3);  // turned clockwise about the edge before falling
}

TEST_CASE("a block barely past its balance point is not taken for still: it tips over in the end") {
  // Centre 0.003 beyond the edge: the initial angular acceleration is about 0.025, slow enough to pass for
  // rest for a while (the ends move slower than rest_speed for the first ~0.8 time units).
  CollapseInput in;
  in.blocks.push_back({0, -0.497, true});
  CollapseOptions options;
  options.max_time = 30.0;
  const CollapsePreview p = simulate_collapse(in, options);
  CHECK(p.end[0] == BlockEnd::kFellOff);
  CHECK(p.came_to_rest);
}

TEST_CASE("a block marked moving that is in fact supported comes to rest where it is") {
  CollapseInput in;
  in.blocks.push_back({0, -1.5, false});
  in.blocks.push_back({1, -1.2, true});  // resting well inside its support
  const CollapsePreview p = simulate_collapse(in);
  CHECK(p.came_to_rest);
  CHECK_FALSE(p.left_pile[1]);
  CHECK(p.end[0] == BlockEnd::kUntouched);
  CHECK(p.end[1] == BlockEnd::kAtRest);
  CHECK(p.frames.back()[1].x == Approx(-0.7).margin(0.01));
  CHECK(p.frames.back()[1].y == Approx(0.5).margin(0.01));
  CHECK(std::abs(p.frames.back()[1].angle) < 0.01);
  CHECK(p.times.back() < 2.0);  // asleep after a second awake and rest_time still
}

TEST_CASE("a block that tips off the back of the pile and slides away alone on the surface stops there") {
  // Block 1 rests on block 0 with its centre 0.2 left of block 0's left end: it tips to the left onto the
  // surface, where (frictionless) it would slide for ever. It leaves the pile and stops.
  CollapseInput in;
  in.blocks.push_back({0, -3.0, false});
  in.blocks.push_back({1, -3.7, true});
  const CollapseOptions options;
  const CollapsePreview p = simulate_collapse(in, options);
  INFO("end " << static_cast<int>(p.end[1]) << " at t = " << p.times.back());
  CHECK(p.came_to_rest);
  CHECK(p.end[1] == BlockEnd::kSlidAway);
  CHECK(p.left_pile[1]);
  CHECK(p.end[0] == BlockEnd::kUntouched);
  CHECK(p.times.back() < options.max_time);
  const Pose& last = p.frames.back()[1];
  CHECK(last.x < -3.5);                                 // left of its support
  CHECK(last.y == Approx(1.0 / 6.0).margin(0.01));      // lying flat on the surface
  CHECK(std::abs(std::remainder(last.angle, M_PI)) < 0.02);
}

TEST_CASE("a 60-block wall whose top rows are pushed over the edge: the preview completes and ends") {
  const CollapseInput in = toppling_wall();
  const CollapseOptions options;
  const CollapsePreview p = simulate_collapse(in, options);
  REQUIRE(p.end.size() == 60);
  CHECK(p.came_to_rest);
  CHECK(p.times.back() < options.max_time);
  CHECK(count(p, BlockEnd::kMoving) == 0);
  CHECK(count(p, BlockEnd::kFellOff) > 0);
  for (const auto& frame : p.frames)
    for (const Pose& pose : frame)
      REQUIRE((std::isfinite(pose.x) && std::isfinite(pose.y) && std::isfinite(pose.angle)));
  // The bottom rows are far from the debris: untouched.
  for (size_t i = 0; i < 20; ++i) CHECK(p.end[i] == BlockEnd::kUntouched);
  // Everything that fell is below where it started.
  for (size_t i = 0; i < 60; ++i)
    if (p.end[i] == BlockEnd::kFellOff) CHECK(p.frames.back()[i].y < p.frames.front()[i].y - 1.0);
}

TEST_CASE("the same input gives the same preview, bit for bit") {
  const CollapseInput in = toppling_wall();
  const CollapsePreview a = simulate_collapse(in);
  const CollapsePreview b = simulate_collapse(in);
  REQUIRE(a.steps == b.steps);
  REQUIRE(a.times == b.times);
  REQUIRE(a.end == b.end);
  REQUIRE(a.frames.size() == b.frames.size());
  for (size_t k = 0; k < a.frames.size(); ++k)
    for (size_t i = 0; i < a.frames[k].size(); ++i) {
      INFO("frame " << k << " block " << i);
      REQUIRE(a.frames[k][i].x == b.frames[k][i].x);
      REQUIRE(a.frames[k][i].y == b.frames[k][i].y);
      REQUIRE(a.frames[k][i].angle == b.frames[k][i].angle);
    }
}

TEST_CASE("a pile with nothing moving ends at once") {
  CollapseInput in;
  in.blocks.push_back({0, -1.0, false});
  const CollapsePreview p = simulate_collapse(in);
  CHECK(p.came_to_rest);
  CHECK(p.steps == 0);
  CHECK(p.times.size() == 1);
  CHECK(p.end[0] == BlockEnd::kUntouched);
}

TEST_CASE("falling debris wakes a balanced block it strikes") {
  // A stable block on the surface; a second block dropped from above onto its right end (a block in row 4
  // with nothing under it).
  CollapseInput in;
  in.blocks.push_back({0, -0.9, false});
  in.blocks.push_back({4, -0.2, true});
  const CollapsePreview p = simulate_collapse(in);
  // The block falls 3 rows onto the stable one: that one is woken (it moves, however little) and the falling
  // block ends below its start.
  CHECK(p.frames.back()[1].y < p.frames.front()[1].y - 0.5);
  CHECK(p.end[0] != BlockEnd::kUntouched);
}

TEST_CASE("a blow on top of a balanced tower wakes the top, not the whole tower") {
  // 30 stable blocks in a column well inside the edge; a block dropped from 10 rows above lands on top. The
  // struck block passes the blow to the sleeping block under it (its contacts are found in the same step);
  // it must not be driven into it and wake it, and so on down the tower.
  CollapseInput in;
  for (int r = 0; r < 30; ++r) in.blocks.push_back({r, -1.2, false});
  in.blocks.push_back({40, -1.2, true});
  const CollapsePreview p = simulate_collapse(in);
  CHECK(p.end[29] != BlockEnd::kUntouched);  // struck
  int untouched = 0;
  for (int r = 0; r < 30; ++r) untouched += p.end[r] == BlockEnd::kUntouched;
  CHECK(untouched >= 26);
  CHECK(p.came_to_rest);
  CHECK(p.frames.back()[30].y == Approx((30 + 0.5) / 3.0).margin(0.02));  // the dropped block rests on top
}

TEST_CASE("bad input is an error") {
  CollapseInput in;
  in.blocks.push_back({0, std::nan(""), true});
  CHECK_THROWS_AS(simulate_collapse(in), std::invalid_argument);
  CollapseInput h;
  h.block_height = 0;
  CHECK_THROWS_AS(simulate_collapse(h), std::invalid_argument);
  CollapseInput row;
  row.blocks.push_back({-1, 0.0, true});
  CHECK_THROWS_AS(simulate_collapse(row), std::invalid_argument);
  const CollapseInput ok = toppling_tower(3, 1, 0.7);
  for (auto bad : {+[](CollapseOptions& o) { o.dt = 0; },
                   +[](CollapseOptions& o) { o.max_time = std::numeric_limits<double>::infinity(); },
                   +[](CollapseOptions& o) { o.max_time = 1e9; }, +[](CollapseOptions& o) { o.max_iterations = 0; },
                   +[](CollapseOptions& o) { o.tolerance = std::nan(""); },
                   +[](CollapseOptions& o) { o.rest_speed = -1; }, +[](CollapseOptions& o) { o.fall_depth = -1; },
                   +[](CollapseOptions& o) { o.key_frame_interval = 0; }}) {
    CollapseOptions o;
    bad(o);
    CHECK_THROWS_AS(simulate_collapse(ok, o), std::invalid_argument);
  }
}

TEST_CASE("a block woken because it rests on a moving block has its weight in that very step") {
  // B overhangs its support S by 0.2 and would tip alone, but C on top of it (centre 0.05 inside B's left end)
  // holds it: the pair's centre is 0.025 inside S's end, so nothing moves. B is marked moving, C asleep: C wakes
  // in the first step because it rests on B. Woken without that step's gravity, C weighed nothing and B tipped.
  CollapseInput in;
  in.blocks.push_back({0, -2.0, false});   // S, on the surface
  in.blocks.push_back({1, -1.3, true});    // B
  in.blocks.push_back({2, -1.75, false});  // C
  const CollapsePreview p = simulate_collapse(in);
  REQUIRE(p.initial.size() == 3);
  for (const Acceleration& a : p.initial) {
    CHECK(std::abs(a.x) < 1e-12);
    CHECK(std::abs(a.y) < 1e-12);
    CHECK(std::abs(a.angle) < 1e-12);
  }
  CHECK(p.end[1] == BlockEnd::kAtRest);
  CHECK(p.frames.back()[1].x == Approx(-0.8).margin(1e-6));
}

TEST_CASE("the first step is the exact initial acceleration: a block past the edge turns about it") {
  // One block with its centre 0.2 beyond the edge, released from rest: it turns about the edge, alpha =
  // -d / (I + d^2) and a = d alpha (d = 0.2, I = (1 + h^2) / 12), the exact annotator's values for it.
  CollapseInput in;
  in.blocks.push_back({0, -0.3, true});
  const CollapsePreview p = simulate_collapse(in);
  const double h = in.block_height, inertia = (1.0 + h * h) / 12.0, d = 0.2;
  const double alpha = -d / (inertia + d * d);
  REQUIRE(p.initial.size() == 1);
  CHECK(p.initial[0].x == 0.0);
  CHECK(p.initial[0].angle == Approx(alpha).epsilon(1e-9));
  CHECK(p.initial[0].y == Approx(d * alpha).epsilon(1e-9));
}
