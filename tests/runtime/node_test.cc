// The node runtime's shared behaviour, on the in-process rig: heartbeats on the bus clock, counted
// and rate-limited errors, queue drops, staleness, the recorded configuration, clean handler faults.
#include <catch2/catch.hpp>

#include <string>
#include <vector>

#include "bricklayer/common/channels.h"
#include "bricklayer/node_config_t.hpp"
#include "bricklayer/runtime/config.h"
#include "bricklayer/runtime/log_bus.h"
#include "bricklayer/runtime/node.h"
#include "bricklayer/stack_t.hpp"
#include "harness/rig.h"
#include "harness/scratch.h"

using namespace bricklayer;
using namespace bricklayer::runtime;
using namespace std::chrono_literals;

namespace {
struct EchoConfig {
  int max_blocks = 10;
  template <typename V>
  void visit(V& v) {
    v(param("max-blocks", max_blocks, "larger stacks are refused").range(1, 1000));
  }
};

// Answers every stack with a copy on BL_PREDICTION's channel name "ECHO"; refuses large ones.
class EchoNode final : public Node {
 public:
  EchoNode(const EchoConfig& config, Bus& bus) : Node("echo", bus), config_(config) {
    subscribe<stack_t>("IN", QueuePolicy::newest(), [this](const stack_t& s) {
      if (s.num_blocks > config_.max_blocks) throw std::runtime_error("too many blocks");
      last_ = s;
      publish("ECHO", s);
    });
    watch_input("IN", 5.0, "no stacks");
  }
  int ticks = 0;
  std::optional<stack_t> last_;

 protected:
  void tick() override { ++ticks; }
  void before_heartbeat() override { set_value("ticks", ticks); }

 private:
  EchoConfig config_;
};

stack_t stack_with(int frame, int blocks = 0) {
  stack_t s{};
  s.utime = frame * 1000;
  s.frame_number = frame;
  for (int i = 0; i < blocks; ++i) s.blocks.push_back(block_t{});
  s.num_blocks = blocks;
  return s;
}
}  // namespace

TEST_CASE("a node answers on the bus and counts what it received and published") {
  harness::Rig rig;
  auto& echo = rig.add<EchoNode>(EchoConfig{});
  auto& rec = rig.record({"ECHO", channel(kHeartbeatChannel)});
  rig.publish("IN", stack_with(7, 2));
  auto out = rec.wait_for<stack_t>("ECHO", [](const stack_t& s) { return s.frame_number == 7; }, 100ms);
  REQUIRE(out);
  CHECK(out->num_blocks == 2);
  CHECK(echo.counters().received == 1);
  CHECK(echo.counters().published == 1);
  CHECK(echo.counters().errors == 0);
}

TEST_CASE("heartbeats come once a second of the bus clock, with counters, values and uptime") {
  harness::Rig rig(10'000);
  rig.add<EchoNode>(EchoConfig{});
  auto& rec = rig.record({channel(kHeartbeatChannel)});
  const int64_t start = rig.now();
  rig.run_for(3'500ms);
  const auto beats = rec.all<heartbeat_t>(channel(kHeartbeatChannel));
  REQUIRE(beats.size() == 4);  // at the first step (10 ms), then at 1, 2 and 3 s
  CHECK(beats[0].utime - start == 10'000);
  for (size_t i = 0; i < beats.size(); ++i) {
    CHECK(beats[i].module == "echo");
    if (i > 0) CHECK(beats[i].utime - start == static_cast<int64_t>(i) * 1'000'000);
    CHECK(beats[i].uptime_us == beats[i].utime - start);
  }
  CHECK(harness::heartbeat_value(beats.back(), "ticks").value_or(0) > 100);
}

TEST_CASE("malformed, oversized and refused inputs are counted errors, the node keeps working") {
  harness::Rig rig;
  auto& echo = rig.add<EchoNode>(EchoConfig{});
  auto& rec = rig.record({"ECHO"});
  rig.publish_bytes("IN", {1, 2, 3});              // not a stack_t
  rig.publish("IN", stack_with(1, 50));            // the handler throws
  rig.publish_bytes("IN", std::vector<uint8_t>(17u << 20, 0));  // over the 16 MB default limit
  rig.step();
  rig.publish("IN", stack_with(2, 1));
  REQUIRE(rec.wait_for<stack_t>("ECHO", {}, 100ms));
  CHECK(echo.counters().received == 2);  // the 50-block stack decoded; its handler's failure is an error
  CHECK(echo.counters().errors == 3);
}

TEST_CASE("a flood of bad messages is counted in full but warned about in a few lines") {
  harness::Rig rig;
  auto& echo = rig.add<EchoNode>(EchoConfig{});
  for (int i = 0; i < 5000; ++i) {
    rig.publish_bytes("IN", {9, 9});
    rig.settle();
  }
  CHECK(echo.counters().errors == 5000);
  CHECK(echo.warnings().written() <= 2);
  CHECK(echo.warnings().suppressed() >= 4999);
}

TEST_CASE("newest wins: inputs that pile up between two handles are dropped and counted") {
  harness::Rig rig;
  auto& echo = rig.add<EchoNode>(EchoConfig{});
  auto& rec = rig.record({"ECHO", channel(kHeartbeatChannel)});
  for (int f = 0; f < 5; ++f) rig.publish("IN", stack_with(f));
  rig.settle();
  const auto out = rec.all<stack_t>("ECHO");
  REQUIRE(out.size() == 1);
  CHECK(out[0].frame_number == 4);
  rig.run_for(1'100ms);
  auto hb = rec.last_heartbeat("echo");
  REQUIRE(hb);
  CHECK(hb->dropped == 4);
  CHECK(echo.counters().received == 5);  // every one decoded; four were superseded
}

TEST_CASE("an input silent for longer than its watch turns the status into what is missing") {
  harness::Rig rig(10'000);
  auto& echo = rig.add<EchoNode>(EchoConfig{});
  auto& rec = rig.record({channel(kHeartbeatChannel)});
  rig.run_for(3s);
  CHECK(echo.status() == "ok");
  rig.run_for(4s);
  CHECK(echo.status() == "no stacks for 7 s");
  auto hb = rec.last_heartbeat("echo");
  REQUIRE(hb);
  CHECK(hb->status == "no stacks for 7 s");
  rig.publish("IN", stack_with(1));
  rig.step();
  CHECK(echo.status() == "ok");
}

TEST_CASE("a node whose bus refuses publications counts it and reports the bus's problem") {
  harness::Rig rig;
  auto& echo = rig.add<EchoNode>(EchoConfig{});
  rig.hub().set_down(true);
  rig.publish("IN", stack_with(1));  // the test's own publication is refused too: nothing arrives
  rig.step();
  CHECK(echo.counters().received == 0);
  CHECK(echo.status() == "in-process bus is down");
  rig.hub().set_down(false);
  rig.publish("IN", stack_with(2));
  rig.step();
  CHECK(echo.counters().received == 1);
  CHECK(echo.status() == "ok");
}

TEST_CASE("the configuration is recorded on BL_CONFIG at start and every 10 s") {
  harness::Rig rig(100'000);
  auto& echo = rig.add<EchoNode>(EchoConfig{});
  echo.set_config("bricklayer-echo", R"({"max-blocks":10})");
  auto& rec = rig.record({channel(kConfigChannel)});
  rig.run_for(20'500ms);
  const auto configs = rec.all<node_config_t>(channel(kConfigChannel));
  REQUIRE(configs.size() == 3);
  CHECK(configs[0].module == "echo");
  CHECK(configs[0].program == "bricklayer-echo");
  CHECK(configs[0].config_json == R"({"max-blocks":10})");
  CHECK(configs[2].utime - configs[1].utime == 10'000'000);  // every 10th heartbeat
}

TEST_CASE("a node on a recorded log runs to its end on the log's clock and publishes the same each time") {
  harness::ScratchDir dir("node-log");
  const std::string path = (dir / "in.lcmlog").string();
  {
    LogWriter w(path);
    for (int f = 0; f < 20; ++f) {
      const auto bytes = encode(stack_with(f, f % 3));
      w.write(1'000'000 + f * 100'000, "IN", bytes.data(), bytes.size());
    }
  }
  auto replay = [&] {
    std::vector<std::string> out;
    LogBus bus(path, {}, [&](const std::string& channel, const uint8_t* data, size_t size, int64_t utime) {
      out.push_back(channel + "@" + std::to_string(utime) + ":" + std::string(data, data + size));
    });
    EchoNode node(EchoConfig{}, bus);
    while (node.step(20)) {
    }
    CHECK(node.counters().received == 20);
    return out;
  };
  const auto first = replay();
  CHECK(first == replay());
  size_t echoes = 0;
  for (const auto& o : first) echoes += o.rfind("ECHO@", 0) == 0;
  CHECK(echoes == 20);
  // Heartbeats on the log's clock: the first at the first event, then every recorded second.
  std::vector<std::string> beats;
  for (const auto& o : first)
    if (o.rfind(channel(kHeartbeatChannel) + "@", 0) == 0) beats.push_back(o.substr(0, o.find(':')));
  REQUIRE(beats.size() >= 2);
  CHECK(beats[0] == channel(kHeartbeatChannel) + "@1000000");
  CHECK(beats[1] == channel(kHeartbeatChannel) + "@2000000");
}

namespace {
class TapNode final : public Node {
 public:
  explicit TapNode(Bus& bus) : Node("tap", bus) {
    subscribe_bytes("T_.*", QueuePolicy::keep(100), [this](const Received& r) { seen.push_back(r.channel + ":" + std::to_string(r.size)); }, 100);
  }
  std::vector<std::string> seen;
};
}  // namespace

TEST_CASE("a node can take every matching channel's bytes undecoded") {
  harness::Rig rig;
  auto& tap = rig.add<TapNode>();
  rig.publish_bytes("T_A", {1, 2, 3});
  rig.publish_bytes("OTHER", {1});
  rig.publish_bytes("T_B", std::vector<uint8_t>(200, 0));  // over its 100-byte limit
  rig.step();
  CHECK(tap.seen == std::vector<std::string>{"T_A:3"});
  CHECK(tap.counters().errors == 1);
}
