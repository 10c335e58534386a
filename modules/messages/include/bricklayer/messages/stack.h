// stack_t <-> core::Stack.
#pragma once

#include <cstdint>

#include "bricklayer/core/stack.h"
#include "bricklayer/stack_t.hpp"

namespace bricklayer::messages {

// The core's model of a measured stack: units, edge, and each block's id, row and x (no validation:
// core::validate or core::predict check it).
core::Stack to_core_stack(const stack_t& stack);

// A stack_t of a model stack (STATUS_OK, confidence 1, no pixel geometry), carrying utime and
// frame_number: what a simulated camera's truth or a test publishes.
stack_t to_stack_message(const core::Stack& stack, int64_t utime, int64_t frame_number);

}  // namespace bricklayer::messages
