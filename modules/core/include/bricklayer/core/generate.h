// Deterministic example piles for tests, benchmarks and demos.
#pragma once

#include <cstdint>

#include "bricklayer/core/stack.h"

namespace bricklayer::core {

// n blocks in one column, block k from the top extending 1/(2k) beyond the block below (overhang H_n / 2).
// Balanced with zero margin. Ids 0..n-1 from the bottom; block_length 1, table_edge 0.
Stack harmonic_stack(int n, double block_height = 1.0 / 3.0);

// A pile "built as a player would": staggered rows (a brick wall) that creep right over the surface edge,
// with placement jitter. Most are balanced, some are not. Same seed -> same pile. Ids 0..n-1.
Stack player_pile(int n, uint64_t seed, double block_height = 1.0 / 3.0);

}  // namespace bricklayer::core
