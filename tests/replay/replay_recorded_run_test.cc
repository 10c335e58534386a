// NETNS, real processes: bricklayer-prediction and bricklayer-planner on the real bus, recorded by
// bricklayer-logger; bricklayer-replay runs both nodes on the recording:
// - each module and the chain replay with 0 mismatches;
// - a tampered output of each module (one prediction's block state, one preview's pose) makes the
//   check fail, naming the channel, the frame and the field;
// - the recording's index lets --from start at a wall time without the parts before it.
#include <catch2/catch.hpp>

#include <regex>

#include "bricklayer/collapse_preview_t.hpp"
#include "bricklayer/command_t.hpp"
#include "bricklayer/common/channels.h"
#include "bricklayer/prediction/sample_stacks.h"
#include "bricklayer/prediction_t.hpp"
#include "bricklayer/runtime/codec.h"
#include "bricklayer/runtime/lcm_bus.h"
#include "bricklayer/runtime/log_file.h"
#include "harness/program.h"
#include "replay_cli.h"
#include "harness/recorder.h"
#include "harness/scratch.h"

using namespace bricklayer;
using namespace bricklayer::test;
using namespace std::chrono_literals;

namespace {
const std::string kUrl = "udpm://239.255.76.67:7667?ttl=0";



}  // namespace

TEST_CASE("a run of the real prediction and planner processes replays with 0 mismatches, and tampering is caught and named") {
  harness::ScratchDir dir("replay-run");
  runtime::LcmBus bus(kUrl);
  auto rec = harness::Recorder::live(bus, {channel(kHeartbeatChannel), channel(kPredictionChannel), channel(kPreviewChannel)});
  harness::Program logger("bricklayer-logger", {"--lcm-url=" + kUrl, "--split-mb", "50", (dir / "run").string()});
  REQUIRE(rec.wait_for_heartbeat("logger", {}, 10s));
  harness::Program prediction("bricklayer-prediction", {"--lcm-url=" + kUrl});
  harness::Program planner("bricklayer-planner", {"--lcm-url=" + kUrl});
  REQUIRE(rec.wait_for_heartbeat("prediction", {}, 10s));
  REQUIRE(rec.wait_for_heartbeat("planner", {}, 10s));
  // 300 stacks, 4 ms apart: piles of 3..14 blocks, many unbalanced (previews), a hint request every 50.
  for (int f = 0; f < 300; ++f) {
    const auto s = runtime::encode(prediction::sample_stack(3 + (f / 10) % 12, static_cast<uint32_t>(f / 10), bus.now_utime(), f));
    REQUIRE(bus.publish(channel(kStackChannel), s.data(), s.size()));
    if (f % 50 == 49) {
      command_t c{};
      c.utime = bus.now_utime();
      c.command = command_t::REQUEST_HINT;
      const auto b = runtime::encode(c);
      bus.publish(channel(kCommandChannel), b.data(), b.size());
    }
    rec.pump_for(4ms);
  }
  REQUIRE(rec.wait_for<prediction_t>(channel(kPredictionChannel), [](const prediction_t& p) { return p.frame_number == 299; }, 10s));
  rec.pump_for(1500ms);  // the last previews, and the configurations (every 10 s: the first ones are in)
  planner.stop();
  prediction.stop();
  REQUIRE(logger.stop().clean());
  const std::string part = (dir / "run.00").string();

  for (const std::string module : {"prediction", "planner", "prediction,planner"}) {
    const auto r = replay({part, "--module", module, "--check"});
    INFO(module << "\n" << r.out << r.err);
    CHECK(r.status.code == 0);
    CHECK(compared_ok(r.out) > (module == "planner" ? 10 : 200));
    CHECK(r.err.find("with its recorded configuration") != std::string::npos);
  }
  // The recording's index: from a wall time, the parts and offsets it names.
  const auto indexed = replay({(dir / "run.index").string(), "--check", "--from", "+0.6"});
  INFO(indexed.out << indexed.err);
  CHECK(indexed.status.code == 0);
  CHECK(compared_ok(indexed.out) > 50);

  int64_t frame = -1;
  const std::string bad_prediction = tampered(dir, part, [&](runtime::LogEvent& e) {
    if (e.channel != channel(kPredictionChannel)) return false;
    auto p = runtime::decode<prediction_t>(e.data);
    if (p->frame_number < 150 || p->num_blocks < 4) return false;
    p->blocks[3].state = p->blocks[3].state == block_prediction_t::STATE_CAUSE ? block_prediction_t::STATE_STABLE
                                                                               : block_prediction_t::STATE_CAUSE;
    frame = p->frame_number;
    e.data = runtime::encode(*p);
    return true;
  }, "tampered.00");
  auto r = replay({bad_prediction, "--module", "prediction,planner", "--check"});
  INFO(r.out << r.err);
  CHECK(r.status.code == 1);
  CHECK(r.out.find("MISMATCH BL_PREDICTION (prediction_t) at ") != std::string::npos);
  CHECK(r.out.find("frame " + std::to_string(frame) + ": blocks[3].state: ") != std::string::npos);

  const std::string bad_preview = tampered(dir, part, [&](runtime::LogEvent& e) {
    if (e.channel != channel(kPreviewChannel)) return false;
    auto p = runtime::decode<collapse_preview_t>(e.data);
    if (p->poses.size() < 3) return false;
    p->poses[2] += 0.25;
    e.data = runtime::encode(*p);
    return true;
  }, "tampered.00");
  r = replay({bad_preview, "--module", "prediction,planner", "--check"});
  INFO(r.out << r.err);
  CHECK(r.status.code == 1);
  CHECK(r.out.find("MISMATCH BL_PREVIEW (collapse_preview_t) at ") != std::string::npos);
  CHECK(r.out.find("poses[2]: ") != std::string::npos);
}
