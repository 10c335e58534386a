#include "bricklayer/common/lcm_url.h"

#include <cstdlib>

#include <catch2/catch.hpp>

using namespace bricklayer;

TEST_CASE("the LCM URL comes from the flag, else the environment, else host-only") {
  unsetenv("LCM_DEFAULT_URL");
  CHECK(resolve_lcm_url("") == kDefaultLcmUrl);
  CHECK(std::string(kDefaultLcmUrl).find("ttl=0") != std::string::npos);
  setenv("LCM_DEFAULT_URL", "udpm://239.255.76.67:7700?ttl=1", 1);
  CHECK(resolve_lcm_url("") == "udpm://239.255.76.67:7700?ttl=1");
  CHECK(resolve_lcm_url("memq://") == "memq://");
  unsetenv("LCM_DEFAULT_URL");
}

TEST_CASE("LCM URLs that would leave the LAN or cannot work are rejected") {
  CHECK_NOTHROW(check_lcm_url(kDefaultLcmUrl));
  CHECK_NOTHROW(check_lcm_url("udpm://239.255.76.67:7667?ttl=1"));
  CHECK_THROWS_WITH(check_lcm_url("udpm://239.255.76.67:7667?ttl=5"), Catch::Contains("beyond the local network"));
  CHECK_NOTHROW(check_lcm_url("udpm://239.255.76.67:7667?ttl=5", true));
  CHECK_THROWS_WITH(check_lcm_url("239.255.76.67"), Catch::Contains("no provider"));
  CHECK_THROWS_WITH(check_lcm_url("http://x"), Catch::Contains("unknown provider"));
}
