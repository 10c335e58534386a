#include "bricklayer/core/contacts.h"

#include <algorithm>

namespace bricklayer::core {

ContactGraph build_contacts(const Stack& stack, double position_tolerance) {
  ContactGraph g;
  const size_t n = stack.blocks.size();
  g.height = stack.block_height / stack.block_length;
  g.x.resize(n);
  g.row.resize(n);
  g.supports.assign(n, {});
  g.carries.assign(n, {});
  int32_t max_row = -1;
  for (size_t i = 0; i < n; ++i) {
    g.x[i] = (stack.blocks[i].x - stack.table_edge) / stack.block_length;
    g.row[i] = stack.blocks[i].row;
    max_row = std::max(max_row, g.row[i]);
  }
  g.rows.assign(static_cast<size_t>(max_row + 1), {});
  for (size_t i = 0; i < n; ++i) g.rows[static_cast<size_t>(g.row[i])].push_back(static_cast<int>(i));
  for (auto& r : g.rows) {
    std::sort(r.begin(), r.end(), [&](int a, int b) { return g.x[static_cast<size_t>(a)] < g.x[static_cast<size_t>(b)] || (g.x[static_cast<size_t>(a)] == g.x[static_cast<size_t>(b)] && a < b); });
  }
  auto add = [&](int upper, int lower, double left, double right) {
    const int index = static_cast<int>(g.contacts.size());
    g.contacts.push_back({upper, lower, left - position_tolerance, right + position_tolerance});
    g.supports[static_cast<size_t>(upper)].push_back(index);
    if (lower != kSurface) g.carries[static_cast<size_t>(lower)].push_back(index);
  };
  for (size_t r = 0; r < g.rows.size(); ++r) {
    if (r == 0) {
      for (int i : g.rows[0]) {
        const double left = g.x[static_cast<size_t>(i)];
        const double right = std::min(left + 1.0, 0.0);
        if (right - left > kContactTolerance) add(i, kSurface, left, right);
      }
      continue;
    }
    const auto& below = g.rows[r - 1];
    size_t start = 0;  // first block below that may still overlap (rows are sorted, blocks in a row disjoint)
    for (int i : g.rows[r]) {
      const double left = g.x[static_cast<size_t>(i)];
      while (start < below.size() && g.x[static_cast<size_t>(below[start])] + 1.0 <= left) ++start;
      for (size_t k = start; k < below.size(); ++k) {
        const int j = below[k];
        const double lx = g.x[static_cast<size_t>(j)];
        if (lx >= left + 1.0) break;
        const double lo = std::max(left, lx);
        const double hi = std::min(left + 1.0, lx + 1.0);
        if (hi - lo > kContactTolerance) add(i, j, lo, hi);
      }
    }
  }
  return g;
}

}  // namespace bricklayer::core
