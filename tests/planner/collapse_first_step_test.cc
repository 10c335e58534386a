// The collapse preview's first step against the exact annotator (DESIGN.md "The physics"): released from
// rest, the blocks that move in the simulation's first step are exactly the ones core::predict calls moving,
// and they move the way its initial accelerations say (down or up, turning clockwise or counter-clockwise, no
// sideways motion), over many seeded unbalanced piles and the zero-margin optimal and harmonic stacks moved
// past the edge. README "First step" states what is compared and why it can be.
#include "bricklayer/planner/collapse.h"

#include <catch2/catch.hpp>

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <fstream>
#include <string>
#include <vector>

#include <nlohmann/json.hpp>

#include "bricklayer/core/predict.h"
#include "bricklayer/piles/chaotic_pile.h"
#include "bricklayer/piles/known.h"
#include "bricklayer/piles/player_pile.h"
#include "bricklayer/piles/walls.h"

using namespace bricklayer;

namespace {

struct Pile {
  std::string name;
  core::Stack stack;
};

core::Stack shifted(core::Stack s, double dx) {
  for (core::Block& b : s.blocks) b.x += dx;
  return s;
}

core::Stack from_rows(const nlohmann::json& blocks) {
  core::Stack s;
  int64_t id = 0;
  for (const auto& b : blocks) s.blocks.push_back({id++, b.at("row").get<int>(), b.at("x").get<double>()});
  return s;
}

// Zero-margin stacks (balanced exactly at their knife edge): the published optima (tests/data, the same file
// as the shared fixtures), the planner's shipped best stacks and harmonic stacks.
std::vector<Pile> knife_edge_stacks() {
  std::vector<Pile> out;
  for (const core::Stack& s : piles::fixture_stacks()) out.push_back({"optimal-" + std::to_string(s.blocks.size()), s});
  std::ifstream in(std::string(BRICKLAYER_SOURCE_DIR) + "/modules/planner/data/best_overhang_stacks.json");
  REQUIRE(in);
  const nlohmann::json shipped = nlohmann::json::parse(in);
  for (const auto& [n, stack] : shipped.items()) out.push_back({"best-" + n, from_rows(stack.at("blocks"))});
  for (int n = 1; n <= 40; ++n) out.push_back({"harmonic-" + std::to_string(n), piles::harmonic_stack(n)});
  return out;
}

// The piles checked (the unbalanced ones among them: a balanced pile gets no preview). Deterministic.
std::vector<Pile> checked_piles() {
  std::vector<Pile> out;
  auto add = [&out](std::string name, core::Stack s) { out.push_back({std::move(name), std::move(s)}); };
  // Knife-edge stacks moved past the edge: the whole stack by d, and the rightmost block alone by d.
  for (const Pile& p : knife_edge_stacks())
    for (double d : {1e-4, 1e-3, 1e-2, 0.1, 0.4}) {
      add(p.name + " shifted " + std::to_string(d), shifted(p.stack, d));
      add(p.name + " rightmost pushed " + std::to_string(d), piles::push_rightmost(p.stack, d));
    }
  // Piles as players build them (mostly balanced; the unbalanced ones are kept below).
  for (uint64_t seed = 1; seed <= 1500; ++seed) add("player " + std::to_string(seed), piles::player_pile(5 + static_cast<int>(seed % 56), seed));
  // Chaotic piles: blocks bridging, overhanging both ways, floating; block heights 0.2 to 0.6.
  for (uint64_t seed = 1; seed <= 400; ++seed) add("random " + std::to_string(seed), piles::chaotic_pile(3 + static_cast<int>(seed % 40), seed));
  // The preview benchmark's kinds, smaller and larger.
  for (uint64_t seed = 1; seed <= 60; ++seed) {
    const int rows = 3 + static_cast<int>(seed % 10), per_row = 2 + static_cast<int>(seed % 4);
    add("wall " + std::to_string(seed), piles::toppling_pile(rows, per_row, 1 + static_cast<int>(seed % 4),
                                                               0.5 + 0.02 * static_cast<double>(seed % 50), seed));
    add("stairs " + std::to_string(seed), piles::stairs_pile(2 + static_cast<int>(seed % 6), 10, 0.42 + 0.002 * static_cast<double>(seed % 40), seed));
    add("tower " + std::to_string(seed), piles::tower_pile(10 + static_cast<int>(seed % 51), 5 + static_cast<int>(seed % 5),
                                                              0.55 + 0.005 * static_cast<double>(seed % 40), seed));
  }
  return out;
}

// The planner's input for a pile and its verdict, as PlannerLogic builds it: blocks the annotator calls
// stable start asleep unless their acceleration is nonzero below the tolerance (planner::starts_awake).
planner::CollapseInput input_for(const core::Stack& s, const core::Prediction& p) {
  planner::CollapseInput in;
  in.block_height = s.block_height / s.block_length;
  in.table_edge = 0.0;
  for (size_t i = 0; i < s.blocks.size(); ++i)
    in.blocks.push_back({s.blocks[i].row, (s.blocks[i].x - s.table_edge) / s.block_length,
                         planner::starts_awake(p.blocks[i].state == core::BlockState::kStable, p.blocks[i].accel,
                                               p.blocks[i].alpha)});
  return in;
}

// Moving as the exact annotator defines it (DESIGN.md: a nonzero initial acceleration; the QP's tolerance), for
// the annotator's accelerations and the simulation's alike. The simulation's x counts too: the annotator has none.
bool moves(double x, double y, double angle) {
  return std::abs(x) + std::abs(y) + 0.5 * std::abs(angle) > core::kAccelerationTolerance;
}
int sign(double v) { return v > core::kAccelerationTolerance ? 1 : v < -core::kAccelerationTolerance ? -1 : 0; }

// Ends of two blocks (in one row, or in adjacent rows without overlapping) closer than the simulation's contact
// margin: only there can the simulation find a contact with a sideways normal in the first step.
bool ends_close(const core::Stack& s) {
  const double margin = 0.02 * s.block_length;
  for (size_t i = 0; i < s.blocks.size(); ++i)
    for (size_t j = i + 1; j < s.blocks.size(); ++j) {
      const core::Block &a = s.blocks[i], &b = s.blocks[j];
      const double gap = std::abs(a.x - b.x) - s.block_length;
      if ((a.row == b.row || (std::abs(a.row - b.row) == 1 && gap >= -core::kContactTolerance)) && gap < margin)
        return true;
    }
  return false;
}

}  // namespace

TEST_CASE("the preview's first step moves the blocks the exact annotator moves, the same way") {
  const std::vector<Pile> all = checked_piles();
  planner::CollapseOptions first_step;
  first_step.max_time = 0.05;  // only the first step is compared; it is the full preview's first step (below)
  int checked = 0, sideways_piles = 0, blocks = 0, moving = 0, causes_at_rest = 0;
  int sideways_blocks = 0, sideways_turn_differs = 0, pushed_within_tolerance = 0, awake_within_tolerance = 0;
  double worst = 0.0, worst_sideways_y = 0.0;
  for (const Pile& pile : all) {
    const core::Prediction p = core::predict(pile.stack);
    if (p.balanced) continue;
    ++checked;
    const planner::CollapseInput input = input_for(pile.stack, p);
    const planner::CollapsePreview preview = planner::simulate_collapse(input, first_step);
    REQUIRE(preview.initial.size() == pile.stack.blocks.size());
    if (checked % 25 == 1) {  // the same first step as the whole preview the planner publishes
      const planner::CollapsePreview full = planner::simulate_collapse(input);
      for (size_t i = 0; i < full.initial.size(); ++i) {
        INFO(pile.name << " block " << i);
        REQUIRE(full.initial[i].x == preview.initial[i].x);
        REQUIRE(full.initial[i].y == preview.initial[i].y);
        REQUIRE(full.initial[i].angle == preview.initial[i].angle);
      }
    }
    // A contact with a sideways normal that carries an impulse moves some block sideways (README "First step").
    bool pushed_sideways = false;
    for (const planner::Acceleration& a : preview.initial) pushed_sideways = pushed_sideways || a.x != 0.0;
    sideways_piles += pushed_sideways;
    if (pushed_sideways) {
      INFO(pile.name << ": pushed sideways, so two blocks' ends are within the contact margin");
      CHECK(ends_close(pile.stack));
    }
    for (size_t i = 0; i < pile.stack.blocks.size(); ++i) {
      ++blocks;
      const core::BlockVerdict& v = p.blocks[i];
      const planner::Acceleration& a = preview.initial[i];
      const bool exact_moves = moves(0.0, v.accel, v.alpha);
      moving += exact_moves;
      // The annotator may call a block a cause that does not move at all (README "First step"): it moves with
      // the rows under it held fixed, and the simulation frees those.
      causes_at_rest += v.state == core::BlockState::kCause && !exact_moves;
      INFO(pile.name << " block " << i << " (row " << pile.stack.blocks[i].row << "): exact a " << v.accel << " alpha "
                     << v.alpha << ", first step " << a.x << ", " << a.y << ", " << a.angle);
      // The same blocks move, and up or down the same way, always; except that a sideways push may move a block
      // the annotator holds only within its tolerance (started awake: a nonzero acceleration below 1e-6).
      const bool held_within_tolerance =
          !exact_moves && v.state == core::BlockState::kStable && planner::starts_awake(true, v.accel, v.alpha);
      awake_within_tolerance += held_within_tolerance;
      if (pushed_sideways && held_within_tolerance && moves(a.x, a.y, a.angle))
        ++pushed_within_tolerance;
      else
        CHECK(moves(a.x, a.y, a.angle) == exact_moves);
      CHECK(sign(a.y) == sign(v.accel));
      if (!pushed_sideways) {
        // No sideways contact: the first step is the annotator's QP, solved exactly.
        CHECK(a.x == 0.0);
        CHECK(a.y == Approx(v.accel).margin(1e-8));
        CHECK(a.angle == Approx(v.alpha).margin(1e-8));
        worst = std::max({worst, std::abs(a.y - v.accel), std::abs(a.angle - v.alpha)});
      } else if (exact_moves) {
        ++sideways_blocks;
        worst_sideways_y = std::max(worst_sideways_y, std::abs(a.y - v.accel));
        // Turning: the same way wherever the annotator turns the block at all; the sideways push may turn a block
        // the annotator only lifts or lowers.
        if (sign(v.alpha) != 0) CHECK(sign(a.angle) == sign(v.alpha));
        sideways_turn_differs += sign(a.angle) != sign(v.alpha);
      }
    }
  }
  std::printf("first step: %d unbalanced piles (%d blocks, %d moving), %d pushed sideways (%d moving blocks in them, %d of "
              "them turning where the annotator does not); worst difference without sideways pushes %.1e, worst vertical "
              "difference with them %.3f; %d causes that do not move; %d stable blocks held only within the tolerance "
              "(started awake), %d of them pushed sideways\n",
              checked, blocks, moving, sideways_piles, sideways_blocks, sideways_turn_differs, worst, worst_sideways_y,
              causes_at_rest, awake_within_tolerance, pushed_within_tolerance);
  CHECK(checked >= 1000);
}
