// Runs inside a private network namespace (NETNS): real LCM udpm multicast on loopback.
#include "bricklayer/common/module.h"

#include <catch2/catch.hpp>

#include "bricklayer/common/channels.h"
#include "bricklayer/heartbeat_t.hpp"
#include "bricklayer/stack_t.hpp"

using namespace bricklayer;

namespace {
constexpr const char* kUrl = "udpm://239.255.76.67:7667?ttl=0";
void pump(Module& m, int rounds = 20) {
  for (int i = 0; i < rounds; ++i) m.lcm().handleTimeout(20);
}
}  // namespace

TEST_CASE("a module receives its own typed messages and counts them") {
  Module m("test", kUrl);
  int seen = 0;
  m.subscribe<stack_t>("T_STACK", [&](const stack_t& s) { seen += static_cast<int>(s.frame_number); });
  stack_t s{};
  s.frame_number = 7;
  REQUIRE(m.publish("T_STACK", s));
  pump(m);
  CHECK(seen == 7);
  CHECK(m.counters().received == 1);
  CHECK(m.counters().published == 1);
  CHECK(m.counters().errors == 0);
}

TEST_CASE("malformed, wrong-type and oversized messages are counted errors, not crashes") {
  Module m("test", kUrl);
  int seen = 0;
  m.subscribe<stack_t>("T_STACK", [&](const stack_t&) { ++seen; }, /*max_bytes=*/4096);
  const char garbage[] = "definitely not a stack";
  m.lcm().publish("T_STACK", garbage, sizeof(garbage));
  heartbeat_t hb{};  // another type: fingerprint mismatch
  m.lcm().publish("T_STACK", &hb);
  std::vector<uint8_t> big(8192, 0);
  m.lcm().publish("T_STACK", big.data(), static_cast<unsigned>(big.size()));
  pump(m);
  CHECK(seen == 0);
  CHECK(m.counters().errors == 3);
  CHECK(m.counters().received == 0);
}

TEST_CASE("a throwing handler is contained and counted") {
  Module m("test", kUrl);
  m.subscribe<stack_t>("T_STACK", [&](const stack_t&) { throw std::runtime_error("boom"); });
  stack_t s{};
  m.publish("T_STACK", s);
  pump(m);
  CHECK(m.counters().errors == 1);
}

TEST_CASE("the heartbeat carries counters and module values") {
  Module m("beater", kUrl);
  heartbeat_t got{};
  int beats = 0;
  m.subscribe<heartbeat_t>(channel(kHeartbeatChannel), [&](const heartbeat_t& hb) {
    got = hb;
    ++beats;
  });
  m.counters().dropped = 3;
  m.set_value("drift_px", 0.25);
  m.publish_heartbeat();
  pump(m);
  REQUIRE(beats == 1);
  CHECK(got.module == "beater");
  CHECK(got.dropped == 3);
  REQUIRE(got.num_values == 1);
  CHECK(got.value_names[0] == "drift_px");
  CHECK(got.values[0] == 0.25);
}
