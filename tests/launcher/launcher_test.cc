// NETNS, real processes: bricklayer-launch supervising bricklayer-prediction.
#include <signal.h>

#include <catch2/catch.hpp>

#include <lcm/lcm-cpp.hpp>

#include <filesystem>
#include <fstream>
#include <regex>
#include <sstream>

#include "bricklayer/common/channels.h"
#include "bricklayer/heartbeat_t.hpp"
#include "bricklayer/command_t.hpp"
#include "bricklayer/host_state_t.hpp"
#include "bricklayer/launcher/supervisor.h"

#include "bricklayer/launcher/process.h"
#include "bricklayer/prediction/sample_stacks.h"
#include "bricklayer/prediction_t.hpp"
#include "bricklayer/runtime/lcm_bus.h"
#include "bricklayer/stack_t.hpp"
#include "harness/live_bus.h"
#include "harness/recorder.h"
#include "launcher_test_util.h"

using namespace bricklayer;
using namespace std::chrono_literals;
namespace fs = std::filesystem;
using Clock = std::chrono::steady_clock;
using test::launch;
using test::TempDir;

TEST_CASE("kill -9 of the prediction under the launcher: heartbeat back within 2 s, predictions resume") {
  TempDir dir("kill");
  auto profile = dir.write("p.json", R"({"modules":[
      {"name":"prediction","command":["bricklayer-prediction","--log-level","warn"],"restart":"always"}]})");
  auto launcher = launch(dir, profile);
  runtime::LcmBus bus(harness::kLiveUrl);
  REQUIRE(bus.open());
  harness::Recorder rec = harness::Recorder::live(bus, {channel(kPredictionChannel), channel(kHeartbeatChannel)});

  const auto hb = rec.wait_for_heartbeat("prediction", {}, 10s);
  REQUIRE(hb);
  const pid_t first = hb->pid;
  CHECK(hb->restarts == 0);

  // The publisher: a stack every 10 ms whatever happens to the subscriber; each publish call is timed.
  int64_t frame = 0;
  double slowest_publish_ms = 0;
  auto publish_for = [&](std::chrono::milliseconds d, const std::function<bool()>& until) {
    auto end = Clock::now() + d;
    while (Clock::now() < end) {
      ++frame;
      bricklayer::stack_t s = prediction::sample_stack(10, static_cast<uint32_t>(frame), frame, frame);
      auto t0 = Clock::now();
      REQUIRE(harness::publish(bus, channel(kStackChannel), s));
      slowest_publish_ms = std::max(slowest_publish_ms, std::chrono::duration<double, std::milli>(Clock::now() - t0).count());
      rec.pump_for(10ms);
      if (until && until()) return true;
    }
    return false;
  };
  publish_for(500ms, nullptr);
  const size_t answered_before = rec.count(channel(kPredictionChannel));
  CHECK(answered_before > 10);

  REQUIRE(::kill(first, SIGKILL) == 0);
  const auto killed_at = Clock::now();
  const int64_t frame_at_kill = frame;
  heartbeat_t back{};
  bool restarted = publish_for(5s, [&] {
    const auto newest = rec.last_heartbeat("prediction");
    if (newest) back = *newest;
    return newest && newest->pid != first;
  });
  const double seconds_to_heartbeat = std::chrono::duration<double>(Clock::now() - killed_at).count();
  REQUIRE(restarted);
  INFO("heartbeat of the restarted prediction after " << seconds_to_heartbeat << " s");
  CHECK(seconds_to_heartbeat < 2.0);
  CHECK(back.restarts == 1);

  // Predictions resume: answers to stacks sent after the restart.
  int64_t frame_after_restart = frame;
  bool resumed = publish_for(3s, [&] {
    for (const prediction_t& p : rec.all<prediction_t>(channel(kPredictionChannel)))
      if (p.frame_number > frame_after_restart) return true;
    return false;
  });
  CHECK(resumed);
  CHECK(frame > frame_at_kill);
  INFO("slowest publish call: " << slowest_publish_ms << " ms");
  CHECK(slowest_publish_ms < 1000.0);  // never blocked on the dead subscriber

  launcher.signal(SIGTERM);
  auto st = launcher.wait_for(15s);
  REQUIRE(st);
  CHECK(st->clean());
  std::string out = dir.read("launch.out");
  INFO(out);
  CHECK(out.find("died: killed by signal 9") != std::string::npos);
  CHECK(out.find("restart #1") != std::string::npos);
  CHECK(out.find("summary of profile p") != std::string::npos);
  CHECK(::kill(back.pid, 0) != 0);  // the restarted prediction was stopped too
}

TEST_CASE("a hung module (heartbeat stops) is killed and restarted") {
  TempDir dir("hang");
  auto profile = dir.write("p.json", R"({"modules":[
      {"name":"prediction","command":["bricklayer-prediction","--log-level","warn"],"heartbeat_timeout_s":1.5}]})");
  auto launcher = launch(dir, profile);
  runtime::LcmBus bus(harness::kLiveUrl);
  REQUIRE(bus.open());
  harness::Recorder rec = harness::Recorder::live(bus, {channel(kHeartbeatChannel)});
  const auto hb = rec.wait_for_heartbeat("prediction", {}, 10s);
  REQUIRE(hb);
  const pid_t hung = hb->pid;
  REQUIRE(::kill(hung, SIGSTOP) == 0);  // alive but silent
  const auto back = rec.wait_for_heartbeat("prediction", [&](const heartbeat_t& h) { return h.pid != hung; }, 8s);
  REQUIRE(back);
  CHECK(back->restarts == 1);
  launcher.signal(SIGTERM);
  REQUIRE(launcher.wait_for(15s));
  std::string out = dir.read("launch.out");
  INFO(out);
  CHECK(out.find("prediction silent for 1.5 s: killing it") != std::string::npos);
  CHECK(out.find("died: killed by signal 9") != std::string::npos);
}

TEST_CASE("the operator's restart (RESTART_MODULE HOST/NAME) stops a module and starts it again, whatever its policy") {
  TempDir dir("operator-restart");
  // on-failure: a module that ends cleanly on SIGTERM would stay down; the operator's restart does not.
  auto profile = dir.write("p.json", R"({"modules":[
      {"name":"prediction","command":["bricklayer-prediction","--log-level","warn"],"restart":"on-failure"}]})");
  auto launcher = launch(dir, profile, {"--host-name", "camera-host"});
  runtime::LcmBus bus(harness::kLiveUrl);
  REQUIRE(bus.open());
  harness::Recorder rec = harness::Recorder::live(bus, {channel(kHeartbeatChannel)});
  auto hb = rec.wait_for_heartbeat("prediction", {}, 10s);
  REQUIRE(hb);
  const pid_t first = hb->pid;
  auto send = [&](const std::string& argument) {
    command_t c{};
    c.command = command_t::RESTART_MODULE;
    c.argument = argument;
    c.sequence = -1;
    REQUIRE(harness::publish(bus, channel(kCommandChannel), c));
  };
  // Another host's module and a module this host does not run: nothing restarts.
  send("projector-host/prediction");
  send("camera-host/no-such-module");
  rec.pump_for(1500ms);
  hb = rec.last_heartbeat("prediction");
  REQUIRE(hb);
  CHECK(hb->pid == first);

  send("camera-host/prediction");
  const auto back = rec.wait_for_heartbeat("prediction", [&](const heartbeat_t& h) { return h.pid != first; }, 10s);
  REQUIRE(back);
  CHECK(back->restarts == 1);
  CHECK(::kill(first, 0) != 0);
  // The launcher's newest heartbeat once one came after the restart was asked for.
  REQUIRE(rec.wait_until([&] { return rec.last_heartbeat("launcher").has_value(); }, 3s));
  CHECK(harness::heartbeat_value(*rec.last_heartbeat("launcher"), "restart_requests_unknown") == 1);
  launcher.signal(SIGTERM);
  REQUIRE(launcher.wait_for(15s));
  const std::string out = dir.read("launch.out");
  INFO(out);
  CHECK(out.find("restarting prediction (pid " + std::to_string(first) + ") as the operator asked") != std::string::npos);
  CHECK(out.find("restart asked for a module this host does not run: \"no-such-module\" (counted)") != std::string::npos);
}

TEST_CASE("launch/bricklayer runs a profile with the build's binaries and stops after --duration") {
  TempDir dir("wrapper");
  auto profile = dir.write("p.json", R"({"modules":[
      {"name":"prediction","command":["bricklayer-prediction","--log-level","warn"]}]})");
  launcher::SpawnOptions o;
  o.stdout_path = (dir.path / "wrapper.out").string();
  o.merge_stderr = true;
  o.env = {"BRICKLAYER_BUILD_DIR=" + harness::binary_dir().string(), std::string("LCM_DEFAULT_URL=") + harness::kLiveUrl};
  auto wrapper = launcher::Process::spawn(
      {std::string(BRICKLAYER_SOURCE_DIR) + "/launch/bricklayer", profile.string(), "--duration", "1"}, o);
  auto st = wrapper.wait_for(20s);
  REQUIRE(st);
  std::string out = dir.read("wrapper.out");
  INFO(out);
  CHECK(st->clean());
  CHECK(out.find("prediction up (pid") != std::string::npos);
  CHECK(out.find("summary of profile p") != std::string::npos);

  auto unknown = launcher::Process::spawn({std::string(BRICKLAYER_SOURCE_DIR) + "/launch/bricklayer", "no-such-profile"}, o);
  auto ust = unknown.wait_for(10s);
  REQUIRE(ust);
  CHECK(ust->code == 2);
  out = dir.read("wrapper.out");
  CHECK(out.find("no profile 'no-such-profile'") != std::string::npos);
  CHECK(out.find("demo") != std::string::npos);  // the list of profiles follows
}

TEST_CASE("a profile naming a binary that does not exist is a clear error before anything starts") {
  TempDir dir("missing");
  auto profile = dir.write("p.json", R"({"modules":[
      {"name":"prediction","command":["bricklayer-prediction"]},
      {"name":"vision","command":["bricklayer-no-such-module","--x"]}]})");
  auto launcher = launch(dir, profile);
  auto st = launcher.wait_for(10s);
  REQUIRE(st);
  CHECK(st->code == 2);
  std::string err = dir.read("launch.err");
  INFO(err);
  CHECK(err.find("module 'vision' needs 'bricklayer-no-such-module', which was not found") != std::string::npos);
  CHECK(dir.read("launch.out").find("starting") == std::string::npos);
}

TEST_CASE("a module that never sends its heartbeat is killed and retried while the rest run, and what is down is said") {
  TempDir dir("silent");
  auto profile = dir.write("p.json", R"({"stop_timeout_s":1,"modules":[
      {"name":"mute","command":["/bin/sleep","60"],"heartbeat":"mute","ready_timeout_s":1,"backoff_max_s":0.5},
      {"name":"prediction","command":["bricklayer-prediction","--log-level","warn"]}]})");
  auto launcher = launch(dir, profile, {"--duration", "5"});
  auto st = launcher.wait_for(20s);
  REQUIRE(st);
  std::string out = dir.read("launch.out");
  INFO(out << dir.read("launch.err"));
  CHECK(st->code == 1);  // stopped with a module down
  CHECK(out.find("mute (pid") != std::string::npos);
  CHECK(out.find("sent no heartbeat on BL_HEARTBEAT within 1.0 s of starting: killing it") != std::string::npos);
  CHECK(out.find("restart #2") != std::string::npos);       // retried, not given up on
  CHECK(out.find("prediction up (pid") != std::string::npos);  // the start order went on past it
  CHECK(out.find("all 2 processes") == std::string::npos);
  CHECK(out.find("1 of 2 processes of profile p are up; down: mute (") != std::string::npos);
  CHECK(out.find("down at the stop: mute (") != std::string::npos);
}

TEST_CASE("a module that keeps exiting before it comes up is retried with a capped backoff, never given up on") {
  TempDir dir("crashloop");
  auto profile = dir.write("p.json", R"({"modules":[
      {"name":"broken","command":["/bin/false"],"heartbeat":"broken","backoff_max_s":0.4},
      {"name":"prediction","command":["bricklayer-prediction","--log-level","warn"]}]})");
  auto launcher = launch(dir, profile, {"--duration", "5"});
  runtime::LcmBus bus(harness::kLiveUrl);
  REQUIRE(bus.open());
  harness::Recorder rec = harness::Recorder::live(bus, {channel(launcher::kHostStateChannel), channel(kHeartbeatChannel)});
  const auto hb = rec.wait_for_heartbeat("prediction", {}, 10s);
  REQUIRE(hb);
  rec.wait_until([&] { return !launcher.running(); }, 10s);  // listening to the host state meanwhile
  auto st = launcher.wait_for(20s);
  REQUIRE(st);
  std::string out = dir.read("launch.out");
  INFO(out << dir.read("launch.err"));
  CHECK(st->code == 1);
  CHECK(out.find("giving up") == std::string::npos);
  // 0.1, 0.2, 0.4, 0.4, ... s: at least 8 restarts in 5 s; without the cap (0.8, 1.6, 3.2) at most 5.
  std::smatch m;
  REQUIRE(std::regex_search(out, m, std::regex(R"(\n  broken +(\d+) )")));
  CHECK(std::stoi(m[1]) >= 8);
  CHECK(out.find("restarting in 0.4 s (5 quick failures in a row)") != std::string::npos);
  CHECK(out.find("restarting in 0.8 s") == std::string::npos);
  CHECK(out.find("1 of 2 processes of profile p are up; down: broken (restarting: exit code 1)") != std::string::npos);
  // The host state named it down the whole time, and the prediction up with its real pid.
  host_state_t hs{};
  bool seen = false;
  for (const host_state_t& one : rec.all<host_state_t>(channel(launcher::kHostStateChannel))) {
    if (one.num_modules == 2 && one.modules[1].state == module_state_t::STATE_UP) {
      hs = one;
      seen = true;
    }
  }
  REQUIRE(seen);
  CHECK(hs.profile == "p");
  CHECK(hs.modules_up == 1);
  CHECK(hs.status.rfind("down: broken (", 0) == 0);
  CHECK(hs.modules[0].name == "broken");
  CHECK((hs.modules[0].state == module_state_t::STATE_RESTARTING || hs.modules[0].state == module_state_t::STATE_STARTING));
  CHECK(hs.modules[0].last_exit == "exit code 1");
  CHECK(hs.modules[1].pid == hb->pid);
}

TEST_CASE("the summary and the host state add up a module's counters across its restarts") {
  TempDir dir("sum");
  auto profile = dir.write("p.json", R"({"modules":[
      {"name":"prediction","command":["bricklayer-prediction","--log-level","warn"]}]})");
  auto launcher = launch(dir, profile);
  runtime::LcmBus bus(harness::kLiveUrl);
  REQUIRE(bus.open());
  harness::Recorder rec = harness::Recorder::live(bus, {channel(kHeartbeatChannel), channel(launcher::kHostStateChannel)});
  const auto hb = rec.wait_for_heartbeat("prediction", {}, 10s);
  REQUIRE(hb);
  int64_t frame = 0;
  // Sends n stacks, then waits until the prediction's own heartbeat counts them all.
  auto send = [&](int n, pid_t pid) {
    for (int i = 0; i < n; ++i) {
      ++frame;
      bricklayer::stack_t s = prediction::sample_stack(5, static_cast<uint32_t>(frame), frame, frame);
      REQUIRE(harness::publish(bus, channel(kStackChannel), s));
      rec.pump_for(5ms);
    }
    return rec.wait_until([&] {
      const auto now = rec.last_heartbeat("prediction");
      return now && now->pid == pid && now->received == n;
    }, 5s);
  };
  REQUIRE(send(40, hb->pid));
  const pid_t first = hb->pid;
  REQUIRE(::kill(first, SIGKILL) == 0);
  const auto back = rec.wait_for_heartbeat("prediction", [&](const heartbeat_t& h) { return h.pid != first; }, 8s);
  REQUIRE(back);
  REQUIRE(send(25, back->pid));
  // The host state: 65 received by the module, though its current process says 25.
  rec.clear();
  const auto hs = rec.wait_for<host_state_t>(channel(launcher::kHostStateChannel), [](const host_state_t& h) {
    return h.num_modules == 1 && h.modules[0].received == 65;
  }, 5s);
  REQUIRE(hs);
  CHECK(hs->modules[0].restarts == 1);
  CHECK(hs->modules[0].pid == back->pid);
  launcher.signal(SIGTERM);
  REQUIRE(launcher.wait_for(15s));
  std::string out = dir.read("launch.out");
  INFO(out);
  std::smatch m;
  REQUIRE(std::regex_search(out, m, std::regex(R"(\n  prediction +(\d+) +(\d+) +(\d+))")));
  CHECK(m[1] == "1");
  CHECK(m[2] == "65");
}

TEST_CASE("a run with a duration stops by itself (SIGTERM, deadline, SIGKILL) and the logger records it") {
  TempDir dir("duration");
  auto profile = dir.write("p.json", R"({"stop_timeout_s":0.5,
      "logger":{"file":"logs/run","rotate":2,"split_mb":10},
      "notes":["look here"],
      "modules":[
      {"name":"prediction","command":["bricklayer-prediction","--log-level","warn"]},
      {"name":"stubborn","command":["/bin/sh","-c","trap '' TERM; sleep 60"],"heartbeat":""}]})");
  auto t0 = Clock::now();
  auto launcher = launch(dir, profile, {"--duration", "2"});
  auto st = launcher.wait_for(20s);
  REQUIRE(st);
  INFO(dir.read("launch.out") << dir.read("launch.err"));
  CHECK(st->clean());
  CHECK(std::chrono::duration<double>(Clock::now() - t0).count() < 10.0);
  std::string out = dir.read("launch.out");
  CHECK(out.find("look here") != std::string::npos);
  CHECK(out.find("stubborn ignored SIGTERM for 0.5 s: SIGKILL") != std::string::npos);
  CHECK(out.find("duration of 2.0 s reached") != std::string::npos);

  // The logger wrote logs/run.0 under the root, with the prediction's heartbeats in it.
  const fs::path log = dir.path / "logs" / "run.0";
  REQUIRE(fs::exists(log));
  lcm::LogFile file(log.string(), "r");
  REQUIRE(file.good());
  int beats = 0;
  while (const lcm::LogEvent* e = file.readNextEvent()) {
    if (e->channel != channel(kHeartbeatChannel)) continue;
    heartbeat_t hb{};
    if (hb.decode(e->data, 0, e->datalen) >= 0 && hb.module == "prediction") ++beats;
  }
  CHECK(beats >= 2);
}

TEST_CASE("a camera absent at boot: the exhibit runs, the camera waits with the same pid, and the host state says so") {
  TempDir dir("nocamera");
  auto profile = dir.write("p.json", R"({"modules":[
      {"name":"prediction","command":["bricklayer-prediction","--log-level","warn"]},
      {"name":"camera","command":["bricklayer-camera","--device","/dev/video-none"]}]})");
  auto launcher = launch(dir, profile);
  runtime::LcmBus bus(harness::kLiveUrl);
  REQUIRE(bus.open());
  harness::Recorder rec = harness::Recorder::live(bus, {channel(kHeartbeatChannel), channel(launcher::kHostStateChannel)});
  const auto first = rec.wait_for_heartbeat("camera", {}, 10s);
  REQUIRE(first);
  rec.pump_for(6s);  // beyond the old launcher's 3 quick tries
  REQUIRE(launcher.running());
  const auto later = rec.last_heartbeat("camera");
  REQUIRE(later);
  CHECK(later->pid == first->pid);
  CHECK(later->restarts == 0);
  CHECK(later->status.rfind("waiting for camera /dev/video-none: cannot open camera", 0) == 0);
  const auto hs = rec.newest<host_state_t>(channel(launcher::kHostStateChannel));
  REQUIRE(hs);
  REQUIRE(hs->num_modules == 2);
  CHECK(hs->modules[1].name == "camera");
  CHECK(hs->modules[1].state == module_state_t::STATE_UP);
  CHECK(hs->modules[1].status == later->status);
  CHECK(hs->modules[1].restarts == 0);
  launcher.signal(SIGTERM);
  auto st = launcher.wait_for(15s);
  REQUIRE(st);
  CHECK(st->clean());
  const std::string out = dir.read("launch.out");
  INFO(out);
  CHECK(out.find("all 2 processes of profile p are up") != std::string::npos);
  CHECK(out.find("died") == std::string::npos);
}
