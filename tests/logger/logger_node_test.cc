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
#include "bricklayer/logger/recording_index.h"
#include "bricklayer/prediction_t.hpp"
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

TEST_CASE("a day's policy: frames thinned, full rate around a red block, the moment and seek points in the index") {
  harness::ScratchDir dir("logger-node-policy");
  harness::Rig rig(1000);
  logger::LoggerConfig config;
  config.file = (dir / "day").string();
  config.frame_rate = 1;
  config.full_rate_before_s = 2;
  config.full_rate_after_s = 3;
  config.exclude = "BL_HEARTBEAT|BL_CONFIG";  // so the written count is frames and predictions only
  config.flush_ms = 0;
  auto& node = rig.add<logger::LoggerNode>(config);
  const int64_t start = rig.now();
  int64_t red_at = 0;
  std::vector<int64_t> sent;
  for (int f = 0; f < 30 * 20; ++f) {  // 20 s of frames at about 30 a second, a prediction each
    sent.push_back(rig.now());
    rig.publish(channel(kImageChannel), frame("cam", f));
    prediction_t p{};
    p.frame_number = f;
    p.status = prediction_t::STATUS_OK;
    p.num_blocks = 2;
    p.blocks.resize(2);
    if (f >= 300 && f < 330) p.blocks[1].state = block_prediction_t::STATE_CAUSE;  // red from 10 s to 11 s
    if (f == 300) red_at = rig.now();
    rig.publish(channel(kPredictionChannel), p);
    rig.run_for(std::chrono::microseconds(33'333));
  }
  rig.run_for(3s);  // past the delay line
  const int64_t frames_in = 600, predictions = 600;
  CHECK(node.policy().frames_kept() + node.policy().frames_thinned() == frames_in);
  REQUIRE(written(rig, node, predictions + node.policy().frames_kept()));
  // Frames the policy left out were received: they are not losses (an exhibit recording all day thins
  // most frames and must not read LOSING for it).
  rig.run_for(1s);
  CHECK(harness::heartbeat_value(node.heartbeat(), "sequence_gaps").value_or(-1) == 0);
  CHECK(harness::heartbeat_value(node.heartbeat(), "frames_thinned").value_or(0) >= 400);
  CHECK(node.heartbeat().status.rfind("LOSING", 0) != 0);
  std::vector<int64_t> frame_times;
  int64_t prediction_events = 0;
  for (const auto& e : read_log((dir / "day.00").string())) {
    if (e.channel == channel(kImageChannel)) frame_times.push_back(e.utime);
    if (e.channel == channel(kPredictionChannel)) ++prediction_events;
  }
  CHECK(prediction_events == predictions);  // every other channel whole
  int in_window = 0, outside = 0;
  for (int64_t t : frame_times) (t >= red_at - 2'000'000 && t <= red_at + 3'000'000 ? in_window : outside)++;
  int sent_in_window = 0;
  for (int64_t t : sent) sent_in_window += t >= red_at - 2'000'000 && t <= red_at + 3'000'000;
  CHECK(sent_in_window >= 140);
  CHECK(in_window == sent_in_window);  // every frame of the 5 s around the red block
  CHECK(outside >= 14);     // about one a second for the other 15 s
  CHECK(outside <= 17);
  const auto index = logger::RecordingIndex::load((dir / "day.index").string());
  REQUIRE(index.moments().size() == 1);
  CHECK(index.moments()[0].kind == "red");
  CHECK(index.moments()[0].utime == red_at);
  CHECK(index.seek_points().size() >= 19);  // about one a second
  const auto seek = index.seek(start + 12'000'000);
  REQUIRE(seek);
  runtime::LogReader reader(seek->part);
  reader.seek(seek->offset);
  runtime::LogEvent e;
  REQUIRE(reader.next(e));
  CHECK(e.utime <= start + 12'000'000);
  CHECK(e.utime > start + 10'900'000);
}

TEST_CASE("the hourly allowance: a red window the allowance cannot pay for falls back to the reduced rate, counted") {
  harness::ScratchDir dir("logger-node-allowance");
  harness::Rig rig(1000);
  logger::LoggerConfig config;
  config.file = (dir / "day").string();
  config.frame_rate = 1;
  config.full_rate_before_s = 2;
  config.full_rate_after_s = 3;
  config.max_mb_per_hour = 0.01;  // 10 kB: less than the reduced rate and the predictions already cost
  config.exclude = "BL_HEARTBEAT|BL_CONFIG";
  config.flush_ms = 0;
  auto& node = rig.add<logger::LoggerNode>(config);
  for (int f = 0; f < 30 * 12; ++f) {
    rig.publish(channel(kImageChannel), frame("cam", f));
    prediction_t p{};
    p.frame_number = f;
    p.status = prediction_t::STATUS_OK;
    p.num_blocks = 2;
    p.blocks.resize(2);
    if (f >= 240 && f < 270) p.blocks[1].state = block_prediction_t::STATE_CAUSE;  // red at 8 s
    rig.publish(channel(kPredictionChannel), p);
    rig.run_for(std::chrono::microseconds(33'333));
  }
  rig.run_for(3s);
  REQUIRE(written(rig, node, 360 + node.policy().frames_kept()));
  // Without the allowance the 5 s window would keep about 150 frames; here the reduced rate only.
  CHECK(node.policy().frames_kept() <= 14);
  CHECK(node.policy().window_frames_refused() >= 140);
  rig.run_for(1s);
  CHECK(harness::heartbeat_value(node.heartbeat(), "window_frames_refused").value_or(0) >= 140);
  // Every prediction is still there.
  int predictions = 0;
  for (const auto& e : read_log((dir / "day.00").string())) predictions += e.channel == channel(kPredictionChannel);
  CHECK(predictions == 360);
}
