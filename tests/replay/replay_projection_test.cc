// bricklayer-replay --module projection on a run recorded from the real prediction, planner and
// projection nodes on the rig (SDL's offscreen driver, software renderer): the round, the projector
// states (PNG) and the status JPEGs replay with 0 mismatches, alone and chained; a tampered round_t,
// projector state and picture are caught and named; two replays publish byte-identical outputs.
#include <catch2/catch.hpp>

#include <regex>

#include <opencv2/imgcodecs.hpp>

#include "bricklayer/common/channels.h"
#include "bricklayer/projector_state_t.hpp"
#include "bricklayer/round_t.hpp"
#include "bricklayer/runtime/codec.h"
#include "bricklayer/runtime/log_file.h"
#include "harness/program.h"
#include "replay_cli.h"
#include "harness/scratch.h"
#include "rig_runs.h"

using namespace bricklayer;
using namespace bricklayer::test;

namespace {




const std::string& projection_log() {
  static harness::ScratchDir dir("replay-projection");
  static const std::string log = [] {
    const std::string path = (dir / "projection.lcm").string();
    test::record_projection_run(path);
    return path;
  }();
  return log;
}


}  // namespace

TEST_CASE("projection, alone and chained after prediction and planner, replays a recorded run with 0 mismatches") {
  for (const std::string module : {"projection", "prediction,planner,projection"}) {
    INFO(module);
    const auto r = replay({projection_log(), "--module", module, "--check"});
    INFO(r.out << r.err);
    CHECK(r.status.code == 0);
    // 8 s: a round_t a second and on every change, projector states at up to 15 a second, a status JPEG a second.
    CHECK(compared_on(r.out, "BL_ROUND") >= 10);
    CHECK(compared_on(r.out, "BL_PROJECTOR") >= 40);
    CHECK(compared_on(r.out, "BL_PROJECTOR_IMAGE") >= 7);
    CHECK(r.out.find(" 0 not in the log") != std::string::npos);
    CHECK(r.err.find("projector_state_t.image.frame_number") != std::string::npos);  // listed as run-to-run
  }
}

TEST_CASE("a tampered round_t, projector state and picture are caught and named") {
  harness::ScratchDir dir("replay-projection-tamper");
  SECTION("round_t") {
    int64_t utime = 0;
    const std::string log = tampered(dir, projection_log(), [&](runtime::LogEvent& e) {
      if (e.channel != channel(kRoundChannel)) return false;
      auto r = runtime::decode<round_t>(e.data);
      if (r->state != round_t::STATE_RUNNING || r->score == 0) return false;
      r->score += 1;
      utime = r->utime;
      e.data = runtime::encode(*r);
      return true;
    });
    const auto r = replay({log, "--module", "projection", "--check"});
    INFO(r.out << r.err);
    CHECK(r.status.code == 1);
    CHECK(r.out.find("MISMATCH BL_ROUND (round_t) at ") != std::string::npos);
    CHECK(std::regex_search(r.out, std::regex(R"(MISMATCH BL_ROUND \(round_t\) at [^\n]*: score: \d+ \(log\) vs \d+ \(replay\))")));
    CHECK(r.out.find(" compared, 1 mismatches") != std::string::npos);
  }
  SECTION("projector_state_t") {
    const std::string log = tampered(dir, projection_log(), [&](runtime::LogEvent& e) {
      if (e.channel != channel(kProjectorChannel)) return false;
      auto s = runtime::decode<projector_state_t>(e.data);
      if (s->frame_number < 100) return false;
      s->command_sequence = 12345;
      e.data = runtime::encode(*s);
      return true;
    });
    const auto r = replay({log, "--module", "projection", "--check"});
    INFO(r.out << r.err);
    CHECK(r.status.code == 1);
    CHECK(r.out.find("MISMATCH BL_PROJECTOR (projector_state_t) at ") != std::string::npos);
    CHECK(r.out.find("command_sequence: 12345 (log) vs ") != std::string::npos);
  }
  SECTION("the picture in a projector state: compared decoded, pixel for pixel") {
    const std::string log = tampered(dir, projection_log(), [&](runtime::LogEvent& e) {
      if (e.channel != channel(kProjectorChannel)) return false;
      auto s = runtime::decode<projector_state_t>(e.data);
      if (s->frame_number < 100) return false;
      cv::Mat im = cv::imdecode(s->image.data, cv::IMREAD_UNCHANGED);
      im.at<cv::Vec3b>(5, 7) = cv::Vec3b(0, 255, 0);  // one green pixel, which the game never draws
      s->image.data.clear();
      cv::imencode(".png", im, s->image.data);
      s->image.size = static_cast<int32_t>(s->image.data.size());
      e.data = runtime::encode(*s);
      return true;
    });
    const auto r = replay({log, "--module", "projection", "--check"});
    INFO(r.out << r.err);
    CHECK(r.status.code == 1);
    CHECK(r.out.find("image.data: the recorded picture (log) vs pixels differ by up to 255 levels (at x 7, y 5) (replay)") !=
          std::string::npos);
  }
}

TEST_CASE("two replays of the projection run publish byte-identical outputs") {
  harness::ScratchDir dir("replay-projection-twice");
  const std::string a = (dir / "a.lcm").string(), b = (dir / "b.lcm").string();
  REQUIRE(replay({projection_log(), "--module", "prediction,planner,projection", "--record-outputs", a}).status.code == 0);
  REQUIRE(replay({projection_log(), "--module", "prediction,planner,projection", "--record-outputs", b}).status.code == 0);
  const std::string bytes = harness::read_file(a);
  CHECK(bytes.size() > 100'000);  // the pictures are in it
  CHECK(bytes == harness::read_file(b));
}
