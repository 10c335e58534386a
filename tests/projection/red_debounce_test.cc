#include "bricklayer/projection/red_debounce.h"

#include <catch2/catch.hpp>

using namespace bricklayer::projection;

namespace {
// Feeds `red` every 10 ms over [from, to) and returns the times at which a beep started.
std::vector<int64_t> feed(RedDebounce& d, bool red, int64_t from, int64_t to) {
  std::vector<int64_t> beeps;
  for (int64_t t = from; t < to; t += 10)
    if (d.update(red, t)) beeps.push_back(t);
  return beeps;
}
}  // namespace

TEST_CASE("red must hold 300 ms before the beep, which sounds once while red stays") {
  RedDebounce d(300, 1000);
  CHECK(feed(d, false, 0, 500).empty());
  auto beeps = feed(d, true, 500, 3000);
  REQUIRE(beeps.size() == 1);
  CHECK(beeps[0] == 800);
}

TEST_CASE("red flicker shorter than the hold never beeps") {
  RedDebounce d(300, 1000);
  for (int64_t t = 0; t < 5000; t += 400) {
    CHECK(feed(d, true, t, t + 200).empty());
    CHECK(feed(d, false, t + 200, t + 400).empty());
  }
}

TEST_CASE("the beep re-arms only after red has been gone for a second") {
  RedDebounce d(300, 1000);
  CHECK(feed(d, true, 0, 1000).size() == 1);
  // Gone for 0.5 s: not re-armed; red again beeps no more.
  CHECK(feed(d, false, 1000, 1500).empty());
  CHECK_FALSE(d.armed());
  CHECK(feed(d, true, 1500, 2500).empty());
  // Gone for 1.2 s: re-armed; the next red beeps after its hold.
  CHECK(feed(d, false, 2500, 3700).empty());
  CHECK(d.armed());
  auto beeps = feed(d, true, 3700, 4500);
  REQUIRE(beeps.size() == 1);
  CHECK(beeps[0] == 4000);
}
