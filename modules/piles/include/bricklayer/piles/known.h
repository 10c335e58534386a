// Known stacks: the harmonic stack, columns given by their left ends, the seed paper's Figure 15
// cases, the optimal stacks of tests/data/optimal-stacks.json, and a pile with its rightmost block
// pushed.
#pragma once

#include <string>
#include <vector>

#include "bricklayer/core/stack.h"

namespace bricklayer::piles {

// n blocks in one column, block k from the top extending 1/(2k) beyond the block below (overhang H_n / 2).
// Balanced with zero margin. Ids 0..n-1 from the bottom; block_length 1, table_edge 0.
core::Stack harmonic_stack(int n, double block_height = 1.0 / 3.0);

// One block per row, left ends xs from the bottom; ids 0..n-1, the core's default sizes.
core::Stack column(const std::vector<double>& xs);

// Figure 15 of the seed paper: three blocks in a column, ids 0 (bottom), 1 (middle), 2 (upper).
core::Stack figure15_upper_alone();
core::Stack figure15_both();
core::Stack figure15_middle_alone();

// tests/data/optimal-stacks.json in the source tree (the default of fixture_stacks).
std::string default_fixture_path();
// The stacks of a fixture file ({"stacks": [...]}, each as core::stack_from_json reads it). Throws
// std::runtime_error naming the file when it cannot be read, and the core's error when a stack is bad.
std::vector<core::Stack> fixture_stacks(const std::string& path = default_fixture_path());

// s with the block whose right end is furthest right moved by dx.
core::Stack push_rightmost(core::Stack s, double dx);

}  // namespace bricklayer::piles
