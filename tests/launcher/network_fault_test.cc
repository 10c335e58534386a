// NETNS (root in a private network namespace): the loopback interface taken down and brought up again,
// which drops the multicast route, as a switch power cycle does on an exhibit's LAN. The launcher
// (--multicast-route lo) puts the route back; the modules wait out the outage on their buses and
// resume publishing with the same pid: nothing is killed as hung, nothing crash-loops.
#include <signal.h>

#include <catch2/catch.hpp>

#include <opencv2/imgcodecs.hpp>

#include <cstdlib>
#include <map>
#include <optional>
#include <thread>

#include "bricklayer/common/channels.h"
#include "bricklayer/heartbeat_t.hpp"
#include "bricklayer/host_state_t.hpp"
#include "bricklayer/image_t.hpp"
#include "bricklayer/launcher/supervisor.h"
#include "bricklayer/prediction/sample_stacks.h"
#include "bricklayer/prediction_t.hpp"
#include "bricklayer/runtime/lcm_bus.h"
#include "bricklayer/stack_t.hpp"
#include "harness/recorder.h"
#include "launcher_test_util.h"

using namespace bricklayer;
using namespace std::chrono_literals;

namespace {
int sh(const std::string& command) { return std::system(command.c_str()); }
}  // namespace

TEST_CASE("an interface down for 7 s and up again: the launcher puts the route back, modules resume, same pids") {
  test::TempDir dir("ifdown");
  std::filesystem::create_directories(dir.path / "frames");
  for (int k = 0; k < 3; ++k)
    cv::imwrite((dir.path / "frames" / ("f" + std::to_string(k) + ".png")).string(),
                cv::Mat(60, 80, CV_8UC3, cv::Scalar::all(40 * k)));
  auto profile = dir.write("p.json", R"({"modules":[
      {"name":"prediction","command":["bricklayer-prediction","--log-level","warn"]},
      {"name":"camera","command":["bricklayer-camera","--images","frames","--loop","--fps","10"]}]})");
  auto launcher = test::launch(dir, profile, {"--multicast-route", "lo"});
  pid_t prediction = 0, camera = 0;
  {
    runtime::LcmBus bus(harness::kLiveUrl);
    REQUIRE(bus.open());
    harness::Recorder rec = harness::Recorder::live(bus, {channel(kHeartbeatChannel)});
    REQUIRE(rec.wait_until([&] { return rec.last_heartbeat("prediction") && rec.last_heartbeat("camera"); }, 15s));
    prediction = rec.last_heartbeat("prediction")->pid;
    camera = rec.last_heartbeat("camera")->pid;
  }
  REQUIRE(sh("ip link set lo down") == 0);
  // Longer than the 5 s heartbeat timeout: a launcher that judged silence on a deaf bus would kill both.
  std::this_thread::sleep_for(7s);
  REQUIRE(sh("ip link set lo up") == 0);
  REQUIRE(sh("ip route show 224.0.0.0/4 | grep -q lo") != 0);  // the route is gone with the link

  // Within a few seconds: the route is back (the launcher), and both modules publish again.
  const auto up_at = std::chrono::steady_clock::now();
  bool route_back = false;
  for (int i = 0; i < 100 && !route_back; ++i) {
    route_back = sh("ip route show 224.0.0.0/4 | grep -q lo") == 0;
    if (!route_back) std::this_thread::sleep_for(100ms);
  }
  REQUIRE(route_back);
  runtime::LcmBus bus(harness::kLiveUrl);  // a new socket: the old one's membership went with the link
  REQUIRE(bus.open());
  harness::Recorder rec = harness::Recorder::live(
      bus, {channel(kHeartbeatChannel), channel(kPredictionChannel), channel(kImageChannel), channel(launcher::kHostStateChannel)});
  int64_t frame = 1000;
  bool predicted = rec.wait_until([&] {
    ++frame;
    bricklayer::stack_t s = prediction::sample_stack(5, static_cast<uint32_t>(frame), frame, frame);
    harness::publish(bus, channel(kStackChannel), s);
    return rec.count(channel(kPredictionChannel)) > 0 && rec.count(channel(kImageChannel)) > 3;
  }, 15s);
  const double resumed_s = std::chrono::duration<double>(std::chrono::steady_clock::now() - up_at).count();
  INFO(dir.read("launch.out") << dir.read("launch.err"));
  REQUIRE(predicted);
  INFO("publishing again " << resumed_s << " s after the interface came back");
  REQUIRE(rec.wait_until([&] { return rec.last_heartbeat("prediction") && rec.last_heartbeat("camera"); }, 3s));
  const heartbeat_t p = *rec.last_heartbeat("prediction"), c = *rec.last_heartbeat("camera");
  CHECK(p.pid == prediction);  // never killed, never restarted
  CHECK(c.pid == camera);
  CHECK(p.restarts == 0);
  REQUIRE(rec.wait_until([&] { return rec.newest<host_state_t>(channel(launcher::kHostStateChannel)).has_value(); }, 3s));
  const host_state_t hs = *rec.newest<host_state_t>(channel(launcher::kHostStateChannel));
  REQUIRE(hs.num_modules == 2);
  CHECK(hs.modules[0].restarts == 0);
  CHECK(hs.modules[1].restarts == 0);
  CHECK(hs.status == "ok");
  launcher.signal(SIGTERM);
  REQUIRE(launcher.wait_for(15s));
  const std::string out = dir.read("launch.out");
  CHECK(out.find("the launcher hears nothing on the bus") != std::string::npos);
  CHECK(out.find("put the multicast route back: ip route replace 224.0.0.0/4 dev lo") != std::string::npos);
  CHECK(out.find("silent for") == std::string::npos);
  CHECK(out.find("died") == std::string::npos);
}

TEST_CASE("the whole demo through an interface down 7 s and up: every module resumes with its pid, 0 restarts") {
  test::TempDir dir("ifdown-demo");
  // The demo's scenarios from the source tree; its logs and snapshots in the scratch root.
  std::filesystem::create_symlink(std::string(BRICKLAYER_SOURCE_DIR) + "/launch", dir.path / "launch");
  auto launcher = test::launch(dir, dir.path / "launch" / "profiles" / "demo.json", {"--multicast-route", "lo", "--duration", "120"});
  std::map<std::string, int32_t> pids;
  {
    runtime::LcmBus bus(harness::kLiveUrl);
    REQUIRE(bus.open());
    harness::Recorder rec = harness::Recorder::live(bus, {channel(launcher::kHostStateChannel)});
    std::optional<host_state_t> hs;
    REQUIRE(rec.wait_until([&] {
      hs = rec.newest<host_state_t>(channel(launcher::kHostStateChannel));
      return hs && hs->num_modules == 5 && hs->modules_up == 5;
    }, 30s));
    for (const auto& m : hs->modules) pids[m.name] = m.pid;
  }
  REQUIRE(sh("ip link set lo down") == 0);
  std::this_thread::sleep_for(7s);
  REQUIRE(sh("ip link set lo up") == 0);
  bool route_back = false;  // put back by the launcher
  for (int i = 0; i < 100 && !route_back; ++i) {
    route_back = sh("ip route show 224.0.0.0/4 | grep -q lo") == 0;
    if (!route_back) std::this_thread::sleep_for(100ms);
  }
  REQUIRE(route_back);

  runtime::LcmBus bus(harness::kLiveUrl);
  REQUIRE(bus.open());
  harness::Recorder rec = harness::Recorder::live(
      bus, {channel(launcher::kHostStateChannel), channel(kPredictionChannel), channel(kImageChannel), channel(kStackChannel)});
  std::optional<host_state_t> hs;
  const bool resumed = rec.wait_until([&] {
    hs = rec.newest<host_state_t>(channel(launcher::kHostStateChannel));
    return hs && hs->modules_up == 5 && rec.count(channel(kImageChannel)) > 5 && rec.count(channel(kStackChannel)) > 5 &&
           rec.count(channel(kPredictionChannel)) > 5;
  }, 30s);
  INFO(dir.read("launch.out") << dir.read("launch.err"));
  REQUIRE(resumed);  // simcam -> vision -> prediction flows again
  for (const auto& m : hs->modules) {
    INFO(m.name << ": " << m.status);
    CHECK(m.pid == pids[m.name]);
    CHECK(m.restarts == 0);
  }
  launcher.signal(SIGTERM);
  REQUIRE(launcher.wait_for(20s));
  const std::string out = dir.read("launch.out");
  CHECK(out.find("silent for") == std::string::npos);
  CHECK(out.find("died") == std::string::npos);
}
