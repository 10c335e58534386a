// Contact geometry of a stack: rows, contact intervals and the support graph, in normalised units
// (block length 1, surface edge at x = 0). Shared by the annotators, the collapse simulator and the planner.
#pragma once

#include <cstdint>
#include <vector>

#include "bricklayer/core/stack.h"

namespace bricklayer::core {

// Two intervals are in contact when they overlap by MORE than this many block lengths (an overlap of
// 1e-4 is a contact; ends that merely touch, up to rounding, are not). Blocks of one row may overlap by at
// most this much.
inline constexpr double kContactTolerance = 1e-9;

inline constexpr int kSurface = -1;  // "lower" index of a contact with the surface

struct Contact {
  int upper = 0;        // index into Stack::blocks
  int lower = kSurface;  // index into Stack::blocks, or kSurface
  double left = 0.0;    // contact interval [left, right], normalised x (edge at 0)
  double right = 0.0;
};

struct ContactGraph {
  double height = 1.0 / 3.0;  // block height in block lengths
  std::vector<double> x;      // left end of each block, normalised (block lengths, edge at 0)
  std::vector<int32_t> row;   // row of each block
  std::vector<Contact> contacts;           // grouped by upper block, in order of increasing left
  std::vector<std::vector<int>> supports;  // supports[i]: contact indices where block i is the upper one
  std::vector<std::vector<int>> carries;   // carries[i]: contact indices where block i is the lower one
  std::vector<std::vector<int>> rows;      // rows[r]: block indices of row r, sorted by x
  int num_rows() const { return static_cast<int>(rows.size()); }
  size_t size() const { return x.size(); }
  double centre(int i) const { return x[static_cast<size_t>(i)] + 0.5; }
  bool floating(int i) const { return supports[static_cast<size_t>(i)].empty(); }
};

// Normalises (x - table_edge) / block_length and finds every contact in O(n log n). Does not validate.
// position_tolerance (block lengths, >= 0): how far a measured position may be off. Each contact interval is
// widened by it at both ends (a support force may act up to that far beyond the measured end of a contact,
// the surface edge included), so a pile that would be balanced with its blocks moved by about that much reads
// balanced. Whether two blocks touch is still decided on the measured overlap. 0 = the positions are exact.
ContactGraph build_contacts(const Stack& stack, double position_tolerance = 0.0);

}  // namespace bricklayer::core
