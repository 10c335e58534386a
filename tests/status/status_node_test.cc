// The node on the in-process rig, asked over real HTTP on loopback (the test binary runs in a private
// network namespace): /state.json follows the host states published on the bus, / is the page.
#include <httplib.h>

#include <catch2/catch.hpp>

#include <fstream>

#include "bricklayer/common/channels.h"
#include "bricklayer/launcher/supervisor.h"
#include "bricklayer/status/status_node.h"
#include "bricklayer/status/status_server.h"
#include "harness/rig.h"
#include "harness/scratch.h"

using namespace bricklayer;
using namespace std::chrono_literals;

namespace {
nlohmann::json get_state(int port) {
  httplib::Client client("127.0.0.1", port);
  auto res = client.Get("/state.json");
  REQUIRE(res);
  REQUIRE(res->status == 200);
  CHECK(res->get_header_value("Content-Type") == "application/json");
  return nlohmann::json::parse(res->body);
}
}  // namespace

TEST_CASE("the status node serves the host states published on the bus") {
  harness::Rig rig;
  status::StatusConfig config;
  config.port = 0;
  auto& node = rig.add<status::StatusNode>(config);
  REQUIRE(node.port() > 0);

  CHECK(get_state(node.port())["hosts"].empty());

  host_state_t hs{};
  hs.host = "camera-host";
  hs.profile = "camera";
  hs.status = "down: camera (restarting: exit code 1)";
  hs.modules.resize(2);
  hs.modules[0].name = "camera";
  hs.modules[0].state = module_state_t::STATE_RESTARTING;
  hs.modules[0].restarts = 3;
  hs.modules[0].last_exit = "exit code 1";
  hs.modules[1].name = "vision";
  hs.modules[1].state = module_state_t::STATE_UP;
  hs.modules[1].status = "no frames for 7 s";
  hs.num_modules = 2;
  hs.modules_up = 1;
  rig.publish(channel(launcher::kHostStateChannel), hs);
  round_t r{};
  r.state = round_t::STATE_ENDED;
  r.max_score = 275;
  rig.publish(channel(kRoundChannel), r);
  rig.step();

  nlohmann::json j = get_state(node.port());
  REQUIRE(j["hosts"].size() == 1);
  const nlohmann::json& h = j["hosts"][0];
  CHECK(h["host"] == "camera-host");
  CHECK(h["status"] == "down: camera (restarting: exit code 1)");
  CHECK(h["modules"][0]["state"] == "restarting");
  CHECK(h["modules"][0]["restarts"] == 3);
  CHECK(h["modules"][1]["status"] == "no frames for 7 s");
  CHECK(j["problems"][0] == "camera: restarting (it ended: exit code 1), restarted 3 times");
  CHECK(j["problems"][1] == "vision: no frames for 7 s");
  CHECK(j["round"]["state"] == "ended");
  CHECK(j["best_today"] == 275);

  // Garbage on the channel is a counted error, not a crash, and leaves the board as it was.
  const int64_t errors = node.counters().errors;
  rig.publish_bytes(channel(launcher::kHostStateChannel), {1, 2, 3});
  rig.step();
  CHECK(node.counters().errors == errors + 1);
  CHECK(get_state(node.port())["hosts"].size() == 1);

  // The launcher falls silent: the rig's clock, not the wall's, makes it so.
  rig.run_for(6s);
  j = get_state(node.port());
  CHECK(j["hosts"][0]["silent"] == true);
  CHECK(j["problems"].back().get<std::string>().rfind("camera-host is silent", 0) == 0);
  CHECK(node.status().rfind("no host states for", 0) == 0);

  httplib::Client client("127.0.0.1", node.port());
  auto page = client.Get("/");
  REQUIRE(page);
  CHECK(page->status == 200);
  CHECK(page->body.find("<title>Bricklayer status</title>") != std::string::npos);
  CHECK(page->body.find("state.json") != std::string::npos);
  auto missing = client.Get("/nothing");
  REQUIRE(missing);
  CHECK(missing->status == 404);
  CHECK(node.server().not_found() == 1);
}

TEST_CASE("an operator's action with the token is published on the bus at the node's time, one without it is refused and counted") {
  harness::Rig rig;
  harness::ScratchDir dir("status-actions");
  const std::string token = "fedcba9876543210fedcba9876543210";
  std::ofstream(dir / "token") << token << "\n";
  status::StatusConfig config;
  config.port = 0;
  config.token_file = (dir / "token").string();
  auto& node = rig.add<status::StatusNode>(config);
  auto& rec = rig.record({channel(kCommandChannel)});
  CHECK(get_state(node.port())["actions"] == true);

  httplib::Client client("127.0.0.1", node.port());
  const std::string restart = R"({"action":"restart","host":"camera-host","module":"vision"})";
  auto refused = client.Post("/action", restart, "application/json");
  REQUIRE(refused);
  CHECK(refused->status == 403);
  auto wrong = client.Post("/action", {{"X-Bricklayer-Token", "0000000000000000"}}, restart, "application/json");
  REQUIRE(wrong);
  CHECK(wrong->status == 403);
  auto bad = client.Post("/action", {{"X-Bricklayer-Token", token}}, "{\"action\":", "application/json");
  REQUIRE(bad);
  CHECK(bad->status == 400);
  auto done = client.Post("/action", {{"X-Bricklayer-Token", token}}, restart, "application/json");
  REQUIRE(done);
  CHECK(done->status == 200);
  CHECK(nlohmann::json::parse(done->body)["words"] == "vision on camera-host is restarted");

  rig.step();
  const auto sent = rec.all<command_t>(channel(kCommandChannel));
  REQUIRE(sent.size() == 1);  // only the accepted one
  CHECK(sent[0].command == command_t::RESTART_MODULE);
  CHECK(sent[0].argument == "camera-host/vision");
  CHECK(sent[0].utime >= rig.now() - 1000);  // the node's clock (the rig's), not the wall's
  CHECK(sent[0].utime <= rig.now());
  CHECK(sent[0].sequence == 1);
  CHECK(node.desk().accepted() == 1);
  CHECK(node.desk().refused() == 2);
  CHECK(node.desk().bad() == 1);
}

TEST_CASE("without a token file the page is read-only and says so") {
  harness::Rig rig;
  harness::ScratchDir dir("status-readonly");
  status::StatusConfig config;
  config.port = 0;
  config.token_file = (dir / "no-such-token").string();
  auto& node = rig.add<status::StatusNode>(config);
  auto& rec = rig.record({channel(kCommandChannel)});
  CHECK(get_state(node.port())["actions"] == false);
  httplib::Client client("127.0.0.1", node.port());
  auto res = client.Post("/action", {{"X-Bricklayer-Token", "anything-anything"}}, R"({"action":"reset_round"})",
                         "application/json");
  REQUIRE(res);
  CHECK(res->status == 503);
  rig.step();
  CHECK(rec.all<command_t>(channel(kCommandChannel)).empty());
  CHECK(node.desk().refused() == 1);
}

TEST_CASE("each module's row carries its own heartbeat's figures, found by its pid") {
  harness::Rig rig;
  status::StatusConfig config;
  config.port = 0;
  auto& node = rig.add<status::StatusNode>(config);
  host_state_t hs{};
  hs.host = "camera-host";
  hs.modules.resize(1);
  hs.modules[0].name = "camera";
  hs.modules[0].state = module_state_t::STATE_UP;
  hs.modules[0].pid = 4242;
  hs.num_modules = 1;
  hs.modules_up = 1;
  heartbeat_t hb{};
  hb.module = "simcam";
  hb.pid = 4242;
  hb.value_names = {"frames_per_s", "drop_ratio"};
  hb.values = {29.5, 0.0};
  hb.num_values = 2;
  heartbeat_t other = hb;
  other.pid = 99;
  other.values = {1.0, 1.0};
  rig.publish(channel(launcher::kHostStateChannel), hs);
  rig.publish(channel(kHeartbeatChannel), other);
  rig.publish(channel(kHeartbeatChannel), hb);
  rig.step();
  const nlohmann::json j = get_state(node.port());
  const nlohmann::json& f = j["hosts"][0]["modules"][0]["figures"];
  CHECK(f["frames_per_s"] == 29.5);
  CHECK(f["drop_ratio"] == 0.0);
  CHECK(f.size() == 2);
}

TEST_CASE("a port already in use is a clear error") {
  harness::Rig rig;
  status::StatusConfig config;
  config.port = 0;
  auto& first = rig.add<status::StatusNode>(config);
  config.port = first.port();
  CHECK_THROWS_WITH(rig.add<status::StatusNode>(config), Catch::Contains("cannot listen on 127.0.0.1:"));
}

TEST_CASE("a server destroyed right after it was built stops (its thread may not be listening yet)") {
  // Without the destructor waiting for the thread to listen, this hangs in its join (stop() came first).
  status::StatusBoard board;
  status::ActionDesk desk("");
  for (int i = 0; i < 50; ++i) {
    status::StatusServer server(board, desk, "127.0.0.1", 0);
    CHECK(server.port() > 0);
  }
}

namespace {
image_t image_of(const std::string& bytes, int32_t format, const std::string& source, int64_t frame) {
  image_t im{};
  im.frame_number = frame;
  im.width = 4;
  im.height = 2;
  im.format = format;
  im.source = source;
  im.data.assign(bytes.begin(), bytes.end());
  im.size = static_cast<int32_t>(im.data.size());
  return im;
}
}  // namespace

TEST_CASE("/camera.jpg and /projector.jpg serve the latest image's bytes, 404 before any") {
  harness::Rig rig;
  status::StatusConfig config;
  config.port = 0;
  auto& node = rig.add<status::StatusNode>(config);
  httplib::Client client("127.0.0.1", node.port());
  for (const char* path : {"/camera.jpg", "/projector.jpg"}) {
    auto res = client.Get(path);
    REQUIRE(res);
    CHECK(res->status == 404);
    CHECK(res->body.rfind("no ", 0) == 0);
  }
  nlohmann::json j = get_state(node.port());
  CHECK(j["camera"]["seen"] == false);
  CHECK(j["projector"]["seen"] == false);

  // The bytes are not decoded, so any bytes do: the page gets exactly the newest ones.
  rig.publish(channel(kImageChannel), image_of("first camera bytes", image_t::FORMAT_JPEG, "/dev/video0", 1));
  rig.publish(channel(kImageChannel), image_of("second camera bytes", image_t::FORMAT_JPEG, "/dev/video0", 2));
  rig.publish(channel(kProjectorImageChannel), image_of("projector png bytes", image_t::FORMAT_PNG, "projector", 7));
  rig.step();
  auto cam = client.Get("/camera.jpg");
  REQUIRE(cam);
  CHECK(cam->status == 200);
  CHECK(cam->body == "second camera bytes");
  CHECK(cam->get_header_value("Content-Type") == "image/jpeg");
  auto proj = client.Get("/projector.jpg");
  REQUIRE(proj);
  CHECK(proj->status == 200);
  CHECK(proj->body == "projector png bytes");
  CHECK(proj->get_header_value("Content-Type") == "image/png");

  rig.run_for(3s);
  j = get_state(node.port());
  CHECK(j["camera"]["seen"] == true);
  CHECK(j["camera"]["frame_number"] == 2);
  CHECK(j["camera"]["age_s"].get<double>() >= 3.0);
  CHECK(j["projector"]["source"] == "projector");

  // A malformed image (a raw 4x2 BGR frame of 5 bytes) is a counted error and the previous one stays.
  const int64_t errors = node.counters().errors;
  rig.publish(channel(kImageChannel), image_of("12345", image_t::FORMAT_BGR8, "/dev/video0", 3));
  rig.step();
  CHECK(node.counters().errors == errors + 1);
  CHECK(client.Get("/camera.jpg")->body == "second camera bytes");

  // A raw frame is encoded to a JPEG that decodes to its size.
  image_t raw = image_of(std::string(4 * 2 * 3, '\x80'), image_t::FORMAT_BGR8, "simcam:test", 4);
  rig.publish(channel(kImageChannel), raw);
  rig.step();
  auto enc = client.Get("/camera.jpg");
  REQUIRE(enc);
  CHECK(enc->status == 200);
  CHECK(enc->get_header_value("Content-Type") == "image/jpeg");
  REQUIRE(enc->body.size() > 3);
  CHECK(static_cast<unsigned char>(enc->body[0]) == 0xFF);
  CHECK(static_cast<unsigned char>(enc->body[1]) == 0xD8);
  // Asked again within the second: the same encoding, not a new one.
  CHECK(client.Get("/camera.jpg")->body == enc->body);
  CHECK(node.camera().encodings() == 1);
}

TEST_CASE("the round's display condition is on the page's JSON") {
  harness::Rig rig;
  status::StatusConfig config;
  config.port = 0;
  auto& node = rig.add<status::StatusNode>(config);
  round_t r{};
  r.condition = 2;
  rig.publish(channel(kRoundChannel), r);
  rig.step();
  CHECK(get_state(node.port())["round"]["condition"] == "red");
}

TEST_CASE("calibrate: with the token one CALIBRATE on the bus, without it refused and nothing sent") {
  harness::Rig rig;
  harness::ScratchDir dir("status-calibrate");
  const std::string token = "fedcba9876543210fedcba9876543210";
  std::ofstream(dir / "token") << token << "\n";
  status::StatusConfig config;
  config.port = 0;
  config.token_file = (dir / "token").string();
  auto& node = rig.add<status::StatusNode>(config);
  auto& rec = rig.record({channel(kCommandChannel)});
  httplib::Client client("127.0.0.1", node.port());
  const std::string calibrate = R"({"action":"calibrate"})";
  auto none = client.Post("/action", calibrate, "application/json");
  REQUIRE(none);
  CHECK(none->status == 403);
  auto wrong = client.Post("/action", {{"X-Bricklayer-Token", token.substr(1) + "0"}}, calibrate, "application/json");
  REQUIRE(wrong);
  CHECK(wrong->status == 403);
  rig.step();
  CHECK(rec.all<command_t>(channel(kCommandChannel)).empty());
  CHECK(node.desk().refused() == 2);

  auto done = client.Post("/action", {{"X-Bricklayer-Token", token}}, calibrate, "application/json");
  REQUIRE(done);
  CHECK(done->status == 200);
  CHECK(nlohmann::json::parse(done->body)["words"].get<std::string>().rfind("the calibration starts once the board", 0) == 0);
  rig.step();
  const auto sent = rec.all<command_t>(channel(kCommandChannel));
  REQUIRE(sent.size() == 1);
  CHECK(sent[0].command == command_t::CALIBRATE);
  CHECK(sent[0].utime <= rig.now());
  CHECK(node.desk().accepted() == 1);
}

TEST_CASE("the serving calibrate node's heartbeat is the page's calibration line, a one-off run's is not") {
  harness::Rig rig;
  status::StatusConfig config;
  config.port = 0;
  auto& node = rig.add<status::StatusNode>(config);
  CHECK(get_state(node.port())["calibration"].is_null());
  heartbeat_t serving{};
  serving.module = "calibrate";
  serving.pid = 500;
  serving.status = "calibrating: step 2 of 6: projector blue";
  serving.value_names = {"calibration_age_s", "calibrations_done", "calibrations_failed"};
  serving.values = {3600.0, 1.0, 0.0};
  serving.num_values = 3;
  heartbeat_t one_off{};
  one_off.module = "calibrate";
  one_off.pid = 501;
  one_off.status = "step 5 of 6: marker set 0";
  rig.publish(channel(kHeartbeatChannel), serving);
  rig.publish(channel(kHeartbeatChannel), one_off);
  rig.step();
  nlohmann::json c = get_state(node.port())["calibration"];
  CHECK(c["status"] == "calibrating: step 2 of 6: projector blue");
  CHECK(c["figures"]["calibration_age_s"] == 3600.0);
  CHECK(c["figures"]["calibrations_done"] == 1.0);
  CHECK(c["age_s"].get<double>() < 0.1);
  rig.run_for(2s);
  CHECK(get_state(node.port())["calibration"]["age_s"].get<double>() >= 2.0);  // the rig's clock
}
