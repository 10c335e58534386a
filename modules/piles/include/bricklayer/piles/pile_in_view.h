// Piles the default camera sees whole, for the soak and the end-to-end latency benchmark.
#pragma once

#include <cstdint>

#include "bricklayer/core/stack.h"

namespace bricklayer::piles {

// A pile of n blocks that the default camera sees whole, as a player builds it: columns of blocks standing
// on each other (each block within +-0.015 of its column, so every one rests on the one below), rows of
// ceil(n / 21) (at least 5) columns with gaps of 0.04-0.3, the last row partly filled. For odd seeds the top
// block of the rightmost column leans 0.6 out over its support: an unbalanced pile with a cause, so the
// frames alternate between the two cases prediction meets. The default view is 10.67 block lengths wide
// and 22 rows tall, so up to 210 blocks fit. (random_pile grows piles upwards past the view, and
// vision rightly drops blocks it cannot see whole: the benchmark would time fewer blocks than it names.)
core::Stack pile_in_view(int n, uint64_t seed);

}  // namespace bricklayer::piles
