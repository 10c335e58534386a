// NETNS, real processes, end to end: the shipped demo profile (headless) plays a whole round by itself.
// The scenario's first block appears on the empty board, a round starts without any key or command,
// runs the profile's 20 s while the player builds the 4-block optimum, and ends by time; the round
// book written by projection holds it with the optimum's score as MAX and its 4 blocks.
#include <catch2/catch.hpp>

#include <unistd.h>

#include <filesystem>
#include <fstream>
#include <sstream>

#include <nlohmann/json.hpp>

#include "bricklayer/launcher/process.h"
#include "../bus/bus_test_util.h"

using namespace bricklayer;
using namespace std::chrono_literals;
namespace fs = std::filesystem;

namespace {
std::string slurp(const fs::path& p) {
  std::ifstream in(p);
  std::stringstream s;
  s << in.rdbuf();
  return s.str();
}
}  // namespace

TEST_CASE("the demo plays a whole round by itself") {
  const fs::path dir = fs::temp_directory_path() / ("bricklayer-demo-round-" + std::to_string(::getpid()));
  fs::remove_all(dir);
  fs::create_directories(dir);
  nlohmann::json profile = nlohmann::json::parse(slurp(std::string(BRICKLAYER_SOURCE_DIR) + "/launch/profiles/demo.json"));
  profile["logger"]["file"] = (dir / "demo").string();
  bool has_book = false;
  for (auto& m : profile["modules"])
    for (auto& arg : m["command"]) {
      if (arg == "logs/snapshots") arg = (dir / "snapshots").string();
      if (arg == "logs/rounds.json") {
        arg = (dir / "rounds.json").string();
        has_book = true;
      }
    }
  REQUIRE(has_book);  // the shipped profile keeps a round book
  std::ofstream(dir / "demo.json") << profile.dump(1);

  launcher::SpawnOptions o;
  o.stdout_path = (dir / "launch.out").string();
  o.stderr_path = (dir / "launch.err").string();
  o.env = {"DISPLAY=", "SDL_AUDIODRIVER=dummy", std::string("LCM_DEFAULT_URL=") + test::kTestUrl};
  // The first block at 2 s of the scenario, the round 2 s later, 20 s long: over by about 25 s.
  auto launch = launcher::Process::spawn(
      {test::bin("bricklayer-launch"), "--root", BRICKLAYER_SOURCE_DIR, "--duration", "28", (dir / "demo.json").string()}, o);
  auto st = launch.wait_for(120s);
  REQUIRE(st);
  INFO(slurp(dir / "launch.out") << slurp(dir / "launch.err"));
  CHECK(st->clean());

  const nlohmann::json book = nlohmann::json::parse(slurp(dir / "rounds.json"));
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
  fs::remove_all(dir);
}
