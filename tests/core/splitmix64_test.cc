#include "bricklayer/core/splitmix64.h"

#include <catch2/catch.hpp>

using bricklayer::core::splitmix64;
using bricklayer::core::unit_double;

TEST_CASE("splitmix64 gives the reference sequence") {
  // The first outputs from state 0 of the reference implementation (Vigna's splitmix64.c): the piles'
  // digests and simcam's frames rest on this exact sequence.
  uint64_t state = 0;
  CHECK(splitmix64(state) == 0xE220A8397B1DCDAFULL);
  CHECK(splitmix64(state) == 0x6E789E6AA1B965F4ULL);
  CHECK(splitmix64(state) == 0x06C45D188009454FULL);
  CHECK(state == 3 * 0x9E3779B97F4A7C15ULL);
}

TEST_CASE("unit_double maps the top 53 bits to a double from 0 up to but not 1") {
  CHECK(unit_double(0) == 0.0);
  CHECK(unit_double(~0ULL) < 1.0);
  CHECK(unit_double(~0ULL) == 1.0 - 1.0 / 9007199254740992.0);
  CHECK(unit_double(1ULL << 63) == 0.5);
  CHECK(unit_double((1ULL << 11) - 1) == 0.0);  // the low 11 bits are dropped
}
