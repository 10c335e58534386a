// NETNS, real processes: a real bricklayer-launch publishes its host's whole state on the bus and a
// real bricklayer-status serves it; the test reads it as a script would, over HTTP on loopback. A
// module killed with -9 turns to a warning on the page and back to ok once the launcher restarted it.
#include <signal.h>

#include <httplib.h>

#include <catch2/catch.hpp>

#include <fstream>
#include <functional>
#include <thread>

#include <nlohmann/json.hpp>

#include "harness/program.h"
#include "harness/scratch.h"

using namespace bricklayer;
using namespace std::chrono_literals;

namespace {
constexpr const char* kUrl = "udpm://239.255.76.67:7667?ttl=0";
constexpr int kPort = 18080;

std::optional<nlohmann::json> get_state() {
  httplib::Client client("127.0.0.1", kPort);
  client.set_connection_timeout(1);
  auto res = client.Get("/state.json");
  if (!res || res->status != 200) return std::nullopt;
  return nlohmann::json::parse(res->body);
}

// Polls /state.json until pred holds on it (or timeout); the last answer.
nlohmann::json wait_state(const std::function<bool(const nlohmann::json&)>& pred, std::chrono::seconds timeout) {
  const auto end = std::chrono::steady_clock::now() + timeout;
  nlohmann::json last;
  while (std::chrono::steady_clock::now() < end) {
    if (auto s = get_state()) {
      last = *s;
      if (pred(last)) return last;
    }
    std::this_thread::sleep_for(200ms);
  }
  return last;
}

const nlohmann::json* find_module(const nlohmann::json& state, const std::string& host, const std::string& name) {
  for (const auto& h : state["hosts"])
    if (h["host"] == host)
      for (const auto& m : h["modules"])
        if (m["name"] == name) return &m;
  return nullptr;
}
}  // namespace

TEST_CASE("bricklayer-status serves a real launcher's host state, a kill -9 and the recovery") {
  harness::ScratchDir dir("status-live");
  {
    std::ofstream(dir / "camera.json") << R"({"modules":[
      {"name":"prediction","command":["bricklayer-prediction","--log-level","warn"]},
      {"name":"broken","command":["/bin/false"],"heartbeat":"broken","backoff_max_s":0.3}]})";
  }
  harness::Program status("bricklayer-status", {"--lcm-url", kUrl, "--port", std::to_string(kPort)});
  harness::Program launch("bricklayer-launch",
                          {"--root", dir.str(), "--bin-dir", std::string(BRICKLAYER_BINARY_DIR) + "/bin", "--lcm-url", kUrl,
                           (dir / "camera.json").string(), "--host-name", "camera-host"},
                          {{"DISPLAY="}});

  nlohmann::json s = wait_state([](const nlohmann::json& j) {
    const auto* p = find_module(j, "camera-host", "prediction");
    const auto* b = find_module(j, "camera-host", "broken");
    return p && (*p)["state"] == "up" && b && (*b)["restarts"].get<int>() >= 1;
  }, 20s);
  INFO(s.dump(2) << "\nstatus: " << status.stderr_text() << "\nlaunch: " << launch.stderr_text());
  const nlohmann::json* prediction = find_module(s, "camera-host", "prediction");
  const nlohmann::json* broken = find_module(s, "camera-host", "broken");
  REQUIRE(prediction);
  REQUIRE(broken);
  // ok, or (once up 5 s without vision) a warning in its own words.
  CHECK(((*prediction)["level"] == "ok" || (*prediction)["status"].get<std::string>().rfind("no stacks for", 0) == 0));
  const int pid = (*prediction)["pid"].get<int>();
  REQUIRE(pid > 0);
  CHECK(::kill(pid, 0) == 0);  // the page's pid is the living process's
  CHECK((*broken)["last_exit"] == "exit code 1");
  CHECK(s["hosts"][0]["profile"] == "camera");
  CHECK(s["level"] != "ok");  // broken keeps failing
  bool said = false;
  for (const auto& p : s["problems"]) said = said || p.get<std::string>().rfind("broken: ", 0) == 0;
  CHECK(said);

  // Killed with -9: a warning on the page, then up again with one restart and a new pid.
  REQUIRE(::kill(pid, SIGKILL) == 0);
  nlohmann::json down = wait_state([](const nlohmann::json& j) {
    const auto* p = find_module(j, "camera-host", "prediction");
    return p && (*p)["level"] != "ok";
  }, 10s);
  const nlohmann::json* killed = find_module(down, "camera-host", "prediction");
  REQUIRE(killed);
  CHECK((*killed)["level"] == "warning");
  nlohmann::json back = wait_state([pid](const nlohmann::json& j) {
    const auto* p = find_module(j, "camera-host", "prediction");
    return p && (*p)["state"] == "up" && (*p)["pid"].get<int>() != pid;
  }, 15s);
  const nlohmann::json* again = find_module(back, "camera-host", "prediction");
  REQUIRE(again);
  CHECK((*again)["state"] == "up");
  CHECK((*again)["restarts"].get<int>() >= 1);
  CHECK((*again)["last_exit"].get<std::string>().find("signal 9") != std::string::npos);

  // The page itself, as a browser fetches it.
  httplib::Client client("127.0.0.1", kPort);
  auto page = client.Get("/");
  REQUIRE(page);
  CHECK(page->body.find("<title>Bricklayer status</title>") != std::string::npos);

  // The launcher stops: its host turns silent on the page.
  launch.stop();
  nlohmann::json silent = wait_state([](const nlohmann::json& j) {
    return !j["hosts"].empty() && j["hosts"][0]["silent"] == true;
  }, 15s);
  CHECK(silent["hosts"][0]["silent"] == true);
  CHECK(silent["level"] == "failed");
}
