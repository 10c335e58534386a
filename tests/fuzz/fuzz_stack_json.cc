// The stack parser and validator must answer any bytes with a Stack or a StackError, nothing else.
#include <cstdint>
#include <string_view>

#include "bricklayer/core/predict.h"
#include "bricklayer/core/stack.h"

extern "C" int LLVMFuzzerTestOneInput(const uint8_t* data, size_t size) {
  std::string_view text(reinterpret_cast<const char*>(data), size);
  bricklayer::core::StackLimits limits;
  limits.max_blocks = 64;  // keep each input cheap; the limit itself is part of what is checked
  try {
    bricklayer::core::Stack stack = bricklayer::core::parse_stack(text, limits);
    // A valid stack must also be predictable without a crash.
    (void)bricklayer::core::predict(stack);
  } catch (const bricklayer::core::StackError&) {
  } catch (const bricklayer::core::SolverError&) {
  }
  return 0;
}
