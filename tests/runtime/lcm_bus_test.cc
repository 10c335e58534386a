// The live bus on real LCM udpm sockets, inside this test's private network namespace (the test may
// change the namespace's routes and links: nothing outside it is touched).
#include <catch2/catch.hpp>

#include <cstdlib>
#include <string>
#include <thread>
#include <vector>

#include "bricklayer/runtime/lcm_bus.h"

using namespace bricklayer::runtime;
using namespace std::chrono_literals;

namespace {
constexpr const char* kUrl = "udpm://239.255.76.67:7667?ttl=0";

bool send(Bus& bus, const std::string& channel, const std::string& text) {
  return bus.publish(channel, reinterpret_cast<const uint8_t*>(text.data()), text.size());
}

// Handles until pred() or timeout (wall time).
template <typename Pred>
bool handle_until(Bus& bus, Pred pred, std::chrono::milliseconds timeout) {
  const auto until = std::chrono::steady_clock::now() + timeout;
  while (!pred()) {
    if (std::chrono::steady_clock::now() > until) return false;
    bus.handle(10);
  }
  return true;
}

int sh(const std::string& command) { return std::system(command.c_str()); }
}  // namespace

TEST_CASE("two live buses hear each other and themselves") {
  LcmBus a(kUrl), b(kUrl);
  REQUIRE(a.open());
  REQUIRE(b.problem().empty());
  std::vector<std::string> at_a, at_b;
  a.subscribe("T", QueuePolicy::keep(10), [&](const Received& r) { at_a.emplace_back(r.data, r.data + r.size); });
  b.subscribe("T", QueuePolicy::keep(10), [&](const Received& r) { at_b.emplace_back(r.data, r.data + r.size); });
  REQUIRE(send(a, "T", "hello"));
  CHECK(handle_until(b, [&] { return !at_b.empty(); }, 2s));
  CHECK(handle_until(a, [&] { return !at_a.empty(); }, 2s));
  CHECK(at_b == std::vector<std::string>{"hello"});
  CHECK(at_a == std::vector<std::string>{"hello"});
}

TEST_CASE("a pattern subscription on the live bus sees each matching channel once, under its own name") {
  LcmBus a(kUrl), b(kUrl);
  std::vector<std::string> all, stacks;
  b.subscribe(".*", QueuePolicy::keep(100), [&](const Received& r) { all.push_back(r.channel); });
  b.subscribe("S", QueuePolicy::keep(100), [&](const Received& r) { stacks.push_back(r.channel); });
  REQUIRE(send(a, "S", "1"));
  REQUIRE(send(a, "T", "2"));
  CHECK(handle_until(b, [&] { return all.size() >= 2; }, 2s));
  b.handle(50);
  CHECK(all == std::vector<std::string>{"S", "T"});
  CHECK(stacks == std::vector<std::string>{"S"});
}

TEST_CASE("newest wins on the live bus: a backlog is drained and all but the newest dropped, counted") {
  LcmBus a(kUrl), b(kUrl);
  std::vector<std::string> got;
  const SubscriptionStats& stats =
      b.subscribe("T", QueuePolicy::newest(), [&](const Received& r) { got.emplace_back(r.data, r.data + r.size); });
  for (int i = 0; i < 50; ++i) REQUIRE(send(a, "T", std::to_string(i)));
  std::this_thread::sleep_for(300ms);  // let LCM's receive thread take them all
  CHECK(b.handle(0) == 1);
  CHECK(got == std::vector<std::string>{"49"});
  CHECK(stats.dropped == 49);
}

TEST_CASE("without a multicast route the bus waits and says why, and opens once the route is back") {
  REQUIRE(sh("ip route del 224.0.0.0/4 dev lo") == 0);
  LcmBus bus(kUrl, LcmBusOptions{"", 3.0, 0.2});
  CHECK_FALSE(bus.open());
  CHECK(bus.problem().find("cannot open the LCM bus") != std::string::npos);
  CHECK_FALSE(send(bus, "T", "lost"));
  CHECK(bus.handle(50) == 0);  // waits, never throws
  std::vector<std::string> got;
  bus.subscribe("T", QueuePolicy::keep(10), [&](const Received& r) { got.emplace_back(r.data, r.data + r.size); });
  REQUIRE(sh("ip route add 224.0.0.0/4 dev lo") == 0);
  CHECK(handle_until(bus, [&] { return bus.open(); }, 3s));
  CHECK(bus.problem().empty());
  LcmBus peer(kUrl);
  REQUIRE(handle_until(bus, [&] { send(peer, "T", "back"); return !got.empty(); }, 3s));
  CHECK(got.front() == "back");
}

TEST_CASE("an interface that goes down and up: sends fail meanwhile, and the bus works again once the route is") {
  LcmBus bus(kUrl, LcmBusOptions{"HB", 0.5, 0.2});
  std::vector<std::string> got;
  bus.subscribe("HB", QueuePolicy::keep(100), [&](const Received& r) { got.emplace_back(r.data, r.data + r.size); });
  REQUIRE(send(bus, "HB", "before"));
  REQUIRE(handle_until(bus, [&] { return !got.empty(); }, 2s));
  // Link down removes every route through lo, the multicast route included; up does not restore it.
  REQUIRE(sh("ip link set lo down && ip link set lo up") == 0);
  CHECK(sh("ip route show 224.0.0.0/4 | grep -q lo") != 0);
  const bool refused = !send(bus, "HB", "during");
  CHECK(refused);
  CHECK_FALSE(bus.problem().empty());
  for (int i = 0; i < 5; ++i) bus.handle(100);  // never throws while the route is gone
  REQUIRE(sh("ip route add 224.0.0.0/4 dev lo") == 0);
  got.clear();
  // Heartbeat-like traffic until this process hears itself again.
  CHECK(handle_until(bus, [&] { send(bus, "HB", "after"); return !got.empty(); }, 5s));
  CHECK(bus.problem().empty());
}

TEST_CASE("a bus that publishes its loopback channel but subscribes to nothing hears itself and is never reopened") {
  // A camera publishes frames and its heartbeat and listens to nothing: LCM delivers only subscribed
  // channels, so the bus must listen to its loopback channel itself, or it would reopen every silence_s.
  LcmBus bus(kUrl, LcmBusOptions{"HB", 0.5, 0.2});
  REQUIRE(bus.open());
  const auto until = std::chrono::steady_clock::now() + 2s;
  while (std::chrono::steady_clock::now() < until) {
    REQUIRE(send(bus, "HB", "beat"));
    bus.handle(100);
  }
  CHECK(bus.reopens() == 0);
  CHECK(bus.problem().empty());
}
