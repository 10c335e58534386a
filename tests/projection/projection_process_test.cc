// NETNS: bricklayer-projection as a real process (SDL's offscreen video driver, dummy audio) on the real
// bus. A stack and its prediction in: the projector state names the frame it drew, a snapshot shows the
// cause red and the stable block blue where the default mapping puts them (nothing green). Rounds over
// BL_COMMAND: START -> RUNNING on BL_ROUND with the pile's score, time up -> ENDED with the best balanced
// score as MAX, RESET -> IDLE. Malformed messages are counted errors; SIGTERM ends it cleanly.
#include <catch2/catch.hpp>

#include <chrono>
#include <filesystem>
#include <functional>
#include <optional>

#include <opencv2/imgcodecs.hpp>

#include "bricklayer/command_t.hpp"
#include "bricklayer/common/channels.h"
#include "bricklayer/heartbeat_t.hpp"
#include "bricklayer/prediction_t.hpp"
#include "bricklayer/board/board_to_projector.h"
#include "bricklayer/projection/game_renderer.h"
#include "bricklayer/projector_state_t.hpp"
#include "bricklayer/round_t.hpp"
#include "bricklayer/runtime/lcm_bus.h"
#include "bricklayer/stack_t.hpp"
#include "harness/live_bus.h"
#include "harness/program.h"
#include "harness/recorder.h"
#include "harness/scratch.h"

using namespace bricklayer;
using namespace std::chrono_literals;
namespace fs = std::filesystem;

namespace {

bricklayer::stack_t pile(int64_t frame, double right_x) {
  bricklayer::stack_t s{};
  s.utime = frame * 1000;
  s.frame_number = frame;
  s.block_length = 1;
  s.block_height = 1.0 / 3.0;
  s.status = bricklayer::stack_t::STATUS_OK;
  for (auto [id, row, x] : {std::tuple<int64_t, int, double>{1, 0, -0.8}, {2, 1, right_x}}) {
    block_t b{};
    b.id = id;
    b.row = row;
    b.x = x;
    b.confidence = 1;
    s.blocks.push_back(b);
  }
  s.num_blocks = 2;
  return s;
}

prediction_t verdict(int64_t frame, bool balanced, int score) {
  prediction_t p{};
  p.utime = frame * 1000;
  p.frame_number = frame;
  p.status = prediction_t::STATUS_OK;
  p.balanced = balanced;
  p.score = score;
  p.overhang = score / 100.0;
  p.annotator = "exact";
  p.solver = "nnls";
  for (int64_t id : {1, 2}) {
    block_prediction_t b{};
    b.id = id;
    b.state = balanced || id == 1 ? block_prediction_t::STATE_STABLE : block_prediction_t::STATE_CAUSE;
    p.blocks.push_back(b);
  }
  p.num_blocks = 2;
  return p;
}

// The test's side of the bus: what projection shows now (its newest state, round and heartbeat).
struct Peer {
  runtime::LcmBus bus{harness::kLiveUrl};
  harness::Recorder rec = harness::Recorder::live(
      bus, {channel(kProjectorChannel), channel(kRoundChannel), channel(kHeartbeatChannel)});

  std::optional<projector_state_t> state() const { return rec.newest<projector_state_t>(channel(kProjectorChannel)); }
  std::optional<round_t> round() const { return rec.newest<round_t>(channel(kRoundChannel)); }
  std::optional<heartbeat_t> heartbeat() const { return rec.last_heartbeat("projection"); }
  // Handles messages until done() or the timeout; returns done().
  bool until(const std::function<bool()>& done, std::chrono::milliseconds timeout) { return rec.wait_until(done, timeout); }
  template <typename T>
  void send(const char* name, const T& msg) {
    REQUIRE(harness::publish(bus, channel(name), msg));
  }
  void command(int32_t which, int64_t sequence) {
    command_t c{};
    c.command = which;
    c.sequence = sequence;
    send(kCommandChannel, c);
  }
};

// The snapshot pixel at the centre of a block of the stack drawn with the default (uncalibrated) mapping.
cv::Vec3b centre_pixel(const cv::Mat& frame, int row, double x) {
  const board::BoardToProjector mapping;
  const double h = 1.0 / 3.0;
  const board::Point2 p = mapping.map(x + 0.5, (row + 0.5) * h);
  return frame.at<cv::Vec3b>(static_cast<int>(p.y), static_cast<int>(p.x));
}

}  // namespace

TEST_CASE("bricklayer-projection draws what it is told, runs rounds and survives bad input") {
  harness::ScratchDir dir("projection-process");
  Peer peer;
  harness::Program projection("bricklayer-projection",
                              {"--headless", "--lcm-url", harness::kLiveUrl, "--round-seconds", "2", "--snapshot-dir",
                               dir.str()},
                              harness::ProgramOptions{{"SDL_AUDIODRIVER=dummy"}, ""});  // no sound card here
  REQUIRE(peer.until([&] { return peer.heartbeat().has_value(); }, 10s));

  // A standing pile, then the same pile with its top block too far out.
  peer.send(kStackChannel, pile(10, -0.7));
  peer.send(kPredictionChannel, verdict(10, true, 30));
  REQUIRE(peer.until([&] { return peer.state() && peer.state()->frame_number == 10; }, 5s));
  CHECK(peer.state()->mode == projector_state_t::MODE_GAME);

  peer.command(command_t::START_ROUND, 1);
  REQUIRE(peer.until([&] { return peer.round() && peer.round()->state == round_t::STATE_RUNNING; }, 3s));
  const round_t running = *peer.round();
  CHECK(running.duration_ms == 2000);
  CHECK(running.score == 30);
  CHECK(running.num_blocks == 2);

  peer.send(kStackChannel, pile(11, 0.1));
  peer.send(kPredictionChannel, verdict(11, false, 110));
  REQUIRE(peer.until([&] { return peer.state() && peer.state()->frame_number == 11; }, 5s));
  peer.command(command_t::SNAPSHOT, 2);
  // Snapshots are written to a temporary name and renamed: once the file is there, it is whole.
  const fs::path shot = dir / "snapshot-0001.png";
  REQUIRE(peer.until([&] { return fs::exists(shot); }, 5s));
  const cv::Mat frame = cv::imread(shot.string(), cv::IMREAD_COLOR);
  REQUIRE(frame.size() == cv::Size(1024, 768));
  const cv::Vec3b bottom = centre_pixel(frame, 0, -0.8), top = centre_pixel(frame, 1, 0.1);
  INFO("bottom block BGR " << bottom << ", top block BGR " << top);
  CHECK(bottom[0] > 150);  // blue: stable
  CHECK(bottom[2] < 60);
  CHECK(top[2] > 150);  // red: the cause
  CHECK(top[0] < 60);
  std::vector<cv::Mat> channels;
  cv::split(frame, channels);
  CHECK(cv::countNonZero(channels[1]) == 0);  // only red and blue light (green leaks into the camera)

  // Time runs out: MAX is the best balanced score of the round (30), not the unbalanced 110.
  REQUIRE(peer.until([&] { return peer.round() && peer.round()->state == round_t::STATE_ENDED; }, 5s));
  CHECK(peer.round()->max_score == 30);
  CHECK(peer.round()->remaining_ms == 0);
  peer.command(command_t::RESET_ROUND, 3);
  REQUIRE(peer.until([&] { return peer.round() && peer.round()->state == round_t::STATE_IDLE; }, 3s));

  // Garbage on its inputs is counted, and it keeps drawing.
  const int64_t errors_before = peer.heartbeat()->errors;
  const std::vector<uint8_t> junk(37, 0xAB);
  for (const char* ch : {kStackChannel, kPredictionChannel, kCommandChannel, kCalibrationChannel})
    REQUIRE(harness::publish_bytes(peer.bus, channel(ch), junk));
  REQUIRE(peer.until([&] { return peer.heartbeat()->errors >= errors_before + 4; }, 4s));
  peer.send(kStackChannel, pile(12, -0.7));
  peer.send(kPredictionChannel, verdict(12, true, 30));
  CHECK(peer.until([&] { return peer.state() && peer.state()->frame_number == 12; }, 5s));

  CHECK(projection.stop().clean());
}
