// Walls of staggered rows, stairs and towers: the planner's benchmark kinds (collapse previews and hints
// time them), deterministic per seed.
#pragma once

#include <cstdint>

#include "bricklayer/core/stack.h"

namespace bricklayer::piles {

// A wall of `rows` rows of `per_row` blocks ending near the surface edge, rows staggered by 0.3 and
// jittered by the seed (seed 0: no jitter). The rightmost block of each row ends at most `reach` beyond the edge.
core::Stack wall_pile(int rows, int per_row, uint64_t seed = 0, double reach = 0.0);

// wall_pile with the top `shifted_rows` rows pushed right by `shift`: their blocks topple over the edge.
core::Stack toppling_pile(int rows, int per_row, int shifted_rows, double shift, uint64_t seed = 0);

// A wide wall of `rows` rows of `per_row` blocks in brick bond whose rows step out over the edge by `step`
// each (row 0 ends at the edge), jittered by the seed: the steps beyond the balance limit collapse.
core::Stack stairs_pile(int rows, int per_row, double step, uint64_t seed);

// A single-column tower of `rows` blocks (centres 0.4 inside the edge, jittered); rows from `lean_from` up
// are pushed right by `shift`, so the part above leans over its support and topples.
core::Stack tower_pile(int rows, int lean_from, double shift, uint64_t seed);

}  // namespace bricklayer::piles
