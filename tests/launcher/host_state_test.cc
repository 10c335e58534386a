// NETNS, real processes: two launchers on one bus (a camera host and a projector host, told apart by
// --host-name) each publish their host's whole state once a second; an observer that starts late
// knows every module of both from one message each.
#include <signal.h>

#include <catch2/catch.hpp>

#include <map>
#include <thread>

#include "bricklayer/common/channels.h"
#include "bricklayer/heartbeat_t.hpp"
#include "bricklayer/host_state_t.hpp"
#include "bricklayer/launcher/supervisor.h"
#include "bricklayer/runtime/lcm_bus.h"
#include "harness/recorder.h"
#include "launcher_test_util.h"

using namespace bricklayer;
using namespace std::chrono_literals;

TEST_CASE("a late observer catches up on both hosts' whole state from one host_state_t each") {
  test::TempDir dir("hoststate");
  auto camera_profile = dir.write("camera.json", R"({"modules":[
      {"name":"prediction","command":["bricklayer-prediction","--log-level","warn"]},
      {"name":"broken","command":["/bin/false"],"heartbeat":"broken","backoff_max_s":0.3}]})");
  auto projector_profile = dir.write("projector.json", R"({"modules":[
      {"name":"planner","command":["bricklayer-planner","--log-level","warn"]},
      {"name":"once","command":["/bin/true"],"heartbeat":"","restart":"on-failure"}]})");
  auto a = test::launch(dir, camera_profile, {"--host-name", "camera-host"}, "a");
  auto b = test::launch(dir, projector_profile, {"--host-name", "projector-host"}, "b");
  // Started late: everything is up (or retrying) by now.
  std::this_thread::sleep_for(4s);
  runtime::LcmBus bus(harness::kLiveUrl);
  REQUIRE(bus.open());
  harness::Recorder rec = harness::Recorder::live(bus, {channel(launcher::kHostStateChannel), channel(kHeartbeatChannel)});
  std::map<std::string, host_state_t> first;  // the first message heard from each host
  REQUIRE(rec.wait_until([&] {
    for (const host_state_t& hs : rec.all<host_state_t>(channel(launcher::kHostStateChannel)))
      if (!first.count(hs.host)) first[hs.host] = hs;
    return first.size() == 2;
  }, 3s));
  INFO(dir.read("launcha.out") << dir.read("launchb.out"));
  const host_state_t& cam = first.at("camera-host");
  const host_state_t& proj = first.at("projector-host");
  CHECK(cam.launcher_pid == a.pid());
  CHECK(proj.launcher_pid == b.pid());
  CHECK(cam.profile == "camera");
  REQUIRE(cam.num_modules == 2);
  REQUIRE(proj.num_modules == 2);

  // The camera host: prediction up with its real, living pid and its status line; broken down, said so.
  const module_state_t& prediction = cam.modules[0];
  CHECK(prediction.name == "prediction");
  CHECK(prediction.state == module_state_t::STATE_UP);
  REQUIRE(prediction.pid > 0);
  CHECK(::kill(prediction.pid, 0) == 0);
  CHECK(prediction.uptime_us > 2'000'000);
  CHECK(prediction.restarts == 0);
  CHECK(prediction.status == "ok");
  const module_state_t& broken = cam.modules[1];
  CHECK((broken.state == module_state_t::STATE_RESTARTING || broken.state == module_state_t::STATE_STARTING));
  CHECK(broken.restarts >= 3);
  CHECK(broken.last_exit == "exit code 1");
  CHECK(cam.modules_up == 1);
  CHECK(cam.status.rfind("down: broken (restarting: exit code 1)", 0) == 0);

  // The projector host: the planner up, the one-shot finished as its policy allows: all up.
  CHECK(proj.modules[0].name == "planner");
  CHECK(proj.modules[0].state == module_state_t::STATE_UP);
  CHECK(::kill(proj.modules[0].pid, 0) == 0);
  CHECK(proj.modules[1].state == module_state_t::STATE_EXITED);
  CHECK(proj.modules[1].pid == 0);
  CHECK(proj.modules_up == 2);
  CHECK(proj.status == "ok");

  // Once a second, and the pid agrees with the module's own heartbeat.
  rec.clear();
  rec.pump_for(2500ms);
  int from_camera = 0;
  for (const host_state_t& hs : rec.all<host_state_t>(channel(launcher::kHostStateChannel))) from_camera += hs.host == "camera-host";
  CHECK(from_camera >= 2);
  CHECK(from_camera <= 4);
  const auto hb = rec.last_heartbeat("prediction");
  REQUIRE(hb);
  CHECK(hb->pid == prediction.pid);

  // A host that stops says so last: its modules stopped.
  rec.clear();
  b.signal(SIGTERM);
  REQUIRE(b.wait_for(15s));
  rec.pump_for(300ms);
  host_state_t last{};
  for (const host_state_t& hs : rec.all<host_state_t>(channel(launcher::kHostStateChannel)))
    if (hs.host == "projector-host") last = hs;
  REQUIRE(last.num_modules == 2);
  CHECK(last.modules[0].state == module_state_t::STATE_STOPPED);
  a.signal(SIGTERM);
  REQUIRE(a.wait_for(15s));
}

TEST_CASE("a host whose launcher goes silent is missed in the other host's status, one stopped on purpose is not") {
  test::TempDir dir("peers");
  auto camera_profile = dir.write("camera.json", R"({"modules":[
      {"name":"prediction","command":["bricklayer-prediction","--log-level","warn"]}]})");
  auto projector_profile = dir.write("projector.json", R"({"modules":[
      {"name":"sleeper","command":["/bin/sleep","60"],"heartbeat":""}]})");
  auto a = test::launch(dir, camera_profile, {"--host-name", "camera-host"}, "a");
  auto b = test::launch(dir, projector_profile, {"--host-name", "projector-host"}, "b");
  runtime::LcmBus bus(harness::kLiveUrl);
  REQUIRE(bus.open());
  harness::Recorder rec = harness::Recorder::live(bus, {channel(launcher::kHostStateChannel)});
  auto camera_status = [&] {
    std::string status;
    for (const host_state_t& hs : rec.all<host_state_t>(channel(launcher::kHostStateChannel)))
      if (hs.host == "camera-host") status = hs.status;
    return status;
  };
  REQUIRE(rec.wait_until([&] { return dir.read("launcha.out").find("host projector-host (profile projector) is on the bus") != std::string::npos; }, 10s));
  INFO(dir.read("launcha.out"));
  // The projector host's launcher dies without a word (kill -9: no last message).
  b.signal(SIGKILL);
  REQUIRE(b.wait_for(5s));
  rec.clear();
  REQUIRE(rec.wait_until([&] { return camera_status().find("no host state from projector-host for") != std::string::npos; }, 10s));
  CHECK(camera_status().rfind("no host state from projector-host for ", 0) == 0);
  CHECK(dir.read("launcha.out").find("no host state from projector-host for 5.0 s (the other machine off") != std::string::npos);

  // Back: heard again, "ok"; then stopped on purpose (SIGTERM: its last message says stopped): not missed.
  auto b2 = test::launch(dir, projector_profile, {"--host-name", "projector-host"}, "b2");
  rec.clear();
  REQUIRE(rec.wait_until([&] { return camera_status() == "ok"; }, 10s));
  CHECK(dir.read("launcha.out").find("host projector-host is heard again") != std::string::npos);
  b2.signal(SIGTERM);
  REQUIRE(b2.wait_for(15s));
  rec.clear();
  rec.pump_for(7s);
  CHECK(camera_status() == "ok");
  a.signal(SIGTERM);
  REQUIRE(a.wait_for(15s));
}
