// Deterministic test and benchmark piles (walls of staggered rows), shared by tests/planner and the benchmark.
#pragma once

#include <cstdint>
#include <random>

#include "bricklayer/core/stack.h"

namespace bricklayer::planner {

// A wall of `rows` rows of `per_row` blocks ending near the surface edge, rows staggered by 0.3 and
// jittered by the seed (seed 0: no jitter). The rightmost block of each row ends at most `reach` beyond the edge.
inline core::Stack wall_pile(int rows, int per_row, uint64_t seed = 0, double reach = 0.0) {
  std::mt19937_64 rng(seed);
  std::uniform_real_distribution<double> jitter(-0.08, 0.08), gap(0.0, 0.08);
  core::Stack s;
  int64_t id = 1;
  for (int r = 0; r < rows; ++r) {
    double x = reach - 1.0 - (r % 2 ? 0.3 : 0.0) + (seed ? jitter(rng) - 0.08 : 0.0);
    for (int k = 0; k < per_row; ++k) {
      s.blocks.push_back({id++, r, x});
      x -= 1.0 + (seed ? gap(rng) : 0.0);
    }
  }
  return s;
}

// wall_pile with the top `shifted_rows` rows pushed right by `shift`: their blocks topple over the edge.
inline core::Stack toppling_pile(int rows, int per_row, int shifted_rows, double shift, uint64_t seed = 0) {
  core::Stack s = wall_pile(rows, per_row, seed);
  for (core::Block& b : s.blocks)
    if (b.row >= rows - shifted_rows) b.x += shift;
  return s;
}

// A wide wall of `rows` rows of `per_row` blocks in brick bond whose rows step out over the edge by `step`
// each (row 0 ends at the edge), jittered by the seed: the steps beyond the balance limit collapse.
inline core::Stack stairs_pile(int rows, int per_row, double step, uint64_t seed) {
  std::mt19937_64 rng(seed);
  std::uniform_real_distribution<double> jitter(-0.04, 0.04), gap(0.0, 0.03);
  core::Stack s;
  int64_t id = 1;
  for (int r = 0; r < rows; ++r) {
    double x = step * r - 1.0 + jitter(rng);
    for (int k = 0; k < per_row; ++k) {
      s.blocks.push_back({id++, r, x});
      x -= 1.0 + gap(rng);
    }
  }
  return s;
}

// A single-column tower of `rows` blocks (centres 0.4 inside the edge, jittered); rows from `lean_from` up
// are pushed right by `shift`, so the part above leans over its support and topples.
inline core::Stack tower_pile(int rows, int lean_from, double shift, uint64_t seed) {
  std::mt19937_64 rng(seed);
  std::uniform_real_distribution<double> jitter(-0.03, 0.03);
  core::Stack s;
  for (int r = 0; r < rows; ++r) s.blocks.push_back({r + 1, r, -0.9 + jitter(rng) + (r >= lean_from ? shift : 0.0)});
  return s;
}

}  // namespace bricklayer::planner
