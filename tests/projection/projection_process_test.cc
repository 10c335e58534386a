// NETNS: bricklayer-projection as a real process (SDL's offscreen video driver, dummy audio) on the real
// bus. A stack and its prediction in: the projector state names the frame it drew, a snapshot shows the
// cause red and the stable block blue where the default mapping puts them (nothing green). Rounds over
// BL_COMMAND: START -> RUNNING on BL_ROUND with the pile's score, time up -> ENDED with the best balanced
// score as MAX, RESET -> IDLE. Malformed messages are counted errors; SIGTERM ends it cleanly.
#include <catch2/catch.hpp>

#include <unistd.h>

#include <chrono>
#include <cstdlib>
#include <filesystem>
#include <functional>
#include <optional>

#include <opencv2/imgcodecs.hpp>

#include "../common/spawn_util.h"
#include "bricklayer/command_t.hpp"
#include "bricklayer/common/channels.h"
#include "bricklayer/common/module.h"
#include "bricklayer/heartbeat_t.hpp"
#include "bricklayer/prediction_t.hpp"
#include "bricklayer/board/board_to_projector.h"
#include "bricklayer/projection/game_renderer.h"
#include "bricklayer/projector_state_t.hpp"
#include "bricklayer/round_t.hpp"
#include "bricklayer/stack_t.hpp"

using namespace bricklayer;
namespace fs = std::filesystem;

namespace {

constexpr const char* kUrl = "udpm://239.255.76.67:7667?ttl=0";

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

struct Bus {
  Module m{"test", kUrl};
  std::optional<projector_state_t> state;
  std::optional<round_t> round;
  std::optional<heartbeat_t> heartbeat;
  Bus() {
    m.subscribe<projector_state_t>(channel(kProjectorChannel), [this](const projector_state_t& s) { state = s; });
    m.subscribe<round_t>(channel(kRoundChannel), [this](const round_t& r) { round = r; });
    m.subscribe<heartbeat_t>(channel(kHeartbeatChannel), [this](const heartbeat_t& h) {
      if (h.module == "projection") heartbeat = h;
    });
  }
  // Handles messages until done() or the timeout; returns done().
  bool until(const std::function<bool()>& done, int timeout_ms) {
    const auto end = std::chrono::steady_clock::now() + std::chrono::milliseconds(timeout_ms);
    while (!done() && std::chrono::steady_clock::now() < end) m.lcm().handleTimeout(20);
    return done();
  }
  void command(int32_t which, int64_t sequence) {
    command_t c{};
    c.command = which;
    c.sequence = sequence;
    m.publish(channel(kCommandChannel), c);
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
  const fs::path dir = fs::temp_directory_path() / ("bricklayer-projection-process-" + std::to_string(getpid()));
  fs::remove_all(dir);
  fs::create_directories(dir);
  setenv("SDL_AUDIODRIVER", "dummy", 1);  // inherited by the child: no sound card here
  Bus bus;
  const pid_t projection = test::spawn({test::program("bricklayer-projection"), "--headless", "--lcm-url", kUrl,
                                        "--round-seconds", "2", "--snapshot-dir", dir.string()});
  REQUIRE(bus.until([&] { return bus.heartbeat.has_value(); }, 10000));

  // A standing pile, then the same pile with its top block too far out.
  bus.m.publish(channel(kStackChannel), pile(10, -0.7));
  bus.m.publish(channel(kPredictionChannel), verdict(10, true, 30));
  REQUIRE(bus.until([&] { return bus.state && bus.state->frame_number == 10; }, 5000));
  CHECK(bus.state->mode == projector_state_t::MODE_GAME);

  bus.command(command_t::START_ROUND, 1);
  REQUIRE(bus.until([&] { return bus.round && bus.round->state == round_t::STATE_RUNNING; }, 3000));
  CHECK(bus.round->duration_ms == 2000);
  CHECK(bus.round->score == 30);
  CHECK(bus.round->num_blocks == 2);

  bus.m.publish(channel(kStackChannel), pile(11, 0.1));
  bus.m.publish(channel(kPredictionChannel), verdict(11, false, 110));
  REQUIRE(bus.until([&] { return bus.state && bus.state->frame_number == 11; }, 5000));
  bus.command(command_t::SNAPSHOT, 2);
  const fs::path shot = dir / "snapshot-0001.png";
  REQUIRE(bus.until([&] { return fs::exists(shot) && fs::file_size(shot) > 0; }, 5000));
  usleep(200000);  // the file is written in one call; give it a moment to be complete on disk
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
  REQUIRE(bus.until([&] { return bus.round && bus.round->state == round_t::STATE_ENDED; }, 5000));
  CHECK(bus.round->max_score == 30);
  CHECK(bus.round->remaining_ms == 0);
  bus.command(command_t::RESET_ROUND, 3);
  REQUIRE(bus.until([&] { return bus.round && bus.round->state == round_t::STATE_IDLE; }, 3000));

  // Garbage on its inputs is counted, and it keeps drawing.
  const int64_t errors_before = bus.heartbeat->errors;
  const std::vector<uint8_t> junk(37, 0xAB);
  for (const char* ch : {kStackChannel, kPredictionChannel, kCommandChannel, kCalibrationChannel})
    bus.m.lcm().publish(channel(ch), junk.data(), static_cast<unsigned>(junk.size()));
  REQUIRE(bus.until([&] { return bus.heartbeat->errors >= errors_before + 4; }, 4000));
  bus.m.publish(channel(kStackChannel), pile(12, -0.7));
  bus.m.publish(channel(kPredictionChannel), verdict(12, true, 30));
  CHECK(bus.until([&] { return bus.state && bus.state->frame_number == 12; }, 5000));

  CHECK(test::stop(projection) == 0);
  fs::remove_all(dir);
}
