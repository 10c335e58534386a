// NETNS: bricklayer-projection as a real process with a round book. Stacks as vision sends them (20 Hz):
// an empty board, then a pile -> a round starts by itself; the process is killed (-9) mid-round and
// started again -> the round runs on with its MAX; the board stays empty -> it ends early; a restart
// between rounds shows the last round and the day's best again (BL_ROUND, heartbeat values, the file).
// Then the inputs stop: the heartbeat and the board say "camera not seeing" (the cause no longer red),
// and with stacks but no predictions "waiting for the other machine".
#include <catch2/catch.hpp>

#include <signal.h>

#include <chrono>
#include <functional>
#include <optional>

#include <nlohmann/json.hpp>
#include <opencv2/imgcodecs.hpp>

#include "bricklayer/board/board_to_projector.h"
#include "bricklayer/command_t.hpp"
#include "bricklayer/common/channels.h"
#include "bricklayer/heartbeat_t.hpp"
#include "bricklayer/prediction_t.hpp"
#include "bricklayer/round_t.hpp"
#include "bricklayer/runtime/lcm_bus.h"
#include "bricklayer/stack_t.hpp"
#include "harness/live_bus.h"
#include "harness/program.h"
#include "harness/recorder.h"
#include "harness/scratch.h"

using namespace bricklayer;
using namespace std::chrono_literals;

namespace {

// The board as vision would send it: empty, or a two-block pile (balanced, or its top block the cause).
struct Board {
  bool pile = false;
  bool balanced = true;
};

struct Exhibit {
  runtime::LcmBus bus{harness::kLiveUrl};
  // What projection showed since the last forget(): its newest round and heartbeat.
  std::optional<round_t> round;
  std::optional<heartbeat_t> heartbeat;
  int64_t frame = 100;
  Board board;
  bool send_stacks = true;
  bool send_predictions = true;

  Exhibit() {
    bus.subscribe(channel(kRoundChannel), runtime::QueuePolicy::keep(1000), [this](const runtime::Received& r) {
      if (auto m = runtime::decode<round_t>(r.data, r.size)) round = *m;
    });
    bus.subscribe(channel(kHeartbeatChannel), runtime::QueuePolicy::keep(1000), [this](const runtime::Received& r) {
      auto h = runtime::decode<heartbeat_t>(r.data, r.size);
      if (h && h->module == "projection") heartbeat = *h;
    });
  }

  void send() {
    ++frame;
    bricklayer::stack_t s{};
    s.utime = bus.now_utime();
    s.frame_number = frame;
    s.block_length = 1;
    s.block_height = 1.0 / 3.0;
    s.status = bricklayer::stack_t::STATUS_OK;
    prediction_t p{};
    p.utime = s.utime;
    p.frame_number = frame;
    p.status = prediction_t::STATUS_OK;
    p.annotator = "exact";
    p.solver = "nnls";
    p.balanced = true;
    if (board.pile) {
      for (auto [id, row, x] : {std::tuple<int64_t, int, double>{1, 0, -0.8}, {2, 1, -0.7}}) {
        block_t b{};
        b.id = id;
        b.row = row;
        b.x = x;
        b.confidence = 1;
        s.blocks.push_back(b);
        block_prediction_t bp{};
        bp.id = id;
        bp.state = board.balanced || id == 1 ? block_prediction_t::STATE_STABLE : block_prediction_t::STATE_CAUSE;
        p.blocks.push_back(bp);
      }
      p.balanced = board.balanced;
      p.score = 30;
      p.overhang = 0.3;
    }
    s.num_blocks = static_cast<int32_t>(s.blocks.size());
    p.num_blocks = static_cast<int32_t>(p.blocks.size());
    if (send_stacks) REQUIRE(harness::publish(bus, channel(kStackChannel), s));
    if (send_predictions) REQUIRE(harness::publish(bus, channel(kPredictionChannel), p));
  }

  // Sends the board at 20 Hz and handles what comes back until done() or the timeout; returns done().
  bool until(const std::function<bool()>& done, std::chrono::milliseconds timeout) {
    const auto end = std::chrono::steady_clock::now() + timeout;
    auto next = std::chrono::steady_clock::now();
    while (!done() && std::chrono::steady_clock::now() < end) {
      if (std::chrono::steady_clock::now() >= next) {
        send();
        next += 50ms;
      }
      bus.handle(10);
    }
    return done();
  }
  void run_for(std::chrono::milliseconds d) { until([] { return false; }, d); }
  double value(const std::string& name) const {
    for (int k = 0; k < heartbeat->num_values; ++k)
      if (heartbeat->value_names[k] == name) return heartbeat->values[k];
    return -1;
  }
  void forget() {
    round.reset();
    heartbeat.reset();
  }
};

harness::Program start_projection(const harness::ScratchDir& dir) {
  return harness::Program("bricklayer-projection",
                          {"--headless", "--lcm-url", harness::kLiveUrl, "--mute", "--snapshot-dir", (dir / "shots").string(),
                           "--rounds-file", (dir / "rounds.json").string(), "--round-seconds", "30",
                           "--round-start-hold", "0.5", "--round-arm-empty", "0.3", "--round-end-empty", "1.5",
                           "--stale-seconds", "1"},
                          harness::ProgramOptions{{"SDL_AUDIODRIVER=dummy"}, ""});
}

}  // namespace

TEST_CASE("rounds run themselves and survive restarts, and stale inputs are shown instead of a frozen verdict") {
  harness::ScratchDir dir("projection-rounds");
  Exhibit ex;
  auto projection = std::make_unique<harness::Program>(start_projection(dir));
  REQUIRE(ex.until([&] { return ex.heartbeat.has_value(); }, 10s));

  // An empty board, then a pile: a round starts by itself after the hold.
  ex.run_for(800ms);
  REQUIRE(ex.round);
  CHECK(ex.round->state == round_t::STATE_IDLE);
  ex.board.pile = true;
  const auto placed = std::chrono::steady_clock::now();
  REQUIRE(ex.until([&] { return ex.round->state == round_t::STATE_RUNNING; }, 5s));
  CHECK(std::chrono::steady_clock::now() - placed >= 450ms);  // not before the hold
  REQUIRE(ex.until([&] { return ex.round->max_score == 30; }, 3s));
  CHECK(ex.round->duration_ms == 30000);
  const int64_t before_kill = ex.round->remaining_ms;

  // Killed mid-round and started again: the round runs on with its MAX.
  projection->signal(SIGKILL);
  projection->wait_exit(5s);
  ex.forget();
  projection = std::make_unique<harness::Program>(start_projection(dir));
  REQUIRE(ex.until([&] { return ex.round.has_value(); }, 10s));
  CHECK(ex.round->state == round_t::STATE_RUNNING);
  CHECK(ex.round->max_score == 30);
  CHECK(ex.round->remaining_ms <= before_kill);  // the same round, not a fresh one
  CHECK(ex.round->remaining_ms > 10000);

  // The players leave: the board stays empty for 1.5 s and the round ends early.
  ex.board.pile = false;
  const auto cleared = std::chrono::steady_clock::now();
  REQUIRE(ex.until([&] { return ex.round->state == round_t::STATE_ENDED; }, 5s));
  CHECK(std::chrono::steady_clock::now() - cleared >= 1400ms);
  CHECK(ex.round->max_score == 30);  // the last round's MAX stays on display
  REQUIRE(ex.until([&] { return ex.heartbeat && ex.value("rounds_today") == 1; }, 3s));
  CHECK(ex.value("day_best") == 30);
  CHECK(projection->stop().clean());

  const nlohmann::json book = nlohmann::json::parse(harness::read_file(dir / "rounds.json"));
  REQUIRE(book["rounds"].size() == 1);
  CHECK(book["rounds"][0]["max_score"] == 30);
  CHECK(book["rounds"][0]["blocks"] == 2);
  CHECK(book["rounds"][0]["most_blocks"] == 2);
  CHECK(book["rounds"][0]["end"] == "board cleared");
  CHECK(book["rounds"][0]["end_utime"].get<int64_t>() > book["rounds"][0]["start_utime"].get<int64_t>());
  CHECK(book["running"].is_null());

  // Between rounds, after a restart: the last round's MAX and the day's best are back.
  ex.forget();
  projection = std::make_unique<harness::Program>(start_projection(dir));
  REQUIRE(ex.until([&] { return ex.round.has_value() && ex.heartbeat.has_value(); }, 10s));
  CHECK(ex.round->state == round_t::STATE_ENDED);
  CHECK(ex.round->max_score == 30);
  CHECK(ex.value("day_best") == 30);
  CHECK(ex.value("rounds_today") == 1);

  // A red cause on the board, then the camera stops: the board says so and the red goes.
  ex.board.pile = true;
  ex.board.balanced = false;
  ex.run_for(600ms);
  ex.send_stacks = ex.send_predictions = false;
  REQUIRE(ex.until([&] { return ex.heartbeat->status.find("camera not seeing") != std::string::npos; }, 5s));
  REQUIRE(harness::publish(ex.bus, channel(kCommandChannel), [] {
    command_t c{};
    c.command = command_t::SNAPSHOT;
    return c;
  }()));
  // Snapshots are written to a temporary name and renamed: once the file is there, it is whole.
  const auto shot = dir / "shots" / "snapshot-0001.png";
  REQUIRE(ex.until([&] { return std::filesystem::exists(shot); }, 5s));
  const cv::Mat frame = cv::imread(shot.string(), cv::IMREAD_COLOR);
  REQUIRE_FALSE(frame.empty());
  const board::Point2 top = board::BoardToProjector{}.map(-0.7 + 0.5, 1.5 / 3.0);
  const cv::Vec3b px = frame.at<cv::Vec3b>(static_cast<int>(top.y), static_cast<int>(top.x));
  INFO("the cause's pixel BGR " << px);
  CHECK(px[2] < 60);  // not red any more
  CHECK(px[0] > 40);  // still shown, dim

  // Stacks again but no predictions: waiting for the other machine; both back: ok.
  ex.send_stacks = true;
  REQUIRE(ex.until([&] { return ex.heartbeat->status.find("waiting for the other machine") != std::string::npos; }, 5s));
  ex.send_predictions = true;
  REQUIRE(ex.until([&] { return ex.heartbeat->status == "ok"; }, 5s));
  CHECK(projection->stop().clean());
}
