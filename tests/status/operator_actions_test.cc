// The operator's actions without a network: which requests become which command, which are refused,
// and how the token file is read.
#include <catch2/catch.hpp>

#include <fstream>
#include <stdexcept>

#include "bricklayer/status/operator_actions.h"
#include "bricklayer/study_session_t.hpp"
#include "harness/scratch.h"

using namespace bricklayer;
using namespace bricklayer::status;

namespace {
const std::string kToken = "0123456789abcdef0123456789abcdef";
}

TEST_CASE("each action becomes the command its module obeys") {
  struct Case {
    std::string body;
    int32_t command;
    std::string argument;
  };
  const Case cases[] = {
      {R"({"action":"start_round"})", command_t::START_ROUND, ""},
      {R"({"action":"reset_round"})", command_t::RESET_ROUND, ""},
      {R"({"action":"check_calibration"})", command_t::SELF_CHECK, ""},
      {R"({"action":"calibrate"})", command_t::CALIBRATE, ""},
      {R"({"action":"calibrate","step":"scale-from-blocks"})", command_t::CALIBRATE, "scale-from-blocks"},
      {R"({"action":"mark_moment","note":"a child cried at the board"})", command_t::MARK_MOMENT, "a child cried at the board"},
      {R"({"action":"mark_moment"})", command_t::MARK_MOMENT, "marked on the status page"},
      {R"({"action":"restart","host":"camera-host","module":"vision"})", command_t::RESTART_MODULE, "camera-host/vision"},
  };
  for (const Case& c : cases) {
    INFO(c.body);
    const ActionAnswer a = decide_action(c.body, kToken, kToken);
    CHECK(a.http_status == 200);
    REQUIRE(a.command);
    CHECK(a.command->command == c.command);
    CHECK(a.command->argument == c.argument);
    CHECK_FALSE(a.words.empty());
  }
}

TEST_CASE("set_condition sends SET_CONDITION with the condition's index, any other condition is a bad request") {
  const std::pair<const char*, int32_t> conditions[] = {
      {"blue", study_session_t::CONDITION_BLUE}, {"red", study_session_t::CONDITION_RED},
      {"proposed", study_session_t::CONDITION_PROPOSED}};
  for (const auto& [word, index] : conditions) {
    INFO(word);
    const ActionAnswer a = decide_action(std::string(R"({"action":"set_condition","condition":")") + word + "\"}",
                                         kToken, kToken);
    CHECK(a.http_status == 200);
    REQUIRE(a.command);
    CHECK(a.command->command == command_t::SET_CONDITION);
    CHECK(a.command->index == index);
    CHECK(a.words == std::string("the display condition is ") + word + " from now on");
  }
  for (const std::string body : {R"({"action":"set_condition"})", R"({"action":"set_condition","condition":"green"})",
                                 R"({"action":"set_condition","condition":3})",
                                 R"({"action":"set_condition","condition":"Blue"})"}) {
    INFO(body);
    const ActionAnswer a = decide_action(body, kToken, kToken);
    CHECK(a.http_status == 400);
    CHECK_FALSE(a.command);
    CHECK(a.words.rfind("the display condition is blue, red or proposed", 0) == 0);
  }
  // Through the desk, a bad value is counted as bad and nothing is queued.
  ActionDesk desk(kToken);
  CHECK(desk.take(R"({"action":"set_condition","condition":"green"})", kToken).http_status == 400);
  CHECK(desk.take(R"({"action":"set_condition","condition":"red"})", kToken).http_status == 200);
  const auto queued = desk.drain();
  REQUIRE(queued.size() == 1);
  CHECK(queued[0].index == study_session_t::CONDITION_RED);
  CHECK(desk.bad() == 1);
  CHECK(desk.accepted() == 1);
}

TEST_CASE("no token, a wrong token, or no token file: refused, and nothing to publish") {
  const std::string body = R"({"action":"restart","host":"camera-host","module":"vision"})";
  ActionAnswer a = decide_action(body, "", kToken);
  CHECK(a.http_status == 403);
  CHECK_FALSE(a.command);
  CHECK(a.words == "this action needs the operator's token");
  a = decide_action(body, kToken.substr(0, 31) + "0", kToken);
  CHECK(a.http_status == 403);
  CHECK(a.words == "wrong token: nothing was done");
  a = decide_action(body, kToken + "x", kToken);  // a longer guess that starts right
  CHECK(a.http_status == 403);
  a = decide_action(body, kToken, "");  // this machine has no token: actions are off, whatever is sent
  CHECK(a.http_status == 503);
  CHECK_FALSE(a.command);
}

TEST_CASE("malformed requests with the right token are bad requests, never a crash") {
  for (const std::string body : {"", "not json", "[]", R"({"action":7})", R"({"action":"format_disk"})",
                                 R"({"action":"restart","module":"vision"})",
                                 R"({"action":"restart","host":"a/b","module":"vision"})",
                                 R"({"action":"restart","host":"camera-host","module":""})",
                                 R"({"action":"calibrate","step":"everything"})"}) {
    INFO(body);
    const ActionAnswer a = decide_action(body, kToken, kToken);
    CHECK(a.http_status == 400);
    CHECK_FALSE(a.command);
    CHECK_FALSE(a.words.empty());
  }
  // A long note is cut, not refused.
  const ActionAnswer a = decide_action(R"({"action":"mark_moment","note":")" + std::string(500, 'x') + "\"}", kToken, kToken);
  REQUIRE(a.command);
  CHECK(a.command->argument.size() == 200);
}

TEST_CASE("the desk counts what it accepts, refuses and finds bad, and hands the commands over in order") {
  ActionDesk desk(kToken);
  CHECK(desk.enabled());
  desk.take(R"({"action":"start_round"})", kToken);
  desk.take(R"({"action":"reset_round"})", "wrong-token-wrong-token");
  desk.take("{", kToken);
  desk.take(R"({"action":"mark_moment","note":"n"})", kToken);
  CHECK(desk.accepted() == 2);
  CHECK(desk.refused() == 1);
  CHECK(desk.bad() == 1);
  const auto commands = desk.drain();
  REQUIRE(commands.size() == 2);
  CHECK(commands[0].command == command_t::START_ROUND);
  CHECK(commands[1].command == command_t::MARK_MOMENT);
  CHECK(desk.drain().empty());

  // A node that stopped draining: the queue stops at its bound, the rest is refused as busy.
  for (size_t i = 0; i < ActionDesk::kMaxQueued + 5; ++i) desk.take(R"({"action":"start_round"})", kToken);
  CHECK(desk.drain().size() == ActionDesk::kMaxQueued);

  ActionDesk off("");
  CHECK_FALSE(off.enabled());
  CHECK(off.take(R"({"action":"start_round"})", kToken).http_status == 503);
  CHECK(off.refused() == 1);
}

TEST_CASE("the token file: missing or empty means read-only, a short token is refused, white space is trimmed") {
  harness::ScratchDir dir("status-token");
  CHECK(load_token((dir / "absent").string()).empty());
  CHECK(load_token("").empty());
  std::ofstream(dir / "empty") << "\n";
  CHECK(load_token((dir / "empty").string()).empty());
  std::ofstream(dir / "short") << "abc123\n";
  CHECK_THROWS_AS(load_token((dir / "short").string()), std::runtime_error);
  std::ofstream(dir / "good") << "  " << kToken << "  \nsecond line ignored\n";
  CHECK(load_token((dir / "good").string()) == kToken);
}
