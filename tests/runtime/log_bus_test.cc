#include <catch2/catch.hpp>

#include <string>
#include <vector>

#include "bricklayer/runtime/log_bus.h"
#include "harness/scratch.h"

using namespace bricklayer::runtime;
using bricklayer::harness::ScratchDir;

namespace {
std::string make_log(const ScratchDir& dir, const std::vector<std::tuple<int64_t, std::string, std::string>>& events) {
  const std::string path = (dir / "bus.lcmlog").string();
  LogWriter w(path);
  for (const auto& [utime, channel, data] : events)
    w.write(utime, channel, reinterpret_cast<const uint8_t*>(data.data()), data.size());
  return path;
}
}  // namespace

TEST_CASE("a log bus delivers its events one per handle, in order, on the recorded clock") {
  ScratchDir dir("logbus");
  const std::string path = make_log(dir, {{1000, "A", "1"}, {1500, "B", "skip"}, {3000, "A", "2"}, {3000, "A", "3"}});
  LogBus bus(path);
  CHECK(bus.now_utime() == 1000);  // the clock starts at the first event
  std::vector<std::string> got;
  std::vector<int64_t> times;
  bus.subscribe("A", QueuePolicy::newest(), [&](const Received& r) {
    got.emplace_back(r.data, r.data + r.size);
    times.push_back(r.utime);
  });
  CHECK(bus.handle(0) == 1);
  CHECK(bus.now_utime() == 1000);
  // The next event is 2 ms away: a 1 ms wait ends without it, and the clock moves by exactly 1 ms.
  CHECK(bus.handle(1) == 0);
  CHECK(bus.now_utime() == 2000);
  CHECK(bus.handle(5) == 1);
  CHECK(bus.now_utime() == 3000);
  CHECK(bus.handle(0) == 1);  // same time: nothing is dropped, every event is delivered
  CHECK(bus.handle(1000) == Bus::kEnded);
  CHECK(bus.ended());
  CHECK(got == std::vector<std::string>{"1", "2", "3"});
  CHECK(times == std::vector<int64_t>{1000, 3000, 3000});
  CHECK(bus.events_delivered() == 3);
}

TEST_CASE("what a node publishes on a log bus goes to the output, stamped with the log's clock, never back in") {
  ScratchDir dir("logbus");
  const std::string path = make_log(dir, {{1000, "IN", "x"}, {2000, "IN", "y"}});
  std::vector<std::string> outputs;
  LogBus bus(path, {}, [&](const std::string& channel, const uint8_t* data, size_t size, int64_t utime) {
    outputs.push_back(channel + "=" + std::string(data, data + size) + "@" + std::to_string(utime));
  });
  int inputs = 0;
  bus.subscribe("IN", QueuePolicy::keep(10), [&](const Received& r) {
    ++inputs;
    const std::string answer = "ans-" + std::string(r.data, r.data + r.size);
    bus.publish("IN", reinterpret_cast<const uint8_t*>(answer.data()), answer.size());
  });
  while (bus.handle(100) != Bus::kEnded) {
  }
  CHECK(inputs == 2);
  CHECK(outputs == std::vector<std::string>{"IN=ans-x@1000", "IN=ans-y@2000"});
}

TEST_CASE("a log bus plays a time range and leaves out excluded channels") {
  ScratchDir dir("logbus");
  const std::string path =
      make_log(dir, {{1000, "A", "1"}, {2000, "A", "2"}, {2500, "B", "b"}, {3000, "A", "3"}, {4000, "A", "4"}});
  LogBusOptions o;
  o.from_utime = 2000;
  o.to_utime = 3000;
  o.exclude = {"B"};
  LogBus bus(path, o);
  CHECK(bus.now_utime() == 2000);
  std::vector<std::string> got;
  auto record = [&](const Received& r) { got.push_back(r.channel + std::string(r.data, r.data + r.size)); };
  bus.subscribe("A", QueuePolicy::keep(10), record);
  bus.subscribe("B", QueuePolicy::keep(10), record);
  while (bus.handle(10) != Bus::kEnded) {
  }
  CHECK(got == std::vector<std::string>{"A2", "A3"});
}
