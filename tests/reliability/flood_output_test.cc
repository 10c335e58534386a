// NETNS, real processes: a flood of garbage and oversized datagrams on the channels the launcher and the
// prediction listen to. Both count every one, stay up (same pid), and print a bounded number of lines:
// warnings are rate-limited with counts, so a day of bad network cannot fill a disk or a journal.
#include <catch2/catch.hpp>

#include <signal.h>

#include <algorithm>
#include <filesystem>
#include <thread>

#include "bricklayer/common/channels.h"
#include "bricklayer/launcher/process.h"
#include "bricklayer/runtime/lcm_bus.h"
#include "harness/live_bus.h"
#include "harness/recorder.h"
#include "harness/scratch.h"

using namespace bricklayer;
using namespace std::chrono_literals;
namespace fs = std::filesystem;

namespace {
size_t count_lines(const std::string& text) { return static_cast<size_t>(std::count(text.begin(), text.end(), '\n')); }
}  // namespace

TEST_CASE("a 6 s flood of garbage: counted errors, no restart, and at most a few lines of output") {
  harness::ScratchDir dir("flood");
  harness::write_file(dir / "p.json", R"({"modules":[{"name":"prediction","command":["bricklayer-prediction"]}]})");
  launcher::SpawnOptions o;
  o.stdout_path = (dir / "out").string();
  o.merge_stderr = true;
  o.env = {"DISPLAY="};
  // One stdout for both streams, so every line it prints is counted in order.
  auto launcher = launcher::Process::spawn({harness::program_path("bricklayer-launch"), "--root", dir.str(), "--bin-dir",
                                            (harness::binary_dir() / "bin").string(), "--lcm-url", harness::kLiveUrl,
                                            (dir / "p.json").string()},
                                           o);
  runtime::LcmBus bus(harness::kLiveUrl);
  REQUIRE(bus.open());
  harness::Recorder rec = harness::Recorder::live(bus, {channel(kHeartbeatChannel)});
  const auto before = rec.wait_for_heartbeat("prediction", {}, 10s);
  REQUIRE(before);
  rec.pump_for(1500ms);  // the launcher's "all up" lines are out
  const size_t lines_before = count_lines(harness::read_file(dir / "out"));

  // Garbage (undecodable bytes) on the prediction's input and on the launcher's, 10,000 a second for
  // 6 s (the exhibit's flood was 6,000 lines a second), from a sender that listens to nothing.
  runtime::LcmBus sender(harness::kLiveUrl);
  std::vector<uint8_t> garbage(200);
  for (size_t i = 0; i < garbage.size(); ++i) garbage[i] = static_cast<uint8_t>(i * 37 + 11);
  int64_t sent = 0;
  const auto end = std::chrono::steady_clock::now() + 6s;
  while (std::chrono::steady_clock::now() < end) {
    for (int k = 0; k < 50; ++k) {
      garbage[0] = static_cast<uint8_t>(sent);
      harness::publish_bytes(sender, channel(kStackChannel), garbage);
      harness::publish_bytes(sender, channel(kHeartbeatChannel), garbage);
      sent += 2;
    }
    std::this_thread::sleep_for(10ms);
  }
  INFO(sent << " garbage messages sent");
  CHECK(sent > 20000);
  runtime::LcmBus after_bus(harness::kLiveUrl);  // a fresh socket: no backlog of the flood in it
  REQUIRE(after_bus.open());
  harness::Recorder after_rec = harness::Recorder::live(after_bus, {channel(kHeartbeatChannel)});
  REQUIRE(after_rec.wait_until(
      [&] { return after_rec.last_heartbeat("prediction") && after_rec.last_heartbeat("launcher"); }, 5s));
  const heartbeat_t after = *after_rec.last_heartbeat("prediction"), launcher_hb = *after_rec.last_heartbeat("launcher");
  CHECK(after.pid == before->pid);  // survived, not restarted
  CHECK(after.errors + after.dropped > 1000);
  CHECK(launcher_hb.errors + launcher_hb.dropped > 1000);

  launcher.signal(SIGTERM);
  REQUIRE(launcher.wait_for(15s));
  const std::string out = harness::read_file(dir / "out");
  INFO(out);
  const size_t flood_lines = count_lines(out) - lines_before;
  // Per kind of warning: the first at once, then one line per 10 s with the count; plus the stop's
  // summary (about 5 lines). Unlimited, it would be one line per message.
  CHECK(flood_lines < 25);
  CHECK(out.find("malformed messages on BL_STACK") != std::string::npos);
  CHECK(out.find("malformed messages on BL_HEARTBEAT") != std::string::npos);
}
