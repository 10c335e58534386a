#include <catch2/catch.hpp>

#include <string>
#include <vector>

#include "bricklayer/runtime/subscription_queues.h"

using namespace bricklayer::runtime;

namespace {
std::vector<uint8_t> bytes(const std::string& s) { return {s.begin(), s.end()}; }
void put(SubscriptionQueues& q, const std::string& channel, const std::string& text, int64_t utime = 0) {
  const auto b = bytes(text);
  q.enqueue(channel, b.data(), b.size(), utime);
}
}  // namespace

TEST_CASE("newest wins: a full queue drops its oldest message and counts it") {
  SubscriptionQueues q;
  std::vector<std::string> got;
  const SubscriptionStats& stats =
      q.add("A", QueuePolicy::newest(), [&](const Received& r) { got.emplace_back(r.data, r.data + r.size); });
  put(q, "A", "1");
  put(q, "A", "2");
  put(q, "A", "3");
  CHECK(q.dispatch() == 1);
  CHECK(got == std::vector<std::string>{"3"});
  CHECK(stats.dropped == 2);
  CHECK(stats.delivered == 1);
  CHECK(q.dispatch() == 0);
}

TEST_CASE("a bounded queue keeps the newest N, in order") {
  SubscriptionQueues q;
  std::vector<std::string> got;
  const SubscriptionStats& stats =
      q.add("A", QueuePolicy::keep(2), [&](const Received& r) { got.emplace_back(r.data, r.data + r.size); });
  for (const char* s : {"1", "2", "3", "4"}) put(q, "A", s);
  q.dispatch();
  CHECK(got == std::vector<std::string>{"3", "4"});
  CHECK(stats.dropped == 2);
  CHECK_THROWS_AS(q.add("B", QueuePolicy::keep(0), [](const Received&) {}), std::invalid_argument);
}

TEST_CASE("delivery follows arrival order across subscriptions, and every subscriber of a channel gets a copy") {
  SubscriptionQueues q;
  std::vector<std::string> got;
  auto record = [&](const std::string& who) {
    return [&got, who](const Received& r) { got.push_back(who + ":" + r.channel + "=" + std::string(r.data, r.data + r.size)); };
  };
  q.add("A", QueuePolicy::keep(10), record("x"));
  q.add("B", QueuePolicy::keep(10), record("y"));
  q.add("A", QueuePolicy::keep(10), record("z"));
  CHECK(q.wanted("A"));
  CHECK_FALSE(q.wanted("C"));
  put(q, "B", "1");
  put(q, "A", "2");
  put(q, "C", "nobody");
  put(q, "B", "3");
  CHECK(q.dispatch() == 4);
  CHECK(got == std::vector<std::string>{"y:B=1", "x:A=2", "z:A=2", "y:B=3"});
}

TEST_CASE("messages queued by a handler wait for the next dispatch") {
  SubscriptionQueues q;
  int calls = 0;
  q.add("A", QueuePolicy::keep(10), [&](const Received&) {
    ++calls;
    put(q, "A", "again");
  });
  put(q, "A", "first");
  CHECK(q.dispatch() == 1);
  CHECK(calls == 1);
  CHECK_FALSE(q.empty());
  CHECK(q.dispatch() == 1);
  CHECK(calls == 2);
}

TEST_CASE("a handler sees the arrival time the bus stamped") {
  SubscriptionQueues q;
  int64_t seen = -1;
  q.add("A", QueuePolicy::newest(), [&](const Received& r) { seen = r.utime; });
  put(q, "A", "x", 1234);
  q.dispatch();
  CHECK(seen == 1234);
}

TEST_CASE("a subscription's channel is a regular expression over the whole name, as in LCM") {
  SubscriptionQueues q;
  std::vector<std::string> all, bl, exact;
  q.add(".*", QueuePolicy::keep(10), [&](const Received& r) { all.push_back(r.channel); });
  q.add("BL_.*", QueuePolicy::keep(10), [&](const Received& r) { bl.push_back(r.channel); });
  q.add("BL_STACK", QueuePolicy::keep(10), [&](const Received& r) { exact.push_back(r.channel); });
  put(q, "BL_STACK", "s");
  put(q, "BL_IMAGE", "i");
  put(q, "XBL_STACK", "x");  // a whole-name match: "BL_.*" does not match inside a name
  CHECK(q.wanted("OTHER"));
  q.dispatch();
  CHECK(all == std::vector<std::string>{"BL_STACK", "BL_IMAGE", "XBL_STACK"});
  CHECK(bl == std::vector<std::string>{"BL_STACK", "BL_IMAGE"});
  CHECK(exact == std::vector<std::string>{"BL_STACK"});
  CHECK_THROWS_AS(q.add("BL_(", QueuePolicy::newest(), [](const Received&) {}), std::invalid_argument);
}
