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

}  // namespace bricklayer::planner
