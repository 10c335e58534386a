// NETNS, real processes: a run of bricklayer-prediction recorded by a real lcm-logger process
// - replays through bricklayer-replay --check with 0 mismatches,
// - fails bricklayer-replay --check once one recorded prediction is altered,
// - replays through lcm-logplayer into a fresh bricklayer-prediction with identical outputs.
#include <catch2/catch.hpp>

#include <lcm/lcm-cpp.hpp>

#include <filesystem>
#include <fstream>
#include <map>
#include <set>
#include <sstream>
#include <thread>

#include "bricklayer/launcher/process.h"
#include "bricklayer/prediction/sample_stacks.h"
#include "bricklayer/prediction_t.hpp"
#include "bricklayer/stack_t.hpp"
#include "../bus/bus_test_util.h"

using namespace bricklayer;
using namespace std::chrono_literals;
namespace fs = std::filesystem;

namespace {

constexpr int kStacks = 200;

struct TempDir {
  fs::path path;
  TempDir() {
    path = fs::temp_directory_path() / ("bricklayer-replay-run-" + std::to_string(::getpid()));
    fs::remove_all(path);
    fs::create_directories(path);
  }
  ~TempDir() {
    std::error_code ec;
    fs::remove_all(path, ec);
  }
};

std::string slurp(const fs::path& p) {
  std::ifstream in(p);
  std::stringstream s;
  s << in.rdbuf();
  return s.str();
}

launcher::SpawnOptions on_test_bus() {
  launcher::SpawnOptions o;
  o.env = {std::string("LCM_DEFAULT_URL=") + test::kTestUrl};
  return o;
}

launcher::Process start_prediction(test::Listener& bus) {
  auto proc = launcher::Process::spawn({test::bin("bricklayer-prediction"), "--log-level", "warn"}, on_test_bus());
  heartbeat_t hb{};
  REQUIRE(bus.pump_until([&] { return bus.last_heartbeat("prediction", hb) && hb.pid == proc.pid(); }, 10s));
  return proc;
}

// Runs bricklayer-replay; returns its exit code and stdout.
std::pair<int, std::string> run_replay(const TempDir& dir, const fs::path& log) {
  launcher::SpawnOptions o;
  o.stdout_path = (dir.path / "replay.out").string();
  auto p = launcher::Process::spawn({test::bin("bricklayer-replay"), log.string(), "--check"}, o);
  auto st = p.wait_for(60s);
  REQUIRE(st);
  return {st->signal ? 128 + st->signal : st->code, slurp(dir.path / "replay.out")};
}

// The frame numbers of every BL_STACK in a log.
std::set<int64_t> stack_frames_in(const fs::path& log) {
  std::set<int64_t> out;
  lcm::LogFile file(log.string(), "r");
  REQUIRE(file.good());
  while (const lcm::LogEvent* e = file.readNextEvent()) {
    if (e->channel != channel(kStackChannel)) continue;
    const auto* d = static_cast<const uint8_t*>(e->data);
    stack_t s{};
    if (test::decode(std::vector<uint8_t>(d, d + e->datalen), s)) out.insert(s.frame_number);
  }
  return out;
}

// Every BL_PREDICTION in a log, by frame number.
std::map<int64_t, std::vector<uint8_t>> predictions_in(const fs::path& log) {
  std::map<int64_t, std::vector<uint8_t>> out;
  lcm::LogFile file(log.string(), "r");
  REQUIRE(file.good());
  while (const lcm::LogEvent* e = file.readNextEvent()) {
    if (e->channel != channel(kPredictionChannel)) continue;
    const auto* d = static_cast<const uint8_t*>(e->data);
    std::vector<uint8_t> bytes(d, d + e->datalen);
    prediction_t p{};
    REQUIRE(test::decode(bytes, p));
    out[p.frame_number] = bytes;
  }
  return out;
}

}  // namespace

TEST_CASE("a run recorded by lcm-logger replays deterministically, in-process and live") {
  TempDir dir;
  const fs::path log = dir.path / "run.lcm";
  test::Listener bus;
  REQUIRE(bus.ok());
  bus.listen(channel(kPredictionChannel));
  bus.listen(channel(kHeartbeatChannel));

  // A real lcm-logger. It is recording once a probe message makes its file grow.
  auto logger = launcher::Process::spawn(
      {"/usr/bin/lcm-logger", std::string("--lcm-url=") + test::kTestUrl, "-q", "-f", "--flush-interval=20", log.string()});
  const char probe[] = "probe";
  REQUIRE(bus.pump_until(
      [&] {
        bus.lcm().publish("BL_TEST_PROBE", probe, sizeof(probe));
        std::error_code ec;
        return fs::exists(log) && fs::file_size(log, ec) > 0;
      },
      10s));

  auto prediction = start_prediction(bus);
  const size_t before = bus.count(channel(kPredictionChannel));
  for (int i = 1; i <= kStacks; ++i) {
    stack_t s = prediction::sample_stack(1 + (i * 11) % 40, static_cast<uint32_t>(1000 + i), 7'000'000 + i * 33'000, i);
    const auto sent_at = std::chrono::steady_clock::now();
    REQUIRE(bus.lcm().publish(channel(kStackChannel), &s) == 0);
    REQUIRE(bus.pump_until([&] { return bus.count(channel(kPredictionChannel)) == before + i; }, 3s));
    // A steady camera-like pace (one stack per 4 ms at most), which the log keeps for lcm-logplayer.
    bus.pump(std::chrono::duration_cast<std::chrono::milliseconds>(sent_at + 4ms - std::chrono::steady_clock::now()));
  }
  bus.pump(300ms);  // the logger flushes every 20 ms
  prediction.stop(3s);
  auto logger_exit = logger.stop(3s);
  CHECK(logger_exit.signal == 0);
  // lcm-logger 1.3.1 never raises its subscription queue above LCM's default of 30 messages, so on a
  // loaded machine it can lose part of a burst. Whatever it kept must replay exactly; count the rest.
  const auto recorded = predictions_in(log);
  const auto stack_frames = stack_frames_in(log);
  std::vector<int64_t> both;  // frames whose stack and prediction are both in the log
  for (const auto& [frame, bytes] : recorded)
    if (stack_frames.count(frame)) both.push_back(frame);
  UNSCOPED_INFO("lcm-logger kept " << stack_frames.size() << " of " << kStacks << " stacks and " << recorded.size()
                                   << " predictions");
  REQUIRE(both.size() >= static_cast<size_t>(kStacks / 2));
  const std::string compared = std::to_string(both.size()) + " compared, ";

  SECTION("bricklayer-replay --check: 0 mismatches") {
    auto [code, out] = run_replay(dir, log);
    INFO(out);
    CHECK(code == 0);
    CHECK(out.find(compared + "0 mismatches") != std::string::npos);
  }

  SECTION("bricklayer-replay --check fails on a log with one altered prediction") {
    const fs::path altered = dir.path / "altered.lcm";
    const int64_t victim = both[both.size() / 3];
    {
      lcm::LogFile in(log.string(), "r");
      lcm::LogFile out(altered.string(), "w");
      REQUIRE(out.good());
      while (const lcm::LogEvent* e = in.readNextEvent()) {
        lcm::LogEvent copy = *e;
        const auto* d = static_cast<const uint8_t*>(e->data);
        std::vector<uint8_t> bytes(d, d + e->datalen);
        prediction_t p{};
        if (e->channel == channel(kPredictionChannel) && test::decode(bytes, p) && p.frame_number == victim) {
          p.overhang += 1e-12;  // the smallest kind of drift a replay must catch
          bytes = test::encode(p);
        }
        copy.data = bytes.data();
        copy.datalen = static_cast<int32_t>(bytes.size());
        REQUIRE(out.writeEvent(&copy) == 0);
      }
    }
    auto [code, out] = run_replay(dir, altered);
    INFO(out);
    CHECK(code == 1);
    CHECK(out.find("MISMATCH BL_PREDICTION") != std::string::npos);
    CHECK(out.find("frame " + std::to_string(victim) + ": overhang") != std::string::npos);
    CHECK(out.find(compared + "1 mismatches") != std::string::npos);
  }

  SECTION("lcm-logplayer into a fresh bricklayer-prediction gives identical outputs") {
    bus.messages.clear();
    auto fresh = start_prediction(bus);
    bus.messages.clear();
    // Only the stacks are played: the fresh process produces the predictions, at the recorded pace;
    // should the process fall behind, newest wins and the drops are counted in its heartbeat.
    auto player = launcher::Process::spawn({"/usr/bin/lcm-logplayer", "-e", "^BL_STACK$", log.string()}, on_test_bus());
    while (player.running()) bus.pump(50ms);
    REQUIRE(player.exit_status()->clean());
    const auto played = static_cast<int64_t>(stack_frames.size());
    heartbeat_t hb{};
    REQUIRE(bus.pump_until(
        [&] {
          return bus.last_heartbeat("prediction", hb) && hb.pid == fresh.pid() && hb.received == played &&
                 hb.published + hb.dropped == played;
        },
        5s));
    bus.pump(100ms);
    int identical = 0, different = 0, unrecorded = 0;
    for (const auto& m : bus.on(channel(kPredictionChannel))) {
      prediction_t p{};
      REQUIRE(test::decode(m.bytes, p));
      auto it = recorded.find(p.frame_number);
      if (it == recorded.end()) {
        ++unrecorded;  // the logger lost this prediction: nothing to compare with
        continue;
      }
      (it->second == m.bytes ? identical : different)++;
    }
    INFO("identical " << identical << ", different " << different << ", not recorded " << unrecorded
                      << ", dropped by the process (newest wins) " << hb.dropped);
    CHECK(different == 0);
    CHECK(identical + unrecorded == hb.published);
    CHECK(identical + unrecorded + hb.dropped == played);
    CHECK(identical >= kStacks / 4);
    UNSCOPED_INFO("logplayer replay: " << identical << " identical, " << hb.dropped << " dropped");
  }
}
