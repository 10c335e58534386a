#include "bricklayer/piles/chaotic_pile.h"

#include <cmath>
#include <random>
#include <vector>

namespace bricklayer::piles {

core::Stack chaotic_pile(int n, uint64_t seed) {
  std::mt19937_64 rng(seed);
  std::uniform_real_distribution<double> unit(0.0, 1.0);
  core::Stack s;
  s.block_height = 0.2 + 0.4 * unit(rng);
  std::vector<std::vector<double>> rows;
  int64_t id = 0;
  while (static_cast<int>(s.blocks.size()) < n) {
    int row = rows.empty() ? 0 : static_cast<int>(unit(rng) * static_cast<double>(rows.size() + 1));
    if (row > 0 && rows[static_cast<size_t>(row - 1)].empty()) row = 0;
    double x;
    if (row == 0) {
      x = -2.5 + 2.9 * unit(rng);
    } else {
      const auto& below = rows[static_cast<size_t>(row - 1)];
      const double base = below[static_cast<size_t>(unit(rng) * static_cast<double>(below.size())) % below.size()];
      x = base + (unit(rng) - 0.5) * (unit(rng) < 0.05 ? 3.0 : 1.3);
    }
    if (row == static_cast<int>(rows.size())) rows.emplace_back();
    bool fits = true;
    for (double other : rows[static_cast<size_t>(row)]) fits = fits && std::abs(other - x) >= 1.0;
    if (!fits) continue;
    rows[static_cast<size_t>(row)].push_back(x);
    s.blocks.push_back({id++, row, x});
  }
  return s;
}

}  // namespace bricklayer::piles
