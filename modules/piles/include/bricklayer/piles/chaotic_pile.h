// A chaotic pile for the physics tests: blocks land anywhere, not as a player builds.
#pragma once

#include <cstdint>

#include "bricklayer/core/stack.h"

namespace bricklayer::piles {

// Each block lands on a random row near a random block of the row below (some overhang, some bridge,
// a few float); a random block height in [0.2, 0.6). Valid (no overlaps in a row) by construction.
// Same seed -> same pile. Ids 0..n-1 in the order placed.
core::Stack chaotic_pile(int n, uint64_t seed);

}  // namespace bricklayer::piles
