#include "bricklayer/messages/stack.h"

namespace bricklayer::messages {

core::Stack to_core_stack(const stack_t& stack) {
  core::Stack s;
  s.block_length = stack.block_length;
  s.block_height = stack.block_height;
  s.table_edge = stack.table_edge;
  s.blocks.reserve(stack.blocks.size());
  for (const auto& b : stack.blocks) s.blocks.push_back(core::Block{b.id, b.row, b.x});
  return s;
}

stack_t to_stack_message(const core::Stack& stack, int64_t utime, int64_t frame_number) {
  stack_t s{};
  s.utime = utime;
  s.frame_number = frame_number;
  s.block_length = stack.block_length;
  s.block_height = stack.block_height;
  s.table_edge = stack.table_edge;
  s.status = stack_t::STATUS_OK;
  s.blocks.reserve(stack.blocks.size());
  for (const auto& b : stack.blocks) {
    block_t m{};
    m.id = b.id;
    m.row = b.row;
    m.x = b.x;
    m.confidence = 1.0;
    s.blocks.push_back(m);
  }
  s.num_blocks = static_cast<int32_t>(s.blocks.size());
  return s;
}

}  // namespace bricklayer::messages
