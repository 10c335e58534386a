// NETNS, real processes, end to end: the shipped demo profile (headless) plays a whole round by itself.
// The scenario's first block appears on the empty board, a round starts without any key or command,
// runs the profile's 20 s while the player builds the 4-block optimum, and ends by time; the round
// book written by projection holds it with the optimum's score as MAX and its 4 blocks.
#include <catch2/catch.hpp>

#include <filesystem>

#include <nlohmann/json.hpp>

#include "harness/demo_profile.h"
#include "harness/live_bus.h"
#include "harness/program.h"
#include "harness/scratch.h"

using namespace bricklayer;
using namespace std::chrono_literals;
namespace fs = std::filesystem;

TEST_CASE("the demo plays a whole round by itself") {
  harness::ScratchDir dir("demo-round");
  const harness::DemoProfile demo = harness::scratch_demo_profile(dir);
  REQUIRE(demo.has_round_book);  // the shipped profile keeps a round book

  // The first block at 2 s of the scenario, the round 2 s later, 20 s long: over by about 25 s.
  const harness::Ran launch = harness::run_program(
      "bricklayer-launch", {"--root", BRICKLAYER_SOURCE_DIR, "--duration", "28", demo.file.string()}, 120s,
      harness::ProgramOptions{{"DISPLAY=", "SDL_AUDIODRIVER=dummy", std::string("LCM_DEFAULT_URL=") + harness::kLiveUrl}, ""});
  REQUIRE_FALSE(launch.timed_out);
  INFO(launch.out << launch.err);
  CHECK(launch.status.clean());

  const nlohmann::json book = nlohmann::json::parse(harness::read_file(dir / "rounds.json"));
  INFO(book.dump(1));
  REQUIRE(book["rounds"].size() >= 1);
  const nlohmann::json& round = book["rounds"][0];
  CHECK(round["end"] == "time up");
  CHECK(round["end_utime"].get<int64_t>() - round["start_utime"].get<int64_t>() == 20'000'000);
  // launch/scenarios/build-4-optimum.json: the balanced 4-block optimum reaches 1.16789 beyond the edge.
  CHECK(round["max_score"].get<int>() >= 110);
  CHECK(round["max_score"].get<int>() <= 125);
  CHECK(round["blocks"] == 4);
  CHECK(round["most_blocks"] == 4);
}
