// NETNS: a real bricklayer-prediction process on the real LCM bus. 1,000 stacks in, 1,000 predictions
// out, each byte-identical to a prediction_t built here from calling the core directly (the knife-edge verdict).
#include <catch2/catch.hpp>

#include <algorithm>
#include <cmath>

#include "bricklayer/core/knife_edge.h"
#include "bricklayer/core/predict.h"
#include "bricklayer/common/channels.h"
#include "bricklayer/prediction/prediction_logic.h"
#include "bricklayer/prediction/sample_stacks.h"
#include "bricklayer/prediction_t.hpp"
#include "bricklayer/runtime/lcm_bus.h"
#include "bricklayer/stack_t.hpp"
#include "harness/program.h"
#include "harness/recorder.h"

using namespace bricklayer;
using namespace std::chrono_literals;

namespace {
constexpr const char* kUrl = "udpm://239.255.76.67:7667?ttl=0";

// The expected answer, from the core directly (independent of PredictionLogic's mapping): the knife-edge
// verdict with every block's uncertainty at the process's floor, and the node's hysteresis written out again
// (a certain verdict right after a knife edge is shown as a knife edge until |margin| >= 1.5 x uncertainty).
struct Expected {
  int8_t shown = -1;
  prediction_t operator()(const stack_t& s) {
    core::Stack cs;
    cs.block_length = s.block_length;
    cs.block_height = s.block_height;
    cs.table_edge = s.table_edge;
    for (const auto& b : s.blocks) cs.blocks.push_back({b.id, b.row, b.x});
    const double floor = prediction::kUncertaintyFloor;  // the process's default
    const core::KnifeEdgeVerdict k = core::judge_knife_edge(cs, std::vector<double>(cs.blocks.size(), floor));
    const core::Prediction& v = k.nominal;
    const int8_t raw = static_cast<int8_t>(k.certainty);
    int8_t verdict = raw;
    if (raw != prediction_t::VERDICT_KNIFE_EDGE && shown == prediction_t::VERDICT_KNIFE_EDGE &&
        std::abs(k.margin) < 1.5 * k.uncertainty)
      verdict = prediction_t::VERDICT_KNIFE_EDGE;
    shown = verdict;
    prediction_t p{};
    p.utime = s.utime;
    p.frame_number = s.frame_number;
    p.status = prediction_t::STATUS_OK;
    p.balanced = verdict != prediction_t::VERDICT_FALLS;
    p.overhang = v.overhang;
    p.score = v.score;
    p.annotator = v.annotator;
    p.solver = v.solver;
    p.position_tolerance = 0.0;
    p.verdict = verdict;
    p.raw_verdict = raw;
    p.margin = k.margin;
    p.margin_mm = k.margin * 75.0;
    p.uncertainty = k.uncertainty;
    p.uncertainty_floor = floor;
    p.counts_for_max = verdict != prediction_t::VERDICT_FALLS;
    for (const auto& b : v.blocks) {
      block_prediction_t bp{};
      bp.id = b.id;
      bp.state = verdict == prediction_t::VERDICT_FALLS ? static_cast<int8_t>(b.state) : block_prediction_t::STATE_STABLE;
      bp.accel = b.accel;
      bp.alpha = b.alpha;
      bp.deciding = std::find(k.deciding.begin(), k.deciding.end(), b.id) != k.deciding.end();
      bp.uncertainty = floor;
      p.blocks.push_back(bp);
    }
    p.num_blocks = static_cast<int32_t>(p.blocks.size());
    return p;
  }
};

}  // namespace

TEST_CASE("1,000 stacks through bricklayer-prediction come back byte-identical to the core's answers") {
  runtime::LcmBus bus(kUrl);
  auto rec = harness::Recorder::live(bus, {channel(kPredictionChannel), channel(kHeartbeatChannel)});
  harness::Program proc("bricklayer-prediction", {"--log-level", "warn", std::string("--lcm-url=") + kUrl});
  REQUIRE(rec.wait_for_heartbeat("prediction", [&](const heartbeat_t& hb) { return hb.pid == proc.pid(); }, 10s));

  constexpr int kCount = 1000;
  std::vector<stack_t> sent;
  int unbalanced = 0;
  // Lock-step: the next stack goes out once the previous answer is back, a pace the process keeps up
  // with, so newest-wins never has to drop (checked below in the heartbeat).
  for (int i = 1; i <= kCount; ++i) {
    stack_t s = prediction::sample_stack(1 + (i * 7) % 30, static_cast<uint32_t>(i), 5'000'000 + i * 1000, i);
    sent.push_back(s);
    const auto bytes = runtime::encode(s);
    REQUIRE(bus.publish(channel(kStackChannel), bytes.data(), bytes.size()));
    INFO("waiting for the answer to frame " << i);
    REQUIRE(rec.wait_until([&] { return rec.count(channel(kPredictionChannel)) == static_cast<size_t>(i); }, 3s));
  }
  std::vector<std::vector<uint8_t>> answers;
  for (const auto& m : rec.messages())
    if (m.channel == channel(kPredictionChannel)) answers.push_back(m.bytes);
  REQUIRE(answers.size() == static_cast<size_t>(kCount));
  int identical = 0;
  Expected from_core;
  for (int i = 0; i < kCount; ++i) {
    prediction_t expected = from_core(sent[static_cast<size_t>(i)]);
    if (!expected.balanced) ++unbalanced;
    if (runtime::encode(expected) == answers[static_cast<size_t>(i)]) ++identical;
  }
  CHECK(identical == kCount);
  // The sample piles must exercise both verdicts, or "identical" proves little.
  CHECK(unbalanced > 50);
  CHECK(unbalanced < kCount - 50);

  // The process's own account: everything received and answered, nothing dropped, no errors.
  auto hb = rec.wait_for_heartbeat("prediction", [](const heartbeat_t& h) { return h.published == kCount; }, 3s);
  REQUIRE(hb);
  CHECK(hb->received == kCount);
  CHECK(hb->dropped == 0);
  CHECK(hb->errors == 0);
  auto st = proc.stop();
  CHECK(st.clean());  // SIGTERM: a clean stop with exit code 0
}
