// Deterministic sample stacks for tests and benchmarks: brick-wall piles with small jitter, shifted
// towards the edge by a seeded amount so some stand and some fall. Same seed -> same bytes.
#pragma once

#include <cstdint>

#include "bricklayer/stack_t.hpp"

namespace bricklayer::prediction {

// A valid pile (no overlaps within a row) of num_blocks blocks, with the given utime and frame_number.
stack_t sample_stack(int num_blocks, uint32_t seed, int64_t utime, int64_t frame_number);

}  // namespace bricklayer::prediction
