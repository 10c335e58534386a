// Test piles: the seed paper's Figure 15 cases, fixtures, harmonic stacks, random piles.
#pragma once

#include <fstream>
#include <random>
#include <string>
#include <vector>

#include <nlohmann/json.hpp>

#include "bricklayer/core/stack.h"

namespace bricklayer::core::testing {

inline Stack column(std::vector<double> xs) {
  Stack s;
  for (size_t i = 0; i < xs.size(); ++i) s.blocks.push_back({static_cast<int64_t>(i), static_cast<int32_t>(i), xs[i]});
  return s;
}

// Figure 15 of the seed paper: three blocks in a column, ids 0 (bottom), 1 (middle), 2 (upper).
inline Stack figure15_upper_alone() { return column({-1.2, -1.1, -0.5}); }
inline Stack figure15_both() { return column({-1.2, -0.6, 0.2}); }
inline Stack figure15_middle_alone() { return column({-1.2, -0.6, -0.7}); }

inline std::vector<Stack> fixture_stacks() {
  std::ifstream in(std::string(BRICKLAYER_SOURCE_DIR) + "/tests/data/optimal-stacks.json");
  const nlohmann::json j = nlohmann::json::parse(in);
  std::vector<Stack> out;
  for (const auto& s : j.at("stacks")) out.push_back(stack_from_json(s));
  return out;
}

// Moves the block whose right end is furthest right by dx.
inline Stack push_rightmost(Stack s, double dx) {
  size_t best = 0;
  for (size_t i = 1; i < s.blocks.size(); ++i) {
    if (s.blocks[i].x > s.blocks[best].x) best = i;
  }
  s.blocks[best].x += dx;
  return s;
}

// A chaotic pile: each block lands on a random row near a random block of the row below (some overhang,
// some bridge, a few float). Valid (no overlaps in a row) by construction.
inline Stack random_pile(int n, uint64_t seed) {
  std::mt19937_64 rng(seed);
  std::uniform_real_distribution<double> unit(0.0, 1.0);
  Stack s;
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

}  // namespace bricklayer::core::testing
