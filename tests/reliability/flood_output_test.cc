// NETNS, real processes: a flood of garbage and oversized datagrams on the channels the launcher and the
// prediction listen to. Both count every one, stay up (same pid), and print a bounded number of lines:
// warnings are rate-limited with counts, so a day of bad network cannot fill a disk or a journal.
#include <catch2/catch.hpp>

#include <signal.h>

#include <filesystem>
#include <fstream>
#include <sstream>
#include <thread>

#include "bricklayer/launcher/process.h"
#include "reliability_test_util.h"

using namespace bricklayer;
using namespace std::chrono_literals;
namespace fs = std::filesystem;

namespace {
size_t count_lines(const std::string& text) { return static_cast<size_t>(std::count(text.begin(), text.end(), '\n')); }
}  // namespace

TEST_CASE("a 6 s flood of garbage: counted errors, no restart, and at most a few lines of output") {
  const fs::path dir = fs::temp_directory_path() / ("bricklayer-flood-" + std::to_string(::getpid()));
  fs::remove_all(dir);
  fs::create_directories(dir);
  std::ofstream(dir / "p.json") << R"({"modules":[{"name":"prediction","command":["bricklayer-prediction"]}]})";
  launcher::SpawnOptions o;
  o.stdout_path = (dir / "out").string();
  o.merge_stderr = true;
  o.env = {"DISPLAY="};
  auto launcher = launcher::Process::spawn({test::bin("bricklayer-launch"), "--root", dir.string(), "--bin-dir",
                                            std::string(BRICKLAYER_BINARY_DIR) + "/bin", "--lcm-url", test::kTestUrl,
                                            (dir / "p.json").string()},
                                           o);
  test::Listener bus;
  REQUIRE(bus.ok());
  bus.listen(channel(kHeartbeatChannel));
  heartbeat_t before{};
  REQUIRE(bus.pump_until([&] { return bus.last_heartbeat("prediction", before); }, 10s));
  bus.pump(1500ms);  // the launcher's "all up" lines are out
  const size_t lines_before = count_lines(test::slurp((dir / "out").string()));

  // Garbage (undecodable bytes) on the prediction's input and on the launcher's, 10,000 a second for
  // 6 s (the exhibit's flood was 6,000 lines a second), from a sender that listens to nothing.
  test::Listener sender;
  std::vector<uint8_t> garbage(200);
  for (size_t i = 0; i < garbage.size(); ++i) garbage[i] = static_cast<uint8_t>(i * 37 + 11);
  int64_t sent = 0;
  const auto end = std::chrono::steady_clock::now() + 6s;
  while (std::chrono::steady_clock::now() < end) {
    for (int k = 0; k < 50; ++k) {
      garbage[0] = static_cast<uint8_t>(sent);
      sender.lcm().publish(channel(kStackChannel), garbage.data(), static_cast<unsigned>(garbage.size()));
      sender.lcm().publish(channel(kHeartbeatChannel), garbage.data(), static_cast<unsigned>(garbage.size()));
      sent += 2;
    }
    std::this_thread::sleep_for(10ms);
  }
  INFO(sent << " garbage messages sent");
  CHECK(sent > 20000);
  test::Listener after_bus;  // a fresh socket: no backlog of the flood in it
  REQUIRE(after_bus.ok());
  after_bus.listen(channel(kHeartbeatChannel));
  heartbeat_t after{}, launcher_hb{};
  REQUIRE(after_bus.pump_until([&] { return after_bus.last_heartbeat("prediction", after) && after_bus.last_heartbeat("launcher", launcher_hb); }, 5s));
  CHECK(after.pid == before.pid);  // survived, not restarted
  CHECK(after.errors + after.dropped > 1000);
  CHECK(launcher_hb.errors + launcher_hb.dropped > 1000);

  launcher.signal(SIGTERM);
  REQUIRE(launcher.wait_for(15s));
  const std::string out = test::slurp((dir / "out").string());
  INFO(out);
  const size_t flood_lines = count_lines(out) - lines_before;
  // Per kind of warning: the first at once, then one line per 10 s with the count; plus the stop's
  // summary (about 5 lines). Unlimited, it would be one line per message.
  CHECK(flood_lines < 25);
  CHECK(out.find("malformed messages on BL_STACK") != std::string::npos);
  CHECK(out.find("malformed messages on BL_HEARTBEAT") != std::string::npos);
  fs::remove_all(dir);
}
