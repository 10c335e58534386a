#include <catch2/catch.hpp>

#include "bricklayer/runtime/rate_limited_log.h"

using namespace bricklayer::runtime;

TEST_CASE("a flood of one kind of warning costs one line per window, with the count") {
  RateLimitedLog log(10'000'000);
  int64_t t = 1'000'000;
  for (int i = 0; i < 93382; ++i, t += 100) log.warn("malformed messages on BL_STACK", "bad message " + std::to_string(i), t);
  // 9.3 s of flood: the first line only, the rest counted.
  CHECK(log.written() == 1);
  CHECK(log.suppressed() == 93381);
  log.flush(t + 10'000'000);
  CHECK(log.written() == 2);  // the summary
  // After the window the next occurrence is written at once again.
  log.warn("malformed messages on BL_STACK", "one more", t + 20'000'000);
  CHECK(log.written() == 3);
}

TEST_CASE("kinds are limited separately") {
  RateLimitedLog log(10'000'000);
  log.warn("a", "first a", 0);
  log.warn("b", "first b", 1);
  log.warn("a", "second a", 2);
  CHECK(log.written() == 2);
  CHECK(log.suppressed() == 1);
}

TEST_CASE("thousands separators") {
  CHECK(with_thousands(0) == "0");
  CHECK(with_thousands(999) == "999");
  CHECK(with_thousands(1234) == "1,234");
  CHECK(with_thousands(1234567) == "1,234,567");
  CHECK(with_thousands(-1000) == "-1,000");
}
