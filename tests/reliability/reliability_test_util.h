// Shared by the reliability tests: the bus helpers of tests/bus plus encode_bytes() and slurp().
#pragma once

#include <fstream>
#include <sstream>
#include <string>
#include <vector>

#include "../bus/bus_test_util.h"

namespace bricklayer::test {

template <typename T>
std::vector<uint8_t> encode_bytes(const T& msg) {
  return encode(msg);
}

inline std::string slurp(const std::string& path) {
  std::ifstream in(path);
  std::stringstream s;
  s << in.rdbuf();
  return s.str();
}

}  // namespace bricklayer::test
