// --from / --to: seconds into the log, a time of day, a date and time, a utime.
#include <catch2/catch.hpp>

#include <cstdlib>
#include <ctime>

#include "bricklayer/replay/time_arg.h"

using bricklayer::replay::parse_time_arg;

TEST_CASE("times for --from and --to") {
  ::setenv("TZ", "UTC", 1);
  ::tzset();
  const int64_t start = 1764599525'250000;  // 2025-12-01 14:32:05.25 UTC
  CHECK(parse_time_arg("90", start) == start + 90'000'000);
  CHECK(parse_time_arg("+1.5s", start) == start + 1'500'000);
  CHECK(parse_time_arg("14:33", start) == 1764599580'000000);
  CHECK(parse_time_arg("14:32:07.5", start) == 1764599527'500000);
  CHECK(parse_time_arg("2025-12-02 00:00:00", start) == 1764633600'000000);
  CHECK(parse_time_arg("2025-12-02T00:00", start) == 1764633600'000000);
  CHECK(parse_time_arg("1764599530000000", start) == 1764599530'000000);
  CHECK_THROWS_WITH(parse_time_arg("soon", start), Catch::Contains("is not a time"));
  CHECK_THROWS_WITH(parse_time_arg("25:00", start), Catch::Contains("not a time of day"));
}
