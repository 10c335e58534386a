// Launch profiles: every shipped profile parses; mistakes are loud and say where.
#include "bricklayer/launcher/profile.h"

#include <catch2/catch.hpp>

#include <filesystem>

using namespace bricklayer::launcher;

namespace {
std::string error_of(const std::string& json) {
  try {
    parse_profile(json, "t");
  } catch (const ProfileError& e) {
    return e.what();
  }
  return "";
}
}  // namespace

TEST_CASE("every profile in launch/profiles parses") {
  int n = 0;
  for (const auto& entry : std::filesystem::directory_iterator(std::string(BRICKLAYER_SOURCE_DIR) + "/launch/profiles")) {
    if (entry.path().extension() != ".json") continue;
    INFO(entry.path());
    Profile p = load_profile(entry.path().string());
    CHECK_FALSE(p.modules.empty());
    CHECK(p.name == entry.path().stem().string());
    ++n;
  }
  CHECK(n >= 4);
  Profile demo = load_profile(std::string(BRICKLAYER_SOURCE_DIR) + "/launch/profiles/demo.json");
  CHECK(demo.headless_duration_s == 30);
  REQUIRE(demo.logger);
  bool projection_has_both = false;
  for (const auto& m : demo.modules)
    if (m.name == "projection") projection_has_both = !m.command.empty() && !m.command_with_display.empty();
  CHECK(projection_has_both);
}

TEST_CASE("a profile's defaults") {
  Profile p = parse_profile(R"({"modules":[{"name":"prediction","command":["bricklayer-prediction"]}]})", "t");
  REQUIRE(p.modules.size() == 1);
  CHECK(p.modules[0].heartbeat == "prediction");
  CHECK(p.modules[0].restart == RestartPolicy::kAlways);
  CHECK(p.modules[0].ready_timeout_s == 10);
  CHECK_FALSE(p.logger);
  CHECK(p.duration_s == 0);
  CHECK(p.stop_timeout_s == 5);
}

TEST_CASE("profile mistakes are loud and name the place") {
  CHECK(error_of("{").find("not valid JSON") != std::string::npos);
  CHECK(error_of(R"({"modules":[], "modulez":1})").find("unknown key 'modulez'") != std::string::npos);
  CHECK(error_of(R"({"modules":[{"name":"a"}]})").find("'a': 'command' is required") != std::string::npos);
  CHECK(error_of(R"({"modules":[{"name":"a","command":[]}]})").find("'command' is empty") != std::string::npos);
  CHECK(error_of(R"({"modules":[{"name":"a","command":["x"],"restart":"sometimes"}]})")
            .find("'sometimes' is not one of always, on-failure, never") != std::string::npos);
  CHECK(error_of(R"({"modules":[{"name":"a","command":["x"]},{"name":"a","command":["y"]}]})")
            .find("two modules are named 'a'") != std::string::npos);
  CHECK(error_of(R"({"modules":[{"name":"a","command":["x"],"ready_timeout_s":-1}]})").find("ready_timeout_s") !=
        std::string::npos);
  CHECK(error_of(R"({"modules":[{"name":"a","command":["x"],"env":["NOEQUALS"]}]})").find("NAME=value") !=
        std::string::npos);
  CHECK(error_of(R"({"modules":[{"name":"a","command":["x"]}],"logger":{"rotat":3}})").find("unknown key 'rotat'") !=
        std::string::npos);
  CHECK(error_of(R"({"modules":[]})").find("nothing to launch") != std::string::npos);
  CHECK_THROWS_AS(load_profile("/nonexistent/profile.json"), ProfileError);
}
