// NETNS, real processes: bricklayer-launch supervising bricklayer-prediction.
#include <signal.h>

#include <catch2/catch.hpp>

#include <lcm/lcm-cpp.hpp>

#include <filesystem>
#include <fstream>
#include <sstream>

#include "bricklayer/launcher/process.h"
#include "bricklayer/prediction/sample_stacks.h"
#include "bricklayer/prediction_t.hpp"
#include "bricklayer/stack_t.hpp"
#include "../bus/bus_test_util.h"

using namespace bricklayer;
using namespace std::chrono_literals;
namespace fs = std::filesystem;
using Clock = std::chrono::steady_clock;

namespace {

struct TempDir {
  fs::path path;
  explicit TempDir(const std::string& tag) {
    path = fs::temp_directory_path() / ("bricklayer-launcher-" + tag + "-" + std::to_string(::getpid()));
    fs::remove_all(path);
    fs::create_directories(path);
  }
  ~TempDir() {
    std::error_code ec;
    fs::remove_all(path, ec);
  }
  fs::path write(const std::string& name, const std::string& text) const {
    std::ofstream(path / name) << text;
    return path / name;
  }
  std::string read(const std::string& name) const {
    std::ifstream in(path / name);
    std::stringstream s;
    s << in.rdbuf();
    return s.str();
  }
};

launcher::Process launch(const TempDir& dir, const fs::path& profile, std::vector<std::string> extra = {}) {
  std::vector<std::string> argv = {test::bin("bricklayer-launch"), "--root", dir.path.string(), "--bin-dir",
                                   std::string(BRICKLAYER_BINARY_DIR) + "/bin", "--lcm-url", test::kTestUrl,
                                   profile.string()};
  argv.insert(argv.end(), extra.begin(), extra.end());
  launcher::SpawnOptions o;
  o.stdout_path = (dir.path / "launch.out").string();
  o.stderr_path = (dir.path / "launch.err").string();
  o.env = {"DISPLAY="};
  return launcher::Process::spawn(argv, o);
}

}  // namespace

TEST_CASE("kill -9 of the prediction under the launcher: heartbeat back within 2 s, predictions resume") {
  TempDir dir("kill");
  auto profile = dir.write("p.json", R"({"modules":[
      {"name":"prediction","command":["bricklayer-prediction","--log-level","warn"],"restart":"always"}]})");
  auto launcher = launch(dir, profile);
  test::Listener bus;
  REQUIRE(bus.ok());
  bus.listen(channel(kPredictionChannel));
  bus.listen(channel(kHeartbeatChannel));

  heartbeat_t hb{};
  REQUIRE(bus.pump_until([&] { return bus.last_heartbeat("prediction", hb); }, 10s));
  const pid_t first = hb.pid;
  CHECK(hb.restarts == 0);

  // The publisher: a stack every 10 ms whatever happens to the subscriber; each publish call is timed.
  int64_t frame = 0;
  double slowest_publish_ms = 0;
  auto publish_for = [&](std::chrono::milliseconds d, const std::function<bool()>& until) {
    auto end = Clock::now() + d;
    while (Clock::now() < end) {
      ++frame;
      bricklayer::stack_t s = prediction::sample_stack(10, static_cast<uint32_t>(frame), frame, frame);
      auto t0 = Clock::now();
      REQUIRE(bus.lcm().publish(channel(kStackChannel), &s) == 0);
      slowest_publish_ms = std::max(slowest_publish_ms, std::chrono::duration<double, std::milli>(Clock::now() - t0).count());
      bus.pump(10ms);
      if (until && until()) return true;
    }
    return false;
  };
  publish_for(500ms, nullptr);
  const size_t answered_before = bus.count(channel(kPredictionChannel));
  CHECK(answered_before > 10);

  REQUIRE(::kill(first, SIGKILL) == 0);
  const auto killed_at = Clock::now();
  const int64_t frame_at_kill = frame;
  heartbeat_t back{};
  bool restarted = publish_for(5s, [&] { return bus.last_heartbeat("prediction", back) && back.pid != first; });
  const double seconds_to_heartbeat = std::chrono::duration<double>(Clock::now() - killed_at).count();
  REQUIRE(restarted);
  INFO("heartbeat of the restarted prediction after " << seconds_to_heartbeat << " s");
  CHECK(seconds_to_heartbeat < 2.0);
  CHECK(back.restarts == 1);

  // Predictions resume: answers to stacks sent after the restart.
  int64_t frame_after_restart = frame;
  bool resumed = publish_for(3s, [&] {
    for (const auto& m : bus.on(channel(kPredictionChannel))) {
      prediction_t p{};
      if (test::decode(m.bytes, p) && p.frame_number > frame_after_restart) return true;
    }
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
  test::Listener bus;
  REQUIRE(bus.ok());
  bus.listen(channel(kHeartbeatChannel));
  heartbeat_t hb{};
  REQUIRE(bus.pump_until([&] { return bus.last_heartbeat("prediction", hb); }, 10s));
  const pid_t hung = hb.pid;
  REQUIRE(::kill(hung, SIGSTOP) == 0);  // alive but silent
  heartbeat_t back{};
  REQUIRE(bus.pump_until([&] { return bus.last_heartbeat("prediction", back) && back.pid != hung; }, 8s));
  CHECK(back.restarts == 1);
  launcher.signal(SIGTERM);
  REQUIRE(launcher.wait_for(15s));
  std::string out = dir.read("launch.out");
  INFO(out);
  CHECK(out.find("prediction silent for 1.5 s: killing it") != std::string::npos);
  CHECK(out.find("died: killed by signal 9") != std::string::npos);
}

TEST_CASE("launch/bricklayer runs a profile with the build's binaries and stops after --duration") {
  TempDir dir("wrapper");
  auto profile = dir.write("p.json", R"({"modules":[
      {"name":"prediction","command":["bricklayer-prediction","--log-level","warn"]}]})");
  launcher::SpawnOptions o;
  o.stdout_path = (dir.path / "wrapper.out").string();
  o.merge_stderr = true;
  o.env = {std::string("BRICKLAYER_BUILD_DIR=") + BRICKLAYER_BINARY_DIR, std::string("LCM_DEFAULT_URL=") + test::kTestUrl};
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

TEST_CASE("a module that never sends a heartbeat fails the start, and everything is stopped") {
  TempDir dir("silent");
  auto profile = dir.write("p.json", R"({"stop_timeout_s":1,"modules":[
      {"name":"prediction","command":["bricklayer-prediction","--log-level","warn"]},
      {"name":"mute","command":["/bin/sleep","60"],"heartbeat":"mute","ready_timeout_s":1}]})");
  auto launcher = launch(dir, profile);
  auto st = launcher.wait_for(15s);
  REQUIRE(st);
  CHECK(st->code == 1);
  std::string err = dir.read("launch.err");
  INFO(err);
  CHECK(err.find("mute (pid") != std::string::npos);
  CHECK(err.find("sent no heartbeat on BL_HEARTBEAT within 1 s") != std::string::npos);
  CHECK(dir.read("launch.out").find("FAILED to start") != std::string::npos);
}

TEST_CASE("a module that keeps exiting before it comes up fails the start instead of looping") {
  TempDir dir("crashloop");
  auto profile = dir.write("p.json", R"({"modules":[
      {"name":"broken","command":["/bin/false"],"heartbeat":"broken"}]})");
  auto launcher = launch(dir, profile);
  auto st = launcher.wait_for(15s);
  REQUIRE(st);
  CHECK(st->code == 1);
  std::string out = dir.read("launch.out");
  INFO(out << dir.read("launch.err"));
  CHECK(out.find("restart #2") != std::string::npos);
  CHECK(out.find("broken keeps exiting before it comes up (exit code 1): giving up") != std::string::npos);
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
