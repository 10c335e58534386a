#include "bricklayer/piles/random_pile.h"

#include <algorithm>
#include <cmath>
#include <stdexcept>
#include <string>

#include "bricklayer/core/splitmix64.h"

namespace bricklayer::piles {
namespace {
double uniform(uint64_t& s, double lo, double hi) { return lo + (hi - lo) * core::unit_double(core::splitmix64(s)); }
}  // namespace

core::Stack random_pile(uint64_t seed, const PileOptions& o) {
  if (o.blocks < 0 || o.max_per_row < 1 || o.max_x < o.min_x || o.min_gap < 0 || o.max_gap < o.min_gap)
    throw std::invalid_argument("random_pile: bad options (blocks >= 0, max_per_row >= 1, min_x <= max_x, 0 <= min_gap <= max_gap)");
  uint64_t s = seed * 0x9E3779B97F4A7C15ULL + 77;
  core::Stack stack;
  int remaining = o.blocks;
  int row = 0;
  double lo = o.min_x, hi = o.max_x;  // where this row's left ends may lie
  // Rows shrink upwards like a player's pile: the bottom row takes about sqrt(2n) blocks.
  int target = std::clamp(static_cast<int>(std::ceil(std::sqrt(2.0 * o.blocks))), 1, o.max_per_row);
  while (remaining > 0) {
    double x = uniform(s, lo, std::min(hi, lo + 0.6));
    double row_left = x, row_right = x + 1.0;
    int in_row = 0;
    while (remaining > 0 && in_row < target && x <= hi) {
      stack.blocks.push_back({static_cast<int64_t>(stack.blocks.size() + 1), row, x});
      row_right = x + 1.0;
      --remaining;
      ++in_row;
      x += 1.0 + uniform(s, o.min_gap, o.max_gap);
    }
    ++row;
    if (uniform(s, 0, 1) < 0.6) target = std::max(1, target - 1);
    // The next row sits over this one, overhanging a little on either side.
    lo = std::max(o.min_x, row_left - 0.3);
    hi = std::min(o.max_x, row_right - 0.7);
    if (hi < lo) { lo = o.min_x; hi = o.max_x; target = std::clamp(remaining, 1, o.max_per_row); }
  }
  return stack;
}

}  // namespace bricklayer::piles
