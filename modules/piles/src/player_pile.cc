#include "bricklayer/piles/player_pile.h"

#include <algorithm>
#include <cmath>
#include <random>

namespace bricklayer::piles {

core::Stack player_pile(int n, uint64_t seed, double block_height) {
  std::mt19937_64 rng(seed);
  std::uniform_real_distribution<double> unit(0.0, 1.0);
  core::Stack stack;
  stack.block_height = block_height;
  if (n <= 0) return stack;
  const int width = std::max(1, static_cast<int>(std::lround(std::sqrt(1.5 * n))));
  const int rows = width >= 2 ? 1 + (std::max(0, n - width) + width - 2) / (width - 1) : n;  // rows above 0 hold width - 1
  // The right-hand column leans over the edge like a harmonic stack scaled by `lean` (about 1 is the knife
  // edge: most piles stay below it, some go past it); the rest of each row is a staggered brick wall.
  const double lean = 0.3 + 0.75 * unit(rng);
  const double gap = 0.04 + 0.08 * unit(rng);  // one gap per pile, so rows keep their lengths
  double right = 0.0;
  int placed = 0;
  for (int row = 0; row < rows && placed < n; ++row) {
    const double step = lean * (1.0 + 0.1 * (2.0 * unit(rng) - 1.0)) / (2.0 * (rows - row));
    right += step;
    const double column_x = right - 1.0;
    stack.blocks.push_back({static_cast<int64_t>(placed++), row, column_x});
    double x = column_x - 1.0 - gap - (row % 2 ? 0.5 : 0.0);
    for (int k = 1; k < width - (row > 0 ? 1 : 0) && placed < n; ++k) {
      stack.blocks.push_back({static_cast<int64_t>(placed++), row, x + 0.03 * (unit(rng) - 0.5)});
      x -= 1.0 + gap;
    }
  }
  return stack;
}

}  // namespace bricklayer::piles
