#include "bricklayer/simcam/piles.h"

#include <algorithm>
#include <stdexcept>
#include <string>

namespace bricklayer::simcam {
namespace {
uint64_t next(uint64_t& s) {
  uint64_t z = (s += 0x9E3779B97F4A7C15ULL);
  z = (z ^ (z >> 30)) * 0xBF58476D1CE4E5B9ULL;
  z = (z ^ (z >> 27)) * 0x94D049BB133111EBULL;
  return z ^ (z >> 31);
}
double uniform(uint64_t& s, double lo, double hi) { return lo + (hi - lo) * (static_cast<double>(next(s) >> 11) / 9007199254740992.0); }
}  // namespace

core::Stack random_pile(uint64_t seed, const PileOptions& o) {
  if (o.blocks < 0 || o.max_per_row < 1 || o.max_x < o.min_x || o.min_gap < 0 || o.max_gap < o.min_gap)
    throw std::invalid_argument("random_pile: bad options (blocks >= 0, max_per_row >= 1, min_x <= max_x, 0 <= min_gap <= max_gap)");
  uint64_t s = seed * 0x9E3779B97F4A7C15ULL + 77;
  core::Stack stack;
  int remaining = o.blocks;
  int row = 0;
  double lo = o.min_x, hi = o.max_x;  // where this row's blocks may start
  while (remaining > 0) {
    // Place left to right from a random start, with random gaps, until the row is full.
    double x = uniform(s, lo, std::min(hi, lo + 1.5));
    double row_left = x, row_right = x;
    int in_row = 0;
    while (remaining > 0 && in_row < o.max_per_row && x <= hi) {
      stack.blocks.push_back({static_cast<int64_t>(stack.blocks.size() + 1), row, x});
      row_right = x + 1.0;
      --remaining;
      ++in_row;
      x += 1.0 + uniform(s, o.min_gap, o.max_gap);
      // Thin rows out as the pile grows, so piles look like piles rather than walls.
      if (in_row >= 2 && uniform(s, 0, 1) < 0.12 * row) break;
    }
    ++row;
    // The next row sits over this one, overhanging a little on either side.
    lo = std::max(o.min_x, row_left - 0.4);
    hi = std::min(o.max_x, row_right - 0.6);
    if (hi < lo) { lo = o.min_x; hi = o.max_x; }
  }
  return stack;
}

}  // namespace bricklayer::simcam
