// bricklayer-replay --module vision on a camera run recorded from the real simcam, vision and prediction
// nodes (frames included, as the demo's logger records them): vision alone and chained with prediction
// replay with 0 mismatches, a tampered stack is caught and named, and a changed vision parameter shows
// block-level differences in --diff.
#include <catch2/catch.hpp>

#include <regex>

#include "bricklayer/common/channels.h"
#include "bricklayer/runtime/codec.h"
#include "bricklayer/runtime/log_file.h"
#include "bricklayer/stack_t.hpp"
#include "harness/program.h"
#include "replay_cli.h"
#include "harness/scratch.h"
#include "replay_fixture.h"

using namespace bricklayer;
using namespace bricklayer::test;

namespace {
const std::string kScenario = std::string(BRICKLAYER_SOURCE_DIR) + "/launch/scenarios/build-4-optimum.json";


int64_t compared(const std::string& out) {
  std::smatch m;
  return std::regex_search(out, m, std::regex(R"((\d+) compared, 0 mismatches)")) ? std::stoll(m[1]) : -1;
}

// The recorded run, made once for every case (rendering and detecting 240 frames takes a few seconds).
const std::string& camera_log() {
  static harness::ScratchDir dir("replay-vision");
  static const std::string log = [] {
    const std::string path = (dir / "camera.lcm").string();
    test::record_camera_run(path, kScenario, 240);
    return path;
  }();
  return log;
}
}  // namespace

TEST_CASE("vision, and vision chained with prediction, replay a recorded camera run with 0 mismatches") {
  for (const std::string module : {"vision", "vision,prediction"}) {
    INFO(module);
    const auto r = replay({camera_log(), "--module", module, "--check"});
    INFO(r.out << r.err);
    CHECK(r.status.code == 0);
    // 240 frames: every stack (and in the chain every prediction) compared.
    CHECK(compared(r.out) >= (module == "vision" ? 240 : 480));
  }
}

TEST_CASE("a tampered stack in the recorded run is caught, with its frame and field") {
  harness::ScratchDir dir("replay-vision-tamper");
  const std::string log = (dir / "tampered.lcm").string();
  int64_t frame = -1;
  {
    runtime::LogReader r(camera_log());
    runtime::LogWriter w(log);
    runtime::LogEvent e;
    while (r.next(e)) {
      if (e.channel == channel(kStackChannel) && frame < 0) {
        auto s = runtime::decode<stack_t>(e.data);
        if (s && s->frame_number >= 150 && s->num_blocks >= 2) {
          s->blocks[1].x += 0.004;
          frame = s->frame_number;
          e.data = runtime::encode(*s);
        }
      }
      REQUIRE(w.write(e.utime, e.channel, e.data.data(), e.data.size()));
    }
  }
  REQUIRE(frame >= 0);
  const auto r = replay({log, "--module", "vision", "--check"});
  INFO(r.out << r.err);
  CHECK(r.status.code == 1);
  CHECK(r.out.find("MISMATCH BL_STACK (stack_t) at ") != std::string::npos);
  CHECK(r.out.find("frame " + std::to_string(frame) + ": blocks[1].x: ") != std::string::npos);
  CHECK(r.out.find(" compared, 1 mismatches") != std::string::npos);
}

TEST_CASE("diff: a changed vision parameter shows block-level differences") {
  // No temporal filter: raw measurements, so x moves within the deadband the filter would have held.
  const auto r = replay({camera_log(), "--module", "vision", "--diff", "--set-b", "no-filter=true"});
  INFO(r.out << r.err);
  CHECK(r.status.code == 1);  // they differ
  CHECK(r.out.find("| BL_STACK |") != std::string::npos);
  CHECK(r.out.find("blocks: ") != std::string::npos);
  CHECK(r.out.find("stacks differ") != std::string::npos);
}
