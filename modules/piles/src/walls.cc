#include "bricklayer/piles/walls.h"

#include <random>

namespace bricklayer::piles {

core::Stack wall_pile(int rows, int per_row, uint64_t seed, double reach) {
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

core::Stack toppling_pile(int rows, int per_row, int shifted_rows, double shift, uint64_t seed) {
  core::Stack s = wall_pile(rows, per_row, seed);
  for (core::Block& b : s.blocks)
    if (b.row >= rows - shifted_rows) b.x += shift;
  return s;
}

core::Stack stairs_pile(int rows, int per_row, double step, uint64_t seed) {
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

core::Stack tower_pile(int rows, int lean_from, double shift, uint64_t seed) {
  std::mt19937_64 rng(seed);
  std::uniform_real_distribution<double> jitter(-0.03, 0.03);
  core::Stack s;
  for (int r = 0; r < rows; ++r) s.blocks.push_back({r + 1, r, -0.9 + jitter(rng) + (r >= lean_from ? shift : 0.0)});
  return s;
}

}  // namespace bricklayer::piles
