// bricklayer-replay --module calibrate on runs recorded from the real calibrate, projection and simcam
// nodes on the rig: a calibration run (the pattern commands it sent on the frames it got, the
// calibration it computed) and a --serve run (republished every second, a SELF_CHECK answered with
// the check markers) replay with 0 mismatches, alone and with projection answering its patterns; a
// tampered calibration_t and a tampered pattern command are caught and named; two replays publish
// byte-identical outputs; the replay writes nothing where the live node did.
#include <catch2/catch.hpp>

#include <filesystem>
#include <regex>

#include "bricklayer/calibration_t.hpp"
#include "bricklayer/command_t.hpp"
#include "bricklayer/common/channels.h"
#include "bricklayer/runtime/codec.h"
#include "bricklayer/runtime/log_file.h"
#include "harness/program.h"
#include "replay_cli.h"
#include "harness/scratch.h"
#include "rig_runs.h"

using namespace bricklayer;
using namespace bricklayer::test;
namespace fs = std::filesystem;

namespace {



struct Runs {
  harness::ScratchDir dir{"replay-calibrate"};
  std::string calibration_log, calibration_file, serve_log;
};

const Runs& runs() {
  static Runs r;
  static const bool recorded = [] {
    r.calibration_log = (r.dir / "calibration.lcm").string();
    r.calibration_file = (r.dir / "calibration.json").string();
    test::record_calibration_run(r.calibration_log, r.calibration_file);
    r.serve_log = (r.dir / "serve.lcm").string();
    test::record_serve_run(r.serve_log, r.calibration_file);
    return true;
  }();
  (void)recorded;
  return r;
}


}  // namespace

TEST_CASE("a recorded calibration run replays with 0 mismatches, alone and with projection showing its patterns") {
  const auto before = fs::last_write_time(runs().calibration_file);
  for (const std::string module : {"calibrate", "projection,calibrate"}) {
    INFO(module);
    const auto r = replay({runs().calibration_log, "--module", module, "--check"});
    INFO(r.out << r.err);
    CHECK(r.status.code == 0);
    CHECK(compared_on(r.out, "BL_CALIBRATION") == 1);
    CHECK(compared_on(r.out, "BL_COMMAND") >= 7);  // six patterns and the CLEAR_PATTERN
    CHECK(r.err.find("writes its calibration into the replay's scratch folder (live: " + runs().calibration_file + ")") !=
          std::string::npos);
    if (module != "calibrate") CHECK(compared_on(r.out, "BL_PROJECTOR") >= 6);
  }
  CHECK(fs::last_write_time(runs().calibration_file) == before);  // the live file is left alone
}

TEST_CASE("a recorded --serve run replays: the republications and the self-check's commands") {
  const auto r = replay({runs().serve_log, "--module", "calibrate", "--check"});
  INFO(r.out << r.err);
  CHECK(r.status.code == 0);
  CHECK(compared_on(r.out, "BL_CALIBRATION") >= 4);  // once a second for 5 s
  CHECK(compared_on(r.out, "BL_COMMAND") >= 2);      // the check markers and the CLEAR_PATTERN
  CHECK(r.err.find("loads the first calibration recorded on BL_CALIBRATION") != std::string::npos);
}

TEST_CASE("a tampered calibration and a tampered pattern command are caught and named") {
  harness::ScratchDir dir("replay-calibrate-tamper");
  SECTION("the computed calibration") {
    const std::string log = tampered(dir, runs().calibration_log, [](runtime::LogEvent& e) {
      if (e.channel != channel(kCalibrationChannel)) return false;
      auto c = runtime::decode<calibration_t>(e.data);
      c->camera_to_board[2] += 1e-6;
      e.data = runtime::encode(*c);
      return true;
    });
    const auto r = replay({log, "--module", "calibrate", "--check"});
    INFO(r.out << r.err);
    CHECK(r.status.code == 1);
    CHECK(r.out.find("MISMATCH BL_CALIBRATION (calibration_t) at ") != std::string::npos);
    CHECK(r.out.find(": camera_to_board[2]: ") != std::string::npos);
    CHECK(r.out.find(" compared, 1 mismatches") != std::string::npos);
  }
  SECTION("a served calibration") {
    int seen = 0;
    const std::string log = tampered(dir, runs().serve_log, [&](runtime::LogEvent& e) {
      if (e.channel != channel(kCalibrationChannel) || ++seen < 3) return false;
      auto c = runtime::decode<calibration_t>(e.data);
      c->colour_mixing[4] *= 1.01;
      e.data = runtime::encode(*c);
      return true;
    });
    const auto r = replay({log, "--module", "calibrate", "--check"});
    INFO(r.out << r.err);
    CHECK(r.status.code == 1);
    CHECK(r.out.find("MISMATCH BL_CALIBRATION (calibration_t) at ") != std::string::npos);
    CHECK(r.out.find(": colour_mixing[4]: ") != std::string::npos);
  }
  SECTION("a pattern command") {
    const std::string log = tampered(dir, runs().calibration_log, [](runtime::LogEvent& e) {
      if (e.channel != channel(kCommandChannel)) return false;
      auto c = runtime::decode<command_t>(e.data);
      if (c->command != command_t::SHOW_PATTERN || c->pattern != command_t::PATTERN_MARKERS) return false;
      c->index += 1;
      e.data = runtime::encode(*c);
      return true;
    });
    // Alone, so the recorded projector answers the recorded commands.
    const auto r = replay({log, "--module", "calibrate", "--check"});
    INFO(r.out << r.err);
    CHECK(r.status.code == 1);
    CHECK(r.out.find("MISMATCH BL_COMMAND (command_t) at ") != std::string::npos);
    CHECK(r.out.find(": index: ") != std::string::npos);
  }
}

TEST_CASE("two replays of the calibration run publish byte-identical outputs") {
  harness::ScratchDir dir("replay-calibrate-twice");
  const std::string a = (dir / "a.lcm").string(), b = (dir / "b.lcm").string();
  REQUIRE(replay({runs().calibration_log, "--module", "projection,calibrate", "--record-outputs", a}).status.code == 0);
  REQUIRE(replay({runs().calibration_log, "--module", "projection,calibrate", "--record-outputs", b}).status.code == 0);
  const std::string bytes = harness::read_file(a);
  CHECK(bytes.size() > 10'000);
  CHECK(bytes == harness::read_file(b));
}
