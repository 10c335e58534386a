// NETNS, real processes, end to end: the demo profile (simcam -> vision -> prediction -> projection,
// bricklayer-logger) runs headless under bricklayer-launch, stops by itself, and its bus log replays through
// bricklayer-replay --module vision,prediction --check with 0 mismatches. Only built when every module of the demo is.
#include <catch2/catch.hpp>

#include <unistd.h>

#include <filesystem>
#include <fstream>
#include <regex>
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

TEST_CASE("the demo profile runs headless, stops by itself, and its log replays with 0 mismatches") {
  const fs::path dir = fs::temp_directory_path() / ("bricklayer-demo-" + std::to_string(::getpid()));
  fs::remove_all(dir);
  fs::create_directories(dir);
  // The shipped profile, with the log and the snapshots in a temporary folder instead of logs/.
  nlohmann::json profile = nlohmann::json::parse(slurp(std::string(BRICKLAYER_SOURCE_DIR) + "/launch/profiles/demo.json"));
  profile["logger"]["file"] = (dir / "demo").string();
  for (auto& m : profile["modules"])
    for (auto& arg : m["command"])
      if (arg == "logs/snapshots") arg = (dir / "snapshots").string();
      else if (arg == "logs/rounds.json") arg = (dir / "rounds.json").string();
  std::ofstream(dir / "demo.json") << profile.dump(1);

  launcher::SpawnOptions o;
  o.stdout_path = (dir / "launch.out").string();
  o.stderr_path = (dir / "launch.err").string();
  o.env = {"DISPLAY=", "SDL_AUDIODRIVER=dummy", std::string("LCM_DEFAULT_URL=") + test::kTestUrl};
  auto launch = launcher::Process::spawn(
      {test::bin("bricklayer-launch"), "--root", BRICKLAYER_SOURCE_DIR, "--duration", "8", (dir / "demo.json").string()}, o);
  auto st = launch.wait_for(60s);
  REQUIRE(st);
  std::string out = slurp(dir / "launch.out");
  INFO(out << slurp(dir / "launch.err"));
  CHECK(st->clean());
  CHECK(out.find("all 5 processes of profile demo are up") != std::string::npos);
  CHECK(out.find("duration of 8.0 s reached") != std::string::npos);
  CHECK(out.find("died") == std::string::npos);
  // The summary line of the prediction: restarts 0 and some stacks answered.
  std::smatch m;
  REQUIRE(std::regex_search(out, m, std::regex(R"(\n  prediction +(\d+) +(\d+) +(\d+) +(\d+) +(\d+))")));
  CHECK(m[1] == "0");
  CHECK(std::stoi(m[3]) > 10);
  CHECK(m[5] == "0");
  CHECK(fs::exists(dir / "snapshots" / "latest.png"));

  REQUIRE(fs::exists(dir / "demo.00"));
  launcher::SpawnOptions ro;
  ro.stdout_path = (dir / "replay.out").string();
  // Vision (from the recorded frames, projector images and its late start) and prediction on its stacks.
  auto replay = launcher::Process::spawn(
      {test::bin("bricklayer-replay"), (dir / "demo.00").string(), "--module", "vision,prediction", "--check"}, ro);
  auto rst = replay.wait_for(60s);
  REQUIRE(rst);
  std::string rout = slurp(dir / "replay.out");
  INFO(rout);
  CHECK(rst->clean());
  REQUIRE(std::regex_search(rout, m, std::regex(R"((\d+) compared, 0 mismatches)")));
  CHECK(std::stoi(m[1]) > 10);
  fs::remove_all(dir);
}
