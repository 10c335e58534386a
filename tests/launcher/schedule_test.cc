// NETNS, real processes: a profile with opening hours (10:00-10:10) and a nightly restart (10:05) under
// the launcher's test clock (BRICKLAYER_LAUNCHER_CLOCK, starting at 09:59:00 and running 30 times faster,
// a minute every 2 s): closed at the start (the prediction waits, "closed until 10:00" in the host state
// and the launcher's heartbeat, the module kept for the closed board runs), started at opening, every
// running process restarted once at 10:05 (not again while the clock is within that minute), the
// prediction stopped cleanly at closing time while the kept one runs on, and a clean stop exits 0.
#include <signal.h>

#include <catch2/catch.hpp>

#include "bricklayer/common/channels.h"
#include "bricklayer/heartbeat_t.hpp"
#include "bricklayer/host_state_t.hpp"
#include "bricklayer/launcher/supervisor.h"
#include "bricklayer/runtime/lcm_bus.h"
#include "harness/recorder.h"
#include "launcher_test_util.h"

using namespace bricklayer;
using namespace std::chrono_literals;

namespace {

size_t count(const std::string& text, const std::string& what) {
  size_t n = 0;
  for (auto at = text.find(what); at != std::string::npos; at = text.find(what, at + 1)) ++n;
  return n;
}

}  // namespace

TEST_CASE("opening hours and the nightly restart under the launcher's test clock") {
  test::TempDir dir("schedule");
  auto profile = dir.write("hours.json", R"({
  "opening_hours": "10:00-10:10",
  "nightly_restart": "10:05",
  "stop_timeout_s": 3,
  "modules": [
    {"name": "kept", "command": ["/bin/sleep", "1000"], "heartbeat": "", "when_closed": "run"},
    {"name": "prediction", "command": ["bricklayer-prediction", "--log-level", "warn"]}
  ]})");
  std::vector<std::string> argv = {harness::program_path("bricklayer-launch"), "--root", dir.path.string(), "--bin-dir",
                                   (harness::binary_dir() / "bin").string(), "--lcm-url", harness::kLiveUrl,
                                   "--host-name", "hours-host", profile.string()};
  launcher::SpawnOptions o;
  o.stdout_path = (dir.path / "launch.out").string();
  o.stderr_path = (dir.path / "launch.err").string();
  o.env = {"DISPLAY=", "BRICKLAYER_LAUNCHER_CLOCK=Wed 09:59:00 x30"};

  runtime::LcmBus bus(harness::kLiveUrl);
  REQUIRE(bus.open());
  harness::Recorder rec = harness::Recorder::live(bus, {channel(launcher::kHostStateChannel), channel(kHeartbeatChannel)});
  launcher::Process launch = launcher::Process::spawn(argv, o);

  host_state_t last{};
  heartbeat_t launcher_beat{};
  auto pump_for = [&](const std::function<bool(const host_state_t&)>& pred, std::chrono::milliseconds timeout) {
    return rec.wait_until([&] {
      bool hit = false;
      for (const heartbeat_t& hb : rec.all<heartbeat_t>(channel(kHeartbeatChannel)))
        if (hb.module == "launcher" && hb.pid == launch.pid()) launcher_beat = hb;
      for (const host_state_t& hs : rec.all<host_state_t>(channel(launcher::kHostStateChannel))) {
        if (hs.launcher_pid != launch.pid()) continue;
        last = hs;
        if (pred(hs)) hit = true;
      }
      rec.clear();
      return hit;
    }, timeout);
  };
  auto module = [](const host_state_t& hs, const std::string& name) {
    for (const auto& m : hs.modules)
      if (m.name == name) return m;
    return module_state_t{};
  };

  // 1. Closed at the start: the prediction is not started, the kept module runs.
  REQUIRE(pump_for([](const host_state_t&) { return true; }, 5s));
  INFO(dir.read("launch.out") << dir.read("launch.err"));
  REQUIRE(last.num_modules == 2);
  CHECK(last.status == "closed until 10:00");
  const module_state_t closed = module(last, "prediction");
  CHECK(closed.state == module_state_t::STATE_WAITING);
  CHECK(closed.status == "closed until 10:00");
  CHECK(closed.pid == 0);
  CHECK(closed.restart_in_us > 0);  // the time to opening, in real time
  const module_state_t kept0 = module(last, "kept");
  CHECK(kept0.state == module_state_t::STATE_UP);
  REQUIRE(kept0.pid > 0);

  // 2. Opening at 10:00: the prediction starts and comes up; the host is "ok".
  REQUIRE(pump_for([&](const host_state_t& hs) { return module(hs, "prediction").state == module_state_t::STATE_UP && hs.status == "ok"; }, 15s));
  const module_state_t open = module(last, "prediction");
  REQUIRE(open.pid > 0);
  CHECK(open.restarts == 0);
  CHECK(::kill(open.pid, 0) == 0);
  CHECK(module(last, "kept").pid == kept0.pid);  // the kept one went on through the opening
  // The launcher's own heartbeat says the same (its next one: it is sent beside the host state).
  CHECK(pump_for([&](const host_state_t&) { return launcher_beat.status == "ok"; }, 3s));

  // 3. The nightly restart at 10:05: both running processes, once, with new pids.
  REQUIRE(pump_for([&](const host_state_t& hs) {
    const module_state_t p = module(hs, "prediction");
    return p.restarts == 1 && p.state == module_state_t::STATE_UP && module(hs, "kept").restarts == 1;
  }, 20s));
  const module_state_t restarted = module(last, "prediction");
  CHECK(restarted.pid != open.pid);
  CHECK(restarted.last_exit == "exit code 0");  // SIGTERM: a clean stop, as an operator's restart
  const module_state_t kept1 = module(last, "kept");
  CHECK(kept1.pid != kept0.pid);
  CHECK(kept1.last_exit == "killed by signal 15 (Terminated)");

  // 4. Closing at 10:10 (the clock passed the rest of 10:05's minute on the way): the prediction is
  //    stopped cleanly and waits for tomorrow; the kept one runs on; the restart happened once only.
  REQUIRE(pump_for([&](const host_state_t& hs) {
    return hs.status == "closed until 10:00" && module(hs, "prediction").state == module_state_t::STATE_WAITING;
  }, 25s));
  const module_state_t night = module(last, "prediction");
  CHECK(night.pid == 0);
  CHECK(night.restarts == 1);
  CHECK(night.status == "closed until 10:00");
  CHECK(night.last_exit == "exit code 0");
  CHECK(::kill(restarted.pid, 0) != 0);  // gone (and reaped by the launcher)
  CHECK(module(last, "kept").pid == kept1.pid);
  CHECK(module(last, "kept").restarts == 1);
  CHECK(last.modules_up == 1);
  CHECK(pump_for([&](const host_state_t&) { return launcher_beat.status == "closed until 10:00"; }, 3s));

  const std::string out = dir.read("launch.out");
  CHECK(count(out, "nightly restart (10:05): restarting 2 running processes") == 1);
  CHECK(count(out, "closed now (opening hours 10:00-10:10, local time 09:59)") == 1);
  CHECK(count(out, "opening time (opening hours 10:00-10:10") == 1);
  CHECK(count(out, "closing time (opening hours 10:00-10:10") == 1);
  CHECK(count(out, "prediction (pid " + std::to_string(restarted.pid) + ") stopped for the closing time: exit code 0") == 1);

  // 5. A stop while closed is a clean run: nothing is down, every module stopped in the last state.
  launch.signal(SIGTERM);
  auto st = launch.wait_for(15s);
  REQUIRE(st);
  CHECK(st->code == 0);
  pump_for([](const host_state_t&) { return false; }, 500ms);
  for (const auto& m : last.modules) CHECK(m.state == module_state_t::STATE_STOPPED);
}
