// NETNS, real processes, end to end: the demo profile (simcam -> vision -> prediction -> projection,
// bricklayer-logger) runs headless under bricklayer-launch, stops by itself, and its bus log replays through
// bricklayer-replay --module vision,prediction --check with 0 mismatches. Only built when every module of the demo is.
#include <catch2/catch.hpp>

#include <filesystem>
#include <regex>

#include "harness/demo_profile.h"
#include "harness/live_bus.h"
#include "harness/program.h"
#include "harness/scratch.h"

using namespace bricklayer;
using namespace std::chrono_literals;
namespace fs = std::filesystem;

TEST_CASE("the demo profile runs headless, stops by itself, and its log replays with 0 mismatches") {
  harness::ScratchDir dir("demo");
  // The shipped profile, with the log and the snapshots in a temporary folder instead of logs/.
  const harness::DemoProfile demo = harness::scratch_demo_profile(dir);

  const harness::Ran launch = harness::run_program(
      "bricklayer-launch", {"--root", BRICKLAYER_SOURCE_DIR, "--duration", "8", demo.file.string()}, 60s,
      harness::ProgramOptions{{"DISPLAY=", "SDL_AUDIODRIVER=dummy", std::string("LCM_DEFAULT_URL=") + harness::kLiveUrl}, ""});
  REQUIRE_FALSE(launch.timed_out);
  const std::string& out = launch.out;
  INFO(out << launch.err);
  CHECK(launch.status.clean());
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
  // Vision (from the recorded frames, projector images and its late start) and prediction on its stacks.
  const harness::Ran replay = harness::run_program(
      "bricklayer-replay", {(dir / "demo.00").string(), "--module", "vision,prediction", "--check"}, 60s);
  REQUIRE_FALSE(replay.timed_out);
  const std::string& rout = replay.out;
  INFO(rout);
  CHECK(replay.status.clean());
  REQUIRE(std::regex_search(rout, m, std::regex(R"((\d+) compared, 0 mismatches)")));
  CHECK(std::stoi(m[1]) > 10);
}
