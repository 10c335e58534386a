// bricklayer-simcam as a real process: frames on the live bus, and its refusal of bad flags. (The node's
// behaviour frame by frame is simcam_node_test.cc.)
#include <catch2/catch.hpp>

#include <opencv2/imgcodecs.hpp>

#include "bricklayer/common/channels.h"
#include "bricklayer/image_t.hpp"
#include "bricklayer/runtime/lcm_bus.h"
#include "bricklayer/stack_t.hpp"
#include "harness/program.h"
#include "harness/recorder.h"

using namespace bricklayer;
using namespace std::chrono_literals;

namespace {
const std::string kScenarios = std::string(BRICKLAYER_SOURCE_DIR) + "/launch/scenarios/";
const std::string kUrl = "udpm://239.255.76.67:7667?ttl=0";
}  // namespace

TEST_CASE("simcam publishes decodable frames on LCM and exits 0 at its frame limit") {
  runtime::LcmBus bus(kUrl);
  auto rec = harness::Recorder::live(bus, {channel(kImageChannel), channel(kTruthChannel)});
  harness::Program simcam("bricklayer-simcam",
                          {"--scenario", kScenarios + "wall-60.json", "--fps", "30", "--frames", "20", "--lcm-url", kUrl});
  REQUIRE(rec.wait_until([&] { return rec.count(channel(kTruthChannel)) == 20; }, 10s));
  const auto status = simcam.wait_exit(5s);
  INFO(simcam.stderr_text());
  REQUIRE(status);
  CHECK(status->clean());
  const auto frames = rec.all<image_t>(channel(kImageChannel));
  REQUIRE(frames.size() == 20);
  for (size_t i = 0; i < frames.size(); ++i) {
    CHECK(frames[i].frame_number == static_cast<int64_t>(i));
    CHECK_FALSE(cv::imdecode(frames[i].data, cv::IMREAD_COLOR).empty());
  }
}

TEST_CASE("simcam refuses bad configuration with a clear error") {
  auto code = [](std::vector<std::string> args) {
    args.push_back("--lcm-url=" + kUrl);
    const auto ran = harness::run_program("bricklayer-simcam", args, 10s);
    INFO(ran.err);
    return ran.status.code;
  };
  CHECK(code({}) == 2);  // no scenario
  CHECK(code({"--scenario", "/nonexistent.json"}) == 1);
  CHECK(code({"--scenario", kScenarios + "wall-60.json", "--fps", "0"}) == 2);
  CHECK(code({"--scenario", kScenarios + "wall-60.json", "--nuisance", "foggy"}) == 2);
  // A bus that would leave this machine is refused.
  const auto ran = harness::run_program("bricklayer-simcam",
                                        {"--scenario", kScenarios + "wall-60.json", "--lcm-url", "udpm://239.255.76.67:7667?ttl=7"}, 10s);
  CHECK(ran.status.code != 0);
}
