// bricklayer-planner on a real bus (NETNS): stack + prediction + REQUEST_HINT in, hint and preview out.
#include <signal.h>
#include <spawn.h>
#include <sys/wait.h>

#include <catch2/catch.hpp>

#include <chrono>
#include <optional>
#include <string>
#include <vector>

#include "bricklayer/command_t.hpp"
#include "bricklayer/common/channels.h"
#include "bricklayer/common/module.h"
#include "bricklayer/core/predict.h"
#include "bricklayer/heartbeat_t.hpp"
#include "bricklayer/planner/hint.h"
#include "bricklayer/planner/planner_logic.h"

extern char** environ;

using namespace bricklayer;

namespace {

constexpr const char* kUrl = "udpm://239.255.76.67:7667?ttl=0";

class Child {
 public:
  explicit Child(std::vector<std::string> args) {
    std::vector<char*> argv;
    for (auto& a : args) argv.push_back(a.data());
    argv.push_back(nullptr);
    REQUIRE(posix_spawn(&pid_, argv[0], nullptr, nullptr, argv.data(), environ) == 0);
  }
  ~Child() {
    kill(pid_, SIGTERM);
    int status = 0;
    waitpid(pid_, &status, 0);
  }

 private:
  pid_t pid_ = 0;
};

bricklayer::stack_t to_message(const core::Stack& s, int64_t frame) {
  bricklayer::stack_t m{};
  m.utime = 1000 + frame;
  m.frame_number = frame;
  m.block_length = s.block_length;
  m.block_height = s.block_height;
  m.table_edge = s.table_edge;
  m.status = bricklayer::stack_t::STATUS_OK;
  for (const auto& b : s.blocks) {
    block_t bt{};
    bt.id = b.id;
    bt.row = b.row;
    bt.x = b.x;
    bt.confidence = 1.0;
    m.blocks.push_back(bt);
  }
  m.num_blocks = static_cast<int32_t>(m.blocks.size());
  return m;
}

prediction_t to_message(const core::Prediction& p, const bricklayer::stack_t& s) {
  prediction_t m{};
  m.utime = s.utime;
  m.frame_number = s.frame_number;
  m.status = prediction_t::STATUS_OK;
  m.balanced = p.balanced;
  m.overhang = p.overhang;
  m.score = p.score;
  m.annotator = p.annotator;
  m.solver = p.solver;
  for (const auto& b : p.blocks) {
    block_prediction_t bp{};
    bp.id = b.id;
    bp.state = static_cast<int8_t>(b.state);
    bp.accel = b.accel;
    bp.alpha = b.alpha;
    m.blocks.push_back(bp);
  }
  m.num_blocks = static_cast<int32_t>(m.blocks.size());
  return m;
}

}  // namespace

TEST_CASE("the planner answers a hint request and an unbalanced prediction") {
  Module bus("test", kUrl);
  bool planner_up = false;
  std::optional<hint_t> hint;
  std::optional<collapse_preview_t> preview;
  bus.subscribe<heartbeat_t>(channel(kHeartbeatChannel), [&](const heartbeat_t& hb) {
    if (hb.module == "planner") planner_up = true;
  });
  bus.subscribe<hint_t>(channel(kHintChannel), [&](const hint_t& h) { hint = h; });
  bus.subscribe<collapse_preview_t>(channel(kPreviewChannel), [&](const collapse_preview_t& p) { preview = p; });

  Child planner({std::string(BRICKLAYER_BINARY_DIR) + "/bin/bricklayer-planner", std::string("--lcm-url=") + kUrl});
  auto pump_until = [&](auto done, int seconds) {
    const auto deadline = std::chrono::steady_clock::now() + std::chrono::seconds(seconds);
    while (!done() && std::chrono::steady_clock::now() < deadline) bus.lcm().handleTimeout(20);
    return done();
  };
  REQUIRE(pump_until([&] { return planner_up; }, 10));  // readiness: its heartbeat, never a sleep

  // A balanced pile: a hint to extend it.
  core::Stack balanced;
  balanced.blocks = {{1, 0, -0.6}, {2, 1, -1.0}, {3, 2, -0.8}};
  const bricklayer::stack_t first = to_message(balanced, 1);
  bus.publish(channel(kStackChannel), first);
  bus.publish(channel(kPredictionChannel), to_message(core::predict(balanced), first));
  command_t request{};
  request.command = command_t::REQUEST_HINT;
  bus.publish(channel(kCommandChannel), request);
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
  bus.publish(channel(kStackChannel), second);
  bus.publish(channel(kPredictionChannel), to_message(verdict, second));
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
