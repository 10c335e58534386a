// The board geometry file loader: any bytes give a geometry or a clear std::runtime_error.
#include <cstdint>
#include <stdexcept>
#include <string>

#include "bricklayer/board/board_geometry.h"

extern "C" int LLVMFuzzerTestOneInput(const uint8_t* data, size_t size) {
  try {
    (void)bricklayer::parse_board_geometry(std::string(reinterpret_cast<const char*>(data), size));
  } catch (const std::runtime_error&) {
  }
  return 0;
}
