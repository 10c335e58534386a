// PlannerNode on the in-process rig: stack + prediction + REQUEST_HINT in, hint and preview out; and
// one process test that bricklayer-planner starts, answers and stops on a real bus.
#include <catch2/catch.hpp>

#include <chrono>
#include <optional>
#include <string>
#include <vector>

#include "bricklayer/command_t.hpp"
#include "bricklayer/common/channels.h"
#include "bricklayer/core/predict.h"
#include "bricklayer/heartbeat_t.hpp"
#include "bricklayer/messages/prediction.h"
#include "bricklayer/messages/stack.h"
#include "bricklayer/planner/hint.h"
#include "bricklayer/planner/planner_node.h"
#include "bricklayer/runtime/lcm_bus.h"
#include "harness/program.h"
#include "harness/recorder.h"
#include "harness/rig.h"

using namespace bricklayer;
using namespace std::chrono_literals;

namespace {

bricklayer::stack_t to_message(const core::Stack& s, int64_t frame) {
  return messages::to_stack_message(s, 1000 + frame, frame);
}

prediction_t to_message(const core::Prediction& p, const bricklayer::stack_t& s) {
  prediction_t m{};
  m.utime = s.utime;
  m.frame_number = s.frame_number;
  m.status = prediction_t::STATUS_OK;
  messages::put_verdict(p, m);
  return m;
}

}  // namespace

TEST_CASE("the planner answers a hint request and an unbalanced prediction") {
  harness::Rig rig;
  rig.add<planner::PlannerNode>(planner::PlannerConfig{});
  auto& rec = rig.record({channel(kHintChannel), channel(kPreviewChannel)});
  std::optional<hint_t> hint;
  std::optional<collapse_preview_t> preview;
  auto pump_until = [&](auto done, int seconds) {
    return rig.run_until(
        [&] {
          if (auto h = rec.all<hint_t>(channel(kHintChannel)); !h.empty()) hint = h.back();
          if (auto p = rec.all<collapse_preview_t>(channel(kPreviewChannel)); !p.empty()) preview = p.back();
          return done();
        },
        std::chrono::seconds(seconds));
  };
  auto publish = [&rig](const std::string& ch, const auto& msg) { rig.publish(ch, msg); };

  // A balanced pile: a hint to extend it.
  core::Stack balanced;
  balanced.blocks = {{1, 0, -0.6}, {2, 1, -1.0}, {3, 2, -0.8}};
  const bricklayer::stack_t first = to_message(balanced, 1);
  publish(channel(kStackChannel), first);
  publish(channel(kPredictionChannel), to_message(core::predict(balanced), first));
  command_t request{};
  request.command = command_t::REQUEST_HINT;
  publish(channel(kCommandChannel), request);
  REQUIRE(pump_until([&] { return hint.has_value(); }, 10));
  CHECK(hint->frame_number == 1);
  CHECK(hint->kind == hint_t::KIND_EXTEND);
  REQUIRE(hint->num_blocks == 1);
  CHECK(hint->margin == 0.02);
  const planner::Hint expected = planner::next_block_hint(balanced);
  CHECK(hint->rows[0] == expected.blocks[0].row);
  CHECK(hint->xs[0] == expected.blocks[0].x);
  CHECK(hint->score_after == expected.score_after);
  CHECK_FALSE(preview.has_value());  // balanced: nothing to preview

  // An unbalanced pile: a preview of its collapse, in answer to its prediction.
  core::Stack tipping;
  tipping.blocks = {{1, 0, -1.5}, {2, 1, -1.5}, {3, 2, -0.6}, {4, 3, -0.6}};
  const bricklayer::stack_t second = to_message(tipping, 2);
  const core::Prediction verdict = core::predict(tipping);
  REQUIRE_FALSE(verdict.balanced);
  publish(channel(kStackChannel), second);
  publish(channel(kPredictionChannel), to_message(verdict, second));
  REQUIRE(pump_until([&] { return preview.has_value(); }, 10));
  CHECK(preview->frame_number == 2);
  CHECK(preview->utime == second.utime);
  REQUIRE(preview->num_blocks == 4);
  REQUIRE(preview->num_frames >= 2);
  REQUIRE(preview->num_values == 3 * preview->num_frames * preview->num_blocks);
  const int last = preview->num_frames - 1;
  auto y = [&](int frame, int block) { return preview->poses[3 * (frame * 4 + block) + 1]; };
  CHECK(y(last, 3) < y(0, 3) - 0.5);  // the shifted top falls
  CHECK(y(last, 0) == y(0, 0));       // the balanced bottom stays
}

TEST_CASE("the preview on the bus says how each block ends: the top one fell off, the bottom one stays") {
  harness::Rig rig;
  rig.add<planner::PlannerNode>(planner::PlannerConfig{});
  auto& rec = rig.record({channel(kPreviewChannel)});
  core::Stack tipping;
  tipping.blocks = {{21, 0, -1.0}, {22, 1, -0.3}};  // the top block's centre is 0.2 beyond the bottom one's end
  const bricklayer::stack_t stack = to_message(tipping, 3);
  const core::Prediction verdict = core::predict(tipping);
  REQUIRE(verdict.moving() == std::vector<int64_t>{22});
  rig.publish(channel(kStackChannel), stack);
  rig.publish(channel(kPredictionChannel), to_message(verdict, stack));
  auto preview = rec.wait_for<collapse_preview_t>(channel(kPreviewChannel), {}, 10s);
  REQUIRE(preview);  // encoded on the bus and decoded by the recorder
  CHECK(preview->frame_number == 3);
  REQUIRE(preview->block_ids == std::vector<int64_t>{21, 22});
  REQUIRE(preview->end_state.size() == 2);
  CHECK(preview->end_state[1] == collapse_preview_t::END_FELL_OFF);
  CHECK((preview->end_state[0] == collapse_preview_t::END_UNTOUCHED ||
         preview->end_state[0] == collapse_preview_t::END_AT_REST));
}

TEST_CASE("the planner remembers invalid stacks as errors, and asks for a stack before it can hint") {
  harness::Rig rig;
  auto& node = rig.add<planner::PlannerNode>(planner::PlannerConfig{});
  auto& rec = rig.record({channel(kHintChannel)});
  command_t request{};
  request.command = command_t::REQUEST_HINT;
  rig.publish(channel(kCommandChannel), request);
  rig.run_for(100ms);
  CHECK(rec.count(channel(kHintChannel)) == 0);  // no stack yet: the request waits
  core::Stack overlapping;
  overlapping.blocks = {{1, 0, -0.5}, {2, 0, -0.2}};
  rig.publish(channel(kStackChannel), to_message(overlapping, 1));
  rig.run_for(10ms);
  CHECK(node.counters().errors == 1);
  core::Stack fine;
  fine.blocks = {{1, 0, -0.6}};
  rig.publish(channel(kStackChannel), to_message(fine, 2));
  auto hint = rec.wait_for<hint_t>(channel(kHintChannel), {}, 100ms);
  REQUIRE(hint);
  CHECK(hint->frame_number == 2);
}

TEST_CASE("bricklayer-planner starts, answers a hint request and stops on a real bus") {
  runtime::LcmBus bus("udpm://239.255.76.67:7667?ttl=0");
  auto rec = harness::Recorder::live(bus, {channel(kHeartbeatChannel), channel(kHintChannel)});
  harness::Program planner("bricklayer-planner", {"--lcm-url=udpm://239.255.76.67:7667?ttl=0"});
  REQUIRE(rec.wait_for_heartbeat("planner", {}, 10s));
  core::Stack balanced;
  balanced.blocks = {{1, 0, -0.6}, {2, 1, -1.0}};
  const auto stack = runtime::encode(to_message(balanced, 5));
  command_t request{};
  request.command = command_t::REQUEST_HINT;
  const auto command = runtime::encode(request);
  bus.publish(channel(kStackChannel), stack.data(), stack.size());
  bus.publish(channel(kCommandChannel), command.data(), command.size());
  auto hint = rec.wait_for<hint_t>(channel(kHintChannel), {}, 10s);
  REQUIRE(hint);
  CHECK(hint->frame_number == 5);
  const auto status = planner.stop();
  INFO(planner.stderr_text());
  CHECK(status.clean());
}
