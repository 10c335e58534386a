#include <catch2/catch.hpp>

#include <string>
#include <vector>

#include "bricklayer/runtime/in_process_bus.h"

using namespace bricklayer::runtime;

namespace {
bool send(Bus& bus, const std::string& channel, const std::string& text) {
  return bus.publish(channel, reinterpret_cast<const uint8_t*>(text.data()), text.size());
}
}  // namespace

TEST_CASE("endpoints of one in-process bus hear each other and themselves, as on LCM") {
  InProcessBus hub;
  Bus& a = hub.endpoint("a");
  Bus& b = hub.endpoint("b");
  std::vector<std::string> at_a, at_b;
  a.subscribe("X", QueuePolicy::keep(10), [&](const Received& r) { at_a.emplace_back(r.data, r.data + r.size); });
  b.subscribe("X", QueuePolicy::keep(10), [&](const Received& r) { at_b.emplace_back(r.data, r.data + r.size); });
  REQUIRE(send(a, "X", "from a"));
  REQUIRE(send(b, "X", "from b"));
  CHECK(hub.pending());
  CHECK(a.handle(100) == 2);
  CHECK(at_a == std::vector<std::string>{"from a", "from b"});
  CHECK(at_b.empty());  // b has not handled yet: delivery happens in handle(), on the caller's thread
  CHECK(b.handle(0) == 2);
  CHECK(at_b == at_a);
  CHECK_FALSE(hub.pending());
}

TEST_CASE("the in-process clock moves only when the test moves it, never backwards") {
  InProcessBus hub(1000);
  Bus& a = hub.endpoint();
  CHECK(a.now_utime() == 1000);
  CHECK(a.handle(500) == 0);  // never blocks, never moves time
  CHECK(a.now_utime() == 1000);
  hub.advance(250);
  CHECK(a.now_utime() == 1250);
  hub.set_utime(2000);
  CHECK(a.now_utime() == 2000);
  CHECK_THROWS_AS(hub.set_utime(1999), std::invalid_argument);
  CHECK_THROWS_AS(hub.advance(-1), std::invalid_argument);
}

TEST_CASE("a message carries the time it was published, and the tap sees every publication") {
  InProcessBus hub(5000);
  Bus& a = hub.endpoint("a");
  std::vector<std::string> tapped;
  hub.set_tap([&](const std::string& from, const std::string& channel, const uint8_t*, size_t size, int64_t utime) {
    tapped.push_back(from + " " + channel + " " + std::to_string(size) + " " + std::to_string(utime));
  });
  int64_t arrival = -1;
  a.subscribe("X", QueuePolicy::newest(), [&](const Received& r) { arrival = r.utime; });
  send(a, "X", "abc");
  hub.advance(100);
  a.handle(0);
  CHECK(arrival == 5000);
  CHECK(tapped == std::vector<std::string>{"a X 3 5000"});
}

TEST_CASE("a bus that is down refuses publications and says so") {
  InProcessBus hub;
  Bus& a = hub.endpoint();
  hub.set_down(true);
  CHECK_FALSE(send(a, "X", "lost"));
  CHECK_FALSE(a.problem().empty());
  hub.set_down(false);
  CHECK(send(a, "X", "sent"));
  CHECK(a.problem().empty());
}

TEST_CASE("settle hands replies to replies on until the bus is quiet, and stops nodes that never are") {
  InProcessBus hub;
  Bus& ping = hub.endpoint("ping");
  Bus& pong = hub.endpoint("pong");
  // pong answers every PING with a PONG; ping answers the first three PONGs with another PING.
  int pongs = 0;
  pong.subscribe("PING", QueuePolicy::keep(10), [&](const Received&) { send(pong, "PONG", "o"); });
  ping.subscribe("PONG", QueuePolicy::keep(10), [&](const Received&) {
    if (++pongs < 3) send(ping, "PING", "i");
  });
  auto round = [&] {
    ping.handle(0);
    pong.handle(0);
  };
  CHECK(hub.settle(round) == 0);  // nothing pending: no round at all
  REQUIRE(send(ping, "PING", "i"));
  const int rounds = hub.settle(round);
  CHECK(pongs == 3);
  CHECK(rounds >= 3);
  CHECK_FALSE(hub.pending());

  // Two endpoints that answer each other for ever.
  Bus& echo = hub.endpoint("echo");
  echo.subscribe("LOOP", QueuePolicy::keep(10), [&](const Received&) { send(echo, "LOOP", "again"); });
  REQUIRE(send(echo, "LOOP", "start"));
  CHECK_THROWS_WITH(hub.settle([&] { round(); echo.handle(0); }, 50), Catch::Contains("more than 50 rounds"));
}
