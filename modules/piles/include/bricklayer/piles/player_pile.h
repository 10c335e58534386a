// A pile "built as a player would", for the prediction benchmarks and tests.
#pragma once

#include <cstdint>

#include "bricklayer/core/stack.h"

namespace bricklayer::piles {

// Staggered rows (a brick wall) that creep right over the surface edge, with placement jitter. Most
// are balanced, some are not. Same seed -> same pile. Ids 0..n-1.
core::Stack player_pile(int n, uint64_t seed, double block_height = 1.0 / 3.0);

}  // namespace bricklayer::piles
