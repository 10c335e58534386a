// LoggerNode on the in-process rig: what it writes, what it leaves out, what it counts.
#include <catch2/catch.hpp>

#include <chrono>
#include <filesystem>
#include <string>
#include <thread>
#include <vector>

#include "bricklayer/common/channels.h"
#include "bricklayer/image_t.hpp"
#include "bricklayer/logger/logger_node.h"
#include "bricklayer/runtime/log_file.h"
#include "harness/rig.h"
#include "harness/scratch.h"

using namespace bricklayer;
using namespace std::chrono_literals;

namespace {
// The writer is a thread of its own: step the rig until it has written n events (5 s of wall time at most).
bool written(harness::Rig& rig, logger::LoggerNode& node, int64_t n) {
  const auto until = std::chrono::steady_clock::now() + 5s;
  while (node.writer_stats().written < n) {
    if (std::chrono::steady_clock::now() > until) return false;
    rig.step();
    std::this_thread::sleep_for(1ms);
  }
  return true;
}

std::vector<runtime::LogEvent> read_log(const std::string& path) {
  runtime::LogReader reader(path);
  std::vector<runtime::LogEvent> out;
  runtime::LogEvent e;
  while (reader.next(e)) out.push_back(e);
  CHECK(reader.damage().empty());
  return out;
}

image_t frame(const std::string& source, int64_t number) {
  image_t im{};
  im.frame_number = number;
  im.source = source;
  im.data = {1, 2, 3};
  im.size = 3;
  return im;
}
}  // namespace

TEST_CASE("the logger writes every wanted message byte for byte, in order, at the bus time it arrived") {
  harness::ScratchDir dir("logger-node");
  harness::Rig rig(1000);
  logger::LoggerConfig config;
  config.file = (dir / "day").string();
  config.exclude = "BL_HEARTBEAT|BL_CONFIG|SECRET";
  config.flush_ms = 0;  // the test reads the file while the logger runs
  auto& node = rig.add<logger::LoggerNode>(config);
  std::vector<std::vector<uint8_t>> sent;
  for (int i = 0; i < 50; ++i) {
    sent.push_back(std::vector<uint8_t>(static_cast<size_t>(i + 1), static_cast<uint8_t>(i)));
    rig.publish_bytes(i % 2 ? "A" : "B", sent.back());
    rig.publish_bytes("SECRET", {9});
    rig.step();
  }
  REQUIRE(written(rig, node, 50));
  const auto events = read_log((dir / "day.00").string());
  REQUIRE(events.size() == 50);
  for (size_t i = 0; i < events.size(); ++i) {
    CHECK(events[i].channel == (i % 2 ? "A" : "B"));
    CHECK(events[i].data == sent[i]);
    CHECK(events[i].utime == runtime::InProcessBus::kDefaultStartUtime + static_cast<int64_t>(i) * 1000);
  }
  CHECK(harness::heartbeat_value(node.heartbeat(), "excluded").value_or(0) >= 50);
  CHECK(node.heartbeat().status == "ok");
}

TEST_CASE("the logger counts frames that never reached it, and starts a new file when asked") {
  harness::ScratchDir dir("logger-node");
  harness::Rig rig(1000);
  logger::LoggerConfig config;
  config.file = (dir / "run").string();
  config.channels = "BL_IMAGE";
  config.flush_ms = 0;
  auto& node = rig.add<logger::LoggerNode>(config);
  for (int64_t n : {0, 1, 2, 5, 6}) {  // 3 and 4 were lost before the logger
    rig.publish(channel(kImageChannel), frame("cam", n));
    rig.step();
  }
  REQUIRE(written(rig, node, 5));
  rig.step();
  CHECK(harness::heartbeat_value(node.heartbeat(), "sequence_gaps").value_or(-1) == 2);
  CHECK(node.heartbeat().status.rfind("LOSING", 0) == 0);
  node.request_new_file();
  const auto until = std::chrono::steady_clock::now() + 5s;
  while (node.writer_stats().files < 2 && std::chrono::steady_clock::now() < until) std::this_thread::sleep_for(1ms);
  REQUIRE(node.writer_stats().files == 2);
  rig.publish(channel(kImageChannel), frame("cam", 7));
  REQUIRE(written(rig, node, 6));
  CHECK(read_log((dir / "run.00").string()).size() == 5);
  CHECK(read_log((dir / "run.01").string()).size() == 1);
}

TEST_CASE("a log the logger cannot create is an error at start") {
  harness::Rig rig;
  logger::LoggerConfig config;
  config.file = "/proc/version/log";
  CHECK_THROWS_AS(rig.add<logger::LoggerNode>(config), std::runtime_error);
  config.file = "";
  CHECK_THROWS_AS(rig.add<logger::LoggerNode>(config), std::invalid_argument);
}
