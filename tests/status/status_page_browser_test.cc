// NETNS, real processes and a real browser: a real bricklayer-launch and bricklayer-status, the page
// opened in Debian's headless Chromium (modules/status/js/status_page_check.mjs, playwright-core). The
// page loads with no console errors, shows the camera frame and projector image published on the bus, each module's state and the problems in words; a module
// killed with -9 turns to a warning on the page and back to ok. The operator's controls pressed in the
// browser: "Set" with the condition red reaches the real bricklayer-projection (the page then shows red
// from its round_t), "Calibrate now" asks for a confirmation (dismissed: nothing sent; accepted: one
// CALIBRATE on the bus) and the real bricklayer-calibrate --serve's answer shows on the calibration line.
// The screenshot it takes is the one in the README (build/test-output/status/status-page.png, copied to
// docs/status-page.png).
#include <signal.h>

#include <httplib.h>

#include <catch2/catch.hpp>

#include <atomic>
#include <filesystem>
#include <fstream>
#include <mutex>
#include <thread>

#include <lcm/lcm-cpp.hpp>
#include <nlohmann/json.hpp>
#include <opencv2/imgcodecs.hpp>
#include <opencv2/imgproc.hpp>

#include "bricklayer/command_t.hpp"
#include "bricklayer/common/channels.h"
#include "bricklayer/image_t.hpp"

#include "bricklayer/launcher/process.h"
#include "harness/program.h"
#include "harness/scratch.h"

using namespace bricklayer;
using namespace std::chrono_literals;
namespace fs = std::filesystem;
using nlohmann::json;

namespace {
constexpr const char* kUrl = "udpm://239.255.76.67:7667?ttl=0";
constexpr int kPort = 18081;
const std::string kScript = std::string(BRICKLAYER_SOURCE_DIR) + "/modules/status/js/status_page_check.mjs";
const std::string kPage = "http://127.0.0.1:" + std::to_string(kPort) + "/";

// The prediction module's pid once the status page shows it up (0 if it never does).
int prediction_pid_when_up(std::chrono::seconds timeout) {
  const auto end = std::chrono::steady_clock::now() + timeout;
  while (std::chrono::steady_clock::now() < end) {
    httplib::Client client("127.0.0.1", kPort);
    if (auto res = client.Get("/state.json"); res && res->status == 200) {
      const json j = json::parse(res->body);
      for (const auto& h : j["hosts"])
        for (const auto& m : h["modules"])
          if (m["name"] == "prediction" && m["state"] == "up") return m["pid"].get<int>();
    }
    std::this_thread::sleep_for(200ms);
  }
  return 0;
}

// What a program wrote on stderr so far; "" until the child has opened the file (just after the spawn).
std::string stderr_of(const harness::Program& p) {
  try {
    return p.stderr_text();
  } catch (const std::exception&) {
    return "";
  }
}

// A test picture as a JPEG image_t: a grey board with a pile of coloured blocks (camera), or the
// projector's black with the blocks in the game's blue; drawn here, as no camera runs in this test.
image_t picture(int width, int height, bool projector, const std::string& source) {
  cv::Mat m(height, width, CV_8UC3, projector ? cv::Scalar(0, 0, 0) : cv::Scalar(150, 150, 150));
  const int bw = width / 4, bh = height / 10;
  for (int i = 0; i < 4; ++i) {
    const cv::Point corner(width / 4 + i * bw / 3, height - (i + 2) * bh);
    cv::rectangle(m, corner, corner + cv::Point(bw, bh - 2),
                  projector ? cv::Scalar(230, 120, 30) : cv::Scalar(40, 40 + 50 * i, 200), cv::FILLED);
  }
  image_t im{};
  cv::imencode(".jpg", m, im.data);
  im.width = width;
  im.height = height;
  im.format = image_t::FORMAT_JPEG;
  im.source = source;
  im.size = static_cast<int32_t>(im.data.size());
  return im;
}

// Every command_t on BL_COMMAND while it lives (its own thread: the test's other waits block).
class CommandListener {
 public:
  CommandListener() : bus_(kUrl) {
    REQUIRE(bus_.good());
    bus_.subscribe(channel(kCommandChannel), &CommandListener::on_command, this);
    thread_ = std::thread([this] {
      while (!stop_) bus_.handleTimeout(100);
    });
  }
  ~CommandListener() {
    stop_ = true;
    thread_.join();
  }
  std::vector<command_t> commands() {
    std::lock_guard lock(mutex_);
    return commands_;
  }

 private:
  void on_command(const lcm::ReceiveBuffer*, const std::string&, const command_t* c) {
    std::lock_guard lock(mutex_);
    commands_.push_back(*c);
  }
  lcm::LCM bus_;
  std::atomic<bool> stop_{false};
  std::mutex mutex_;
  std::vector<command_t> commands_;
  std::thread thread_;
};

json row(const json& result, const std::string& module) {
  for (const auto& r : result.at("rows"))
    if (r.at("module") == module) return r;
  return nullptr;
}
}  // namespace

TEST_CASE("the status page in Chromium: no console errors, the modules' states, a kill -9 and the recovery") {
  const std::string node = launcher::find_program("node", "", {});
  REQUIRE_FALSE(node.empty());
  REQUIRE(fs::exists("/usr/bin/chromium"));
  harness::ScratchDir dir("status-browser");
  std::ofstream(dir / "camera.json") << R"({"modules":[
      {"name":"prediction","command":["bricklayer-prediction","--log-level","warn"]},
      {"name":"broken","command":["/bin/false"],"heartbeat":"broken","backoff_max_s":0.3},
      {"name":"projection","command":["bricklayer-projection","--headless","--mute","--fps","10","--log-level","warn"]},
      {"name":"calibrate","command":["bricklayer-calibrate","--serve","--output","calibration.json","--log-level","warn"]}]})";
  const std::string token = "0123456789abcdef0123456789abcdef";
  std::ofstream(dir / "token") << token << "\n";
  harness::Program status("bricklayer-status", {"--lcm-url", kUrl, "--port", std::to_string(kPort), "--token-file",
                                                (dir / "token").string()});
  harness::Program launch("bricklayer-launch",
                          {"--root", dir.str(), "--bin-dir", std::string(BRICKLAYER_BINARY_DIR) + "/bin", "--lcm-url", kUrl,
                           (dir / "camera.json").string(), "--host-name", "camera-host"},
                          harness::ProgramOptions{{"DISPLAY="}, ""});
  const int pid = prediction_pid_when_up(20s);
  INFO("status: " << status.stderr_text() << "\nlaunch: " << launch.stderr_text());
  REQUIRE(pid > 0);

  // A camera frame and a projector image on the bus, until the status page says it has both.
  {
    lcm::LCM bus(kUrl);
    REQUIRE(bus.good());
    image_t camera = picture(640, 360, false, "/dev/video0");
    image_t projector = picture(320, 180, true, "projector");
    bool seen = false;
    for (int i = 0; i < 50 && !seen; ++i) {
      camera.frame_number = projector.frame_number = i;
      bus.publish(channel(kImageChannel), &camera);
      bus.publish(channel(kProjectorImageChannel), &projector);
      std::this_thread::sleep_for(100ms);
      httplib::Client client("127.0.0.1", kPort);
      if (auto res = client.Get("/state.json"); res && res->status == 200) {
        const json j = json::parse(res->body);
        seen = j["camera"]["seen"] == true && j["projector"]["seen"] == true;
      }
    }
    REQUIRE(seen);
  }

  const fs::path out_dir = fs::path(BRICKLAYER_BINARY_DIR) / "test-output" / "status";
  fs::create_directories(out_dir);
  const fs::path shot = out_dir / "status-page.png";
  fs::remove(shot);
  harness::Ran page = harness::run_program(node, {kScript, kPage, "--screenshot", shot.string(), "--images"}, 60s);
  INFO(page.err);
  REQUIRE(page.status.code == 0);
  const json result = json::parse(page.out);
  INFO(page.out);
  CHECK(result.at("title") == "Bricklayer status");
  CHECK(result.at("console").empty());
  CHECK(result.at("errors").empty());
  CHECK(result.at("failed_requests").empty());
  // Both images loaded (a broken image has natural width 0), captioned with their source.
  CHECK(result.at("images").at("camera").at("natural_width") == 640);
  CHECK(result.at("images").at("projector").at("natural_width") == 320);
  CHECK(result.at("images").at("camera").at("caption").get<std::string>().rfind("Camera frame from ", 0) == 0);
  CHECK(result.at("images").at("projector").at("caption").get<std::string>().find("projector)") != std::string::npos);
  const json prediction = row(result, "prediction");
  REQUIRE(prediction.is_object());
  CHECK(prediction.at("cells").at(1) == "up");
  // Up; ok while its own status is, else a warning in its own words (prediction says "no stacks for
  // N s" once it has been up 5 s without vision, as here).
  if (prediction.at("cells").at(4) == "ok") {
    CHECK(prediction.at("level") == "ok");
  } else {
    CHECK(prediction.at("level") == "warning");
    CHECK(prediction.at("cells").at(4).get<std::string>().rfind("no stacks for", 0) == 0);
  }
  const json broken = row(result, "broken");
  REQUIRE(broken.is_object());
  CHECK(broken.at("level") == "warning");
  CHECK(result.at("overall") == "Something needs a look.");
  bool said = false;
  // Between its restarts the failing module is starting or restarting: either way, said.
  for (const auto& p : result.at("problems")) said = said || p.get<std::string>().rfind("broken: ", 0) == 0;
  CHECK(said);
  REQUIRE(fs::exists(shot));
  CHECK(fs::file_size(shot) > 10000);

  // The operator's controls, in the browser, with the token: the display condition red reaches the real
  // projection (the page shows red once projection's round_t says so); "Calibrate now" asks first
  // (dismissed: no request), then sends CALIBRATE, and the calibrate node's answer (no board state: no
  // vision runs here) is on the calibration line.
  {
    CommandListener listener;
    harness::Ran pressed = harness::run_program(
        node, {kScript, kPage, "--set-condition", "red", "--calibrate", "--token", token, "--calibration-shows",
               "calibration waits for an empty board", "--timeout-s", "30"},
        60s);
    INFO(pressed.err);
    REQUIRE(pressed.status.code == 0);
    const json r = json::parse(pressed.out);
    INFO(pressed.out);
    CHECK(r.at("set_condition") == "Done: the display condition is red from now on");
    CHECK(r.at("condition_after") == "red");
    REQUIRE(r.at("dialogs").size() == 3);
    CHECK(r.at("dialogs")[0].get<std::string>().rfind("Calibrate now? The board must be empty", 0) == 0);
    CHECK(r.at("posts_after_dismiss") == 1);  // the condition's only: the dismissed confirmation sent nothing
    CHECK(r.at("dialogs")[2].get<std::string>().rfind("Correct the board scale now? Three or more blocks", 0) == 0);
    CHECK(r.at("action_posts") == 3);
    CHECK(r.at("calibrate").get<std::string>().rfind("Done: the calibration starts once the board", 0) == 0);
    CHECK(r.at("calibration_line").get<std::string>().rfind(
              "Calibration: calibration waits for an empty board: clear the board", 0) == 0);
    CHECK(r.at("scale") == "Done: the board scale is measured from the blocks on the bottom row now (see Calibration)");
    CHECK(r.at("console").empty());
    CHECK(r.at("errors").empty());
    // On the bus: the condition (index 2, red), exactly one CALIBRATE for a full calibration and one for
    // the scale step, all from the status page.
    const auto end = std::chrono::steady_clock::now() + 10s;
    auto count = [&](int32_t code) {
      int n = 0;
      for (const command_t& c : listener.commands()) n += c.command == code;
      return n;
    };
    while (count(command_t::CALIBRATE) < 2 && std::chrono::steady_clock::now() < end) std::this_thread::sleep_for(50ms);
    int full = 0, scale = 0;
    for (const command_t& c : listener.commands()) {
      full += c.command == command_t::CALIBRATE && c.argument.empty();
      scale += c.command == command_t::CALIBRATE && c.argument == "scale-from-blocks";
    }
    CHECK(full == 1);
    CHECK(scale == 1);
    int red = 0;
    for (const command_t& c : listener.commands()) red += c.command == command_t::SET_CONDITION && c.index == 2;
    CHECK(red == 1);
  }

  // Watching the page while prediction is killed with -9: up, then restarting or starting (a warning),
  // then up again.
  harness::Program watch(node, {kScript, kPage, "--watch", "prediction", "--timeout-s", "40"});
  const auto end = std::chrono::steady_clock::now() + 30s;
  while (stderr_of(watch).find("watching") == std::string::npos && watch.running() && std::chrono::steady_clock::now() < end)
    std::this_thread::sleep_for(100ms);
  REQUIRE(stderr_of(watch).find("watching") != std::string::npos);
  REQUIRE(::kill(pid, SIGKILL) == 0);
  const auto ended = watch.wait_exit(60s);
  REQUIRE(ended);
  INFO(watch.stderr_text());
  CHECK(ended->code == 0);
  const json watched = json::parse(watch.stdout_text());
  INFO(watched.dump());
  const json& t = watched.at("transitions");
  REQUIRE(t.size() >= 2);
  CHECK(t.front().at("state") == "up");
  CHECK(t.back().at("state") == "up");
  for (const auto& e : t) {  // while it was not up, a warning (its "no stacks" warning may come before)
    if (e.at("state") == "up") continue;
    CHECK((e.at("state") == "restarting" || e.at("state") == "starting"));
    CHECK(e.at("level") == "warning");
  }
  // The page polls once a second and the launcher publishes once a second: a quick restart may show
  // only as the restart count going up, with a new pid.
  CHECK(t.back().at("restarts").get<int>() > t.front().at("restarts").get<int>());
  CHECK(watched.at("errors").empty());
  CHECK(watched.at("console").empty());
  const json again = row(watched, "prediction");
  REQUIRE(again.is_object());
  CHECK(again.at("cells").at(2) != "0");  // restarts

  // The operator's restart button: refused with a wrong token (nothing happens), done with the right one:
  // the launcher stops prediction and starts it again, the page sees the restart count go up.
  const int before = prediction_pid_when_up(20s);
  REQUIRE(before > 0);
  harness::Ran pressed = harness::run_program(
      node, {kScript, kPage, "--restart", "prediction", "--token", token, "--wrong-token", "not-the-token-at-all",
             "--timeout-s", "40"},
      60s);
  INFO(pressed.err);
  REQUIRE(pressed.status.code == 0);
  const json r = json::parse(pressed.out);
  INFO(pressed.out << "\nlaunch: " << launch.stderr_text() << launch.stdout_text());
  CHECK(r.at("refused") == "Not done: wrong token: nothing was done");
  CHECK(r.at("action") == "Done: prediction on camera-host is restarted");
  const json& rt = r.at("transitions");
  REQUIRE(rt.size() >= 2);
  CHECK(rt.back().at("state") == "up");
  CHECK(rt.back().at("restarts").get<int>() == rt.front().at("restarts").get<int>() + 1);
  CHECK(r.at("errors").empty());
  // The browser itself reports the refused request (a 403) in the console, and nothing else is there.
  REQUIRE(r.at("console").size() == 1);
  CHECK(r.at("console")[0].at("text").get<std::string>().find("status of 403 (Forbidden)") != std::string::npos);
  const int after = prediction_pid_when_up(20s);
  CHECK(after > 0);
  CHECK(after != before);
  CHECK(::kill(before, 0) != 0);  // the old process is gone
  // The page's requests: one refused (wrong token), one accepted; the status program counts them.
  httplib::Client client("127.0.0.1", kPort);
  auto res = client.Post("/action", R"({"action":"reset_round"})", "application/json");
  REQUIRE(res);
  CHECK(res->status == 403);
}
