// lcmtypes/harden_decoders.cmake: hostile length fields are rejected before anything is allocated.
#include <cstring>
#include <vector>

#include <catch2/catch.hpp>

#include "bricklayer/command_t.hpp"
#include "bricklayer/heartbeat_t.hpp"
#include "bricklayer/stack_t.hpp"

using namespace bricklayer;

namespace {
// Overwrites the big-endian int32 at byte offset `at`.
void poke_int32(std::vector<uint8_t>& bytes, size_t at, int32_t value) {
  uint32_t v = static_cast<uint32_t>(value);
  for (int i = 0; i < 4; ++i) bytes[at + i] = static_cast<uint8_t>(v >> (24 - 8 * i));
}
template <typename T>
std::vector<uint8_t> encode(const T& msg) {
  std::vector<uint8_t> bytes(static_cast<size_t>(msg.getEncodedSize()));
  REQUIRE(msg.encode(bytes.data(), 0, static_cast<int>(bytes.size())) == static_cast<int>(bytes.size()));
  return bytes;
}
}  // namespace

TEST_CASE("a stack claiming more blocks than its bytes could hold is rejected without allocating") {
  stack_t s{};
  auto bytes = encode(s);
  // fingerprint 8 + utime 8 + frame 8 + three doubles 24 + status 1 = offset 49 of num_blocks
  for (int32_t claim : {100000000, -5, 1}) {
    poke_int32(bytes, 49, claim);
    stack_t out{};
    CHECK(out.decode(bytes.data(), 0, static_cast<int>(bytes.size())) < 0);
    CHECK(out.blocks.size() <= bytes.size());
  }
}

TEST_CASE("a negative or oversized string length is rejected, not thrown") {
  command_t c{};
  c.argument = "hello";
  auto bytes = encode(c);
  size_t at = bytes.size() - (4 + 6);  // the argument is last: int32 length + "hello\0"
  for (int32_t claim : {-1, 0, -2147483647, 1 << 30}) {
    poke_int32(bytes, at, claim);
    command_t out{};
    CHECK_NOTHROW(out.decode(bytes.data(), 0, static_cast<int>(bytes.size())));
    CHECK(out.decode(bytes.data(), 0, static_cast<int>(bytes.size())) < 0);
  }
}

TEST_CASE("valid messages still round-trip after hardening") {
  heartbeat_t hb{};
  hb.module = "vision";
  hb.num_values = 2;
  hb.value_names = {"a", "drift_px"};
  hb.values = {1.0, 0.5};
  auto bytes = encode(hb);
  heartbeat_t out{};
  REQUIRE(out.decode(bytes.data(), 0, static_cast<int>(bytes.size())) == static_cast<int>(bytes.size()));
  CHECK(out.value_names[1] == "drift_px");
  CHECK(out.values[1] == 0.5);
}
