// Random piles of blocks for benchmarks and tests (vision accuracy, simcam timing): a player's pile
// seen by the default camera (rows shrinking upwards; a pile may grow past the top of the view). Not necessarily balanced; blocks never overlap within a row.
#pragma once

#include <cstdint>

#include "bricklayer/core/stack.h"

namespace bricklayer::piles {

struct PileOptions {
  int blocks = 30;          // exact number of blocks
  double min_x = -5.2;      // left limit of any block's left end, block lengths (default view: -5.33..5.33)
  double max_x = 4.2;       // right limit of any block's right end minus one
  double min_gap = 0.1;     // smallest gap between neighbours in a row, block lengths (0 allows touching)
  double max_gap = 0.8;     // largest gap between neighbours in a row
  int max_per_row = 9;      // at most this many blocks in a row
};

// Rows from the bottom, each row's blocks left to right; ids 1..n in that order (bottom row first),
// block_length 1, block_height 1/3, table_edge 0. Deterministic per seed.
core::Stack random_pile(uint64_t seed, const PileOptions& options = {});

}  // namespace bricklayer::piles
