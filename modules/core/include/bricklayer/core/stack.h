// A pile of identical blocks against the board, and its validation.
// Units: x, block_length, block_height and table_edge share one length unit (block lengths when
// block_length == 1). x is a block's left end; row 0 rests on the surface, which occupies x <= table_edge.
#pragma once

#include <cstdint>
#include <stdexcept>
#include <string>
#include <string_view>
#include <vector>

#include <nlohmann/json_fwd.hpp>

namespace bricklayer::core {

struct Block {
  int64_t id = 0;
  int32_t row = 0;
  double x = 0.0;
};

struct Stack {
  double block_length = 1.0;
  double block_height = 1.0 / 3.0;
  double table_edge = 0.0;
  std::vector<Block> blocks;
};

struct StackLimits {
  size_t max_blocks = 2000;
};

// Invalid input: a one-line message that names the offending block or field.
class StackError : public std::runtime_error {
 public:
  using std::runtime_error::runtime_error;
};

// Throws StackError for NaN/infinite numbers, non-positive sizes, negative rows, duplicate ids, two blocks
// overlapping in one row, or more than limits.max_blocks blocks. A block resting on nothing is valid.
void validate(const Stack& stack, const StackLimits& limits = {});

// Parses bricklayer-predict's input format and validates it. Throws StackError.
Stack stack_from_json(const nlohmann::json& json, const StackLimits& limits = {});
Stack parse_stack(std::string_view text, const StackLimits& limits = {});

}  // namespace bricklayer::core
