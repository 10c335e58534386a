// The board: a module's state in plain words, hosts kept by name, silence, the round and the day's best.
#include <catch2/catch.hpp>

#include "bricklayer/status/status_board.h"

using namespace bricklayer;
using namespace bricklayer::status;

namespace {
module_state_t module(const std::string& name, int8_t state, const std::string& status = "ok") {
  module_state_t m{};
  m.name = name;
  m.state = state;
  m.status = status;
  return m;
}
host_state_t host(const std::string& name, std::vector<module_state_t> modules) {
  host_state_t h{};
  h.host = name;
  h.profile = "camera-host";
  h.status = "ok";
  h.modules = std::move(modules);
  h.num_modules = static_cast<int32_t>(h.modules.size());
  return h;
}
constexpr int64_t kT0 = 1'700'000'000'000'000;
}  // namespace

TEST_CASE("a module's state reads as plain words") {
  CHECK(read_module(module("vision", module_state_t::STATE_UP)).level == Level::ok);
  ModuleReading camera = read_module(module("camera", module_state_t::STATE_UP, "waiting for camera 0"));
  CHECK(camera.level == Level::warning);
  CHECK(camera.words == "waiting for camera 0");
  module_state_t crashed = module("vision", module_state_t::STATE_RESTARTING);
  crashed.last_exit = "killed by signal 9 (Killed)";
  crashed.restarts = 2;
  CHECK(read_module(crashed).words == "restarting (it ended: killed by signal 9 (Killed)), restarted 2 times");
  module_state_t failed = module("camera", module_state_t::STATE_FAILED);
  failed.last_exit = "exit code 2";
  CHECK(read_module(failed).level == Level::failed);
  CHECK(read_module(failed).words == "stopped for good (it ended: exit code 2); it will not restart by itself");
  CHECK(read_module(module("x", 42)).level == Level::failed);
}

TEST_CASE("the board keeps every host's latest state and says which problem is whose") {
  StatusBoard board(5.0);
  nlohmann::json empty = board.to_json();
  CHECK(empty["level"] == "failed");
  CHECK(empty["problems"][0].get<std::string>().find("no machine heard from yet") == 0);

  board.update(host("projector-host", {module("projection", module_state_t::STATE_UP)}), kT0);
  board.update(host("camera-host", {module("camera", module_state_t::STATE_UP, "waiting for camera 0"),
                                    module("vision", module_state_t::STATE_UP)}), kT0);
  nlohmann::json j = board.to_json();
  REQUIRE(j["hosts"].size() == 2);
  CHECK(j["hosts"][0]["host"] == "camera-host");  // by name
  CHECK(j["hosts"][0]["level"] == "warning");
  CHECK(j["hosts"][0]["modules"][0]["state"] == "up");
  CHECK(j["hosts"][1]["level"] == "ok");
  CHECK(j["level"] == "warning");
  REQUIRE(j["problems"].size() == 1);
  CHECK(j["problems"][0] == "camera: waiting for camera 0");

  // A newer state replaces the old one: the camera came up.
  board.update(host("camera-host", {module("camera", module_state_t::STATE_UP), module("vision", module_state_t::STATE_UP)}),
               kT0 + 1'000'000);
  CHECK(board.to_json()["level"] == "ok");
  CHECK(board.to_json()["problems"].empty());

  // The projector host falls silent: after 5 s it is the problem, said in words.
  board.set_now(kT0 + 5'500'000);
  j = board.to_json();
  CHECK(j["level"] == "failed");
  CHECK(j["hosts"][1]["silent"] == true);
  REQUIRE(j["problems"].size() == 1);
  CHECK(j["problems"][0].get<std::string>().rfind("projector-host is silent: nothing heard from it for 5 s", 0) == 0);
  CHECK(j["hosts"][0]["silent"] == false);
}

TEST_CASE("the round and the day's best, which starts again at midnight (UTC)") {
  StatusBoard board;
  CHECK(board.to_json()["round"].is_null());
  round_t r{};
  r.utime = kT0;
  r.state = round_t::STATE_RUNNING;
  r.remaining_ms = 90'000;
  r.max_score = 350;
  r.score = 200;
  r.num_blocks = 4;
  board.update(r);
  r.max_score = 120;  // the next round, lower
  board.update(r);
  nlohmann::json j = board.to_json();
  CHECK(j["round"]["state"] == "running");
  CHECK(j["round"]["max_score"] == 120);
  CHECK(j["round"]["remaining_s"] == 90.0);
  CHECK(j["best_today"] == 350);
  r.utime = kT0 + 86'400'000'000LL;
  r.max_score = 50;
  board.update(r);
  CHECK(board.to_json()["best_today"] == 50);
}
