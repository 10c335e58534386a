// NETNS, real processes: the headless demo (simcam -> vision -> prediction -> projection, bricklayer-logger
// under bricklayer-launch) recorded on the real LCM bus, and bricklayer-replay --module projection --check on
// its log. Live, projection stamps its outputs (round_t, projector states with their PNG, the status JPEG)
// at its own loop ticks, which the log does not hold: they pair by nearest stamp time, compared without
// their tick-dependent fields.
// - every channel compares (N > 0 each), with 0 mismatches, and the tick-dependent fields are listed;
// - a tampered round_t (its score), a tampered projector state (a block's colour in its PNG) and a
//   tampered status JPEG are caught: exit 1, the channel, time and field named.
#include <catch2/catch.hpp>

#include <algorithm>
#include <cstdlib>
#include <filesystem>
#include <regex>

#include <nlohmann/json.hpp>
#include <opencv2/imgcodecs.hpp>

#include "bricklayer/common/channels.h"
#include "bricklayer/image_t.hpp"
#include "bricklayer/projector_state_t.hpp"
#include "bricklayer/round_t.hpp"
#include "bricklayer/runtime/codec.h"
#include "bricklayer/runtime/log_file.h"
#include "harness/demo_profile.h"
#include "harness/live_bus.h"
#include "harness/program.h"
#include "harness/scratch.h"
#include "replay_cli.h"

using namespace bricklayer;
using namespace bricklayer::test;
using namespace std::chrono_literals;
namespace fs = std::filesystem;

namespace {

// The shipped demo profile run headless for 8 s, its log and snapshots in a scratch folder (as
// test_launcher_demo runs it). Recorded once for every test case.
const std::string& demo_log() {
  static harness::ScratchDir dir("replay-live-demo");
  static const std::string log = [] {
    const harness::DemoProfile demo = harness::scratch_demo_profile(dir);
    const harness::Ran launch = harness::run_program(
        "bricklayer-launch", {"--root", BRICKLAYER_SOURCE_DIR, "--duration", "8", demo.file.string()}, 60s,
        harness::ProgramOptions{{"DISPLAY=", "SDL_AUDIODRIVER=dummy", std::string("LCM_DEFAULT_URL=") + harness::kLiveUrl}, ""});
    INFO(launch.out << launch.err);
    REQUIRE_FALSE(launch.timed_out);
    REQUIRE(launch.status.clean());
    REQUIRE(fs::exists(dir / "demo.00"));
    return (dir / "demo.00").string();
  }();
  return log;
}

// "paired by nearest time: BL_PROJECTOR 8 BL_ROUND 12" -> the count for one channel (0 if absent).
int64_t nearest_on(const std::string& out, const std::string& ch) {
  std::smatch m;
  return std::regex_search(out, m, std::regex("paired by nearest time:.* " + ch + R"( (\d+))")) ? std::stoll(m[1]) : 0;
}

// The replayed projection's outputs on the demo log: (channel, frame_number or -1, stamp).
struct Stamp {
  std::string channel;
  int64_t frame_number, utime;
};
std::vector<Stamp> replayed_stamps(const harness::ScratchDir& dir) {
  const std::string outputs = (dir / "outputs.lcm").string();
  const auto r = replay({demo_log(), "--module", "projection", "--record-outputs", outputs});
  REQUIRE(r.status.code == 0);
  std::vector<Stamp> out;
  runtime::LogReader reader(outputs);
  runtime::LogEvent e;
  while (reader.next(e)) {
    if (e.channel == channel(kProjectorChannel)) {
      if (auto s = runtime::decode<projector_state_t>(e.data)) out.push_back({e.channel, s->frame_number, s->utime});
    } else if (e.channel == channel(kProjectorImageChannel)) {
      if (auto im = runtime::decode<image_t>(e.data)) out.push_back({e.channel, im->frame_number, im->utime});
    } else if (e.channel == channel(kRoundChannel)) {
      if (auto round = runtime::decode<round_t>(e.data)) out.push_back({e.channel, -1, round->utime});
    }
  }
  return out;
}

// The log times of projection's inputs in the demo log (what it reads: projection_node.h).
std::vector<int64_t> input_utimes() {
  const std::vector<std::string> inputs = {channel(kStackChannel),   channel(kPredictionChannel), channel(kCalibrationChannel),
                                           channel(kHintChannel),    channel(kPreviewChannel),    channel(kStudySessionChannel),
                                           channel(kStudyProblemChannel), channel(kCommandChannel)};
  std::vector<int64_t> out;
  runtime::LogReader reader(demo_log());
  runtime::LogEvent e;
  while (reader.next(e))
    if (std::find(inputs.begin(), inputs.end(), e.channel) != inputs.end()) out.push_back(e.utime);
  return out;
}

// Whether a recorded output is compared: a replayed one about the same input within 50 ms, and no input
// delivered between their stamps or 10 ms before the earlier (the others are counted, never compared,
// so tampering with one would prove nothing).
bool compared(const std::vector<Stamp>& replayed, const std::vector<int64_t>& inputs, const std::string& ch,
              int64_t frame_number, int64_t utime) {
  return std::any_of(replayed.begin(), replayed.end(), [&](const Stamp& s) {
    if (s.channel != ch || s.frame_number != frame_number || std::llabs(s.utime - utime) > 50'000) return false;
    const int64_t lo = std::min(s.utime, utime) - 10'000, hi = std::max(s.utime, utime);
    return std::none_of(inputs.begin(), inputs.end(), [&](int64_t t) { return t > lo && t <= hi; });
  });
}

}  // namespace

TEST_CASE("projection replays the live-recorded demo with 0 mismatches on every channel, its tick-stamped outputs paired by nearest time") {
  const auto r = replay({demo_log(), "--module", "projection", "--check"});
  INFO(r.out << r.err);
  CHECK(r.status.code == 0);
  CHECK(compared_ok(r.out) >= 3);
  // 8 s of demo: a round_t a second and on every change, projector states on change (at most 15 a
  // second), a status JPEG every 2 s. Every channel compares (pairs whose ticks saw other inputs are
  // counted, not compared), some by nearest time (live stamps).
  for (const std::string ch : {"BL_ROUND", "BL_PROJECTOR", "BL_PROJECTOR_IMAGE"}) {
    INFO(ch);
    CHECK(compared_on(r.out, ch) > 0);
  }
  CHECK(nearest_on(r.out, "BL_PROJECTOR") + nearest_on(r.out, "BL_PROJECTOR_IMAGE") + nearest_on(r.out, "BL_ROUND") > 0);
  CHECK(r.out.find("paired with a replayed one") == std::string::npos);  // no channel left without pairs
  // The fields left out are listed: run-to-run, and tick-dependent for pairs by nearest time.
  CHECK(r.err.find("never compared (run-to-run): ") != std::string::npos);
  CHECK(r.err.find("projector_state_t.image.frame_number") != std::string::npos);
  CHECK(r.err.find("such pairs also leave out (tick-dependent): round_t.utime, round_t.remaining_ms, "
                   "projector_state_t.utime, projector_state_t.image.utime, image_t.utime") != std::string::npos);
}

TEST_CASE("a tampered output of projection on the live-recorded demo is caught and named") {
  harness::ScratchDir dir("replay-live-tamper");
  const std::vector<Stamp> replayed = replayed_stamps(dir);
  const std::vector<int64_t> inputs = input_utimes();
  SECTION("round_t: the score") {
    const std::string log = tampered(dir, demo_log(), [&](runtime::LogEvent& e) {
      if (e.channel != channel(kRoundChannel)) return false;
      auto r = runtime::decode<round_t>(e.data);
      if (!r || !compared(replayed, inputs, e.channel, -1, r->utime)) return false;
      r->score += 7;
      e.data = runtime::encode(*r);
      return true;
    });
    const auto r = replay({log, "--module", "projection", "--check"});
    INFO(r.out << r.err);
    CHECK(r.status.code == 1);
    CHECK(std::regex_search(
        r.out, std::regex(R"(first divergence: BL_ROUND \(round_t\) at \d\d:\d\d:\d\d\.\d{3} \(\+[0-9.]+ s\)[^\n]*: score: \d+ \(log\) vs \d+ \(replay\))")));
    CHECK(r.out.find(" compared, 1 mismatches") != std::string::npos);
  }
  SECTION("projector_state_t: a block's colour in its picture") {
    const std::string log = tampered(dir, demo_log(), [&](runtime::LogEvent& e) {
      if (e.channel != channel(kProjectorChannel)) return false;
      auto s = runtime::decode<projector_state_t>(e.data);
      if (!s || s->mode != projector_state_t::MODE_GAME || !compared(replayed, inputs, e.channel, s->frame_number, s->utime))
        return false;
      cv::Mat im = cv::imdecode(s->image.data, cv::IMREAD_COLOR);
      // The most saturated blue pixel (a stable block's light) made red, with its neighbours.
      int best = -1;
      cv::Point at;
      for (int y = 0; y < im.rows; ++y)
        for (int x = 0; x < im.cols; ++x) {
          const cv::Vec3b p = im.at<cv::Vec3b>(y, x);
          const int blueness = p[0] - std::max(p[1], p[2]);
          if (blueness > best) {
            best = blueness;
            at = {x, y};
          }
        }
      if (best >= 100) {
        for (int y = std::max(0, at.y - 1); y <= std::min(im.rows - 1, at.y + 1); ++y)
          for (int x = std::max(0, at.x - 1); x <= std::min(im.cols - 1, at.x + 1); ++x) {
            cv::Vec3b& p = im.at<cv::Vec3b>(y, x);
            std::swap(p[0], p[2]);
          }
      } else {
        im.at<cv::Vec3b>(5, 7) = cv::Vec3b(0, 255, 0);  // no block drawn: one green pixel, which the game never draws
      }
      s->image.data.clear();
      cv::imencode(".png", im, s->image.data);
      s->image.size = static_cast<int32_t>(s->image.data.size());
      e.data = runtime::encode(*s);
      return true;
    });
    const auto r = replay({log, "--module", "projection", "--check"});
    INFO(r.out << r.err);
    CHECK(r.status.code == 1);
    CHECK(std::regex_search(
        r.out, std::regex(R"(first divergence: BL_PROJECTOR \(projector_state_t\) at \d\d:\d\d:\d\d\.\d{3} [^\n]*image\.data: the recorded picture \(log\) vs pixels differ by up to \d+ levels)")));
    CHECK(r.out.find(" compared, 1 mismatches") != std::string::npos);
  }
  SECTION("the status JPEG: its size") {
    const std::string log = tampered(dir, demo_log(), [&](runtime::LogEvent& e) {
      if (e.channel != channel(kProjectorImageChannel)) return false;
      auto im = runtime::decode<image_t>(e.data);
      if (!im || !compared(replayed, inputs, e.channel, im->frame_number, im->utime)) return false;
      im->width += 1;
      e.data = runtime::encode(*im);
      return true;
    });
    const auto r = replay({log, "--module", "projection", "--check"});
    INFO(r.out << r.err);
    CHECK(r.status.code == 1);
    CHECK(std::regex_search(r.out, std::regex(R"(first divergence: BL_PROJECTOR_IMAGE \(image_t\) at [^\n]*: width: \d+ \(log\) vs \d+ \(replay\))")));
  }
}
