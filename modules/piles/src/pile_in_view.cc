#include "bricklayer/piles/pile_in_view.h"

#include <algorithm>
#include <cmath>
#include <random>
#include <vector>

namespace bricklayer::piles {

core::Stack pile_in_view(int n, uint64_t seed) {
  std::mt19937_64 rng(seed);
  const int columns = std::max(5, (n + 20) / 21);
  const double max_gap = std::min(0.3, (10.4 - columns) / std::max(1, columns - 1));
  std::uniform_real_distribution<double> gap(0.04, std::max(0.04, max_gap)), jitter(-0.015, 0.015), unit(0.0, 1.0);
  std::vector<double> base(static_cast<size_t>(columns));
  double width = columns;
  for (int k = 1; k < columns; ++k) width += (base[static_cast<size_t>(k)] = gap(rng));
  double x = -5.25 + unit(rng) * std::max(0.0, 10.5 - width);
  for (int k = 0; k < columns; ++k) {
    x += base[static_cast<size_t>(k)];
    base[static_cast<size_t>(k)] = x;
    x += 1.0;
  }
  core::Stack s;
  for (int id = 1, row = 0; id <= n; ++row)
    for (int k = 0; k < columns && id <= n; ++k, ++id) s.blocks.push_back({id, row, base[static_cast<size_t>(k)] + jitter(rng)});
  if (seed % 2 == 1 && !s.blocks.empty()) {
    // The top block of the rightmost column (the last block placed in that column).
    size_t top = 0;
    for (size_t i = 0; i < s.blocks.size(); ++i)
      if (std::abs(s.blocks[i].x - base.back()) < 0.1 && s.blocks[i].row >= s.blocks[top].row) top = i;
    if (s.blocks[top].row > 0) s.blocks[top].x += 0.6;
  }
  return s;
}

}  // namespace bricklayer::piles
