// The recording policy: frames thinned to the reduced rate, every frame in the window around a moment
// (before it too), every other channel whole, everything in arrival order; answers to a frame thinned
// with it when asked.
#include <catch2/catch.hpp>

#include <map>
#include <set>

#include "bricklayer/image_t.hpp"
#include "bricklayer/logger/event_writer.h"
#include "bricklayer/logger/recording_policy.h"
#include "bricklayer/prediction_t.hpp"
#include "bricklayer/stack_t.hpp"

using namespace bricklayer;

namespace {
logger::Event ev(const std::string& ch, int64_t t) { return {t, ch, {1, 2, 3}}; }
constexpr int64_t kFrameUs = 33'333;  // 30 frames a second
}  // namespace

TEST_CASE("without a moment frames are kept at the reduced rate, other channels whole, in order") {
  logger::RecordingPolicy p({"BL_IMAGE", 2, 10, 10});
  std::vector<logger::Event> out;
  for (int i = 0; i < 30 * 60; ++i) {  // a minute
    const int64_t t = i * kFrameUs;
    p.offer(ev("BL_IMAGE", t));
    p.offer(ev("BL_STACK", t + 1));
    for (auto& e : p.release(t + 1)) out.push_back(std::move(e));
  }
  for (auto& e : p.release_all()) out.push_back(std::move(e));
  int frames = 0, stacks = 0;
  for (size_t i = 1; i < out.size(); ++i) CHECK(out[i - 1].utime <= out[i].utime);
  for (const auto& e : out) (e.channel == "BL_IMAGE" ? frames : stacks)++;
  CHECK(stacks == 1800);
  CHECK(frames >= 119);
  CHECK(frames <= 121);
  CHECK(p.frames_kept() == frames);
  CHECK(p.frames_thinned() == 1800 - frames);
}

TEST_CASE("every frame from before_s before a moment to after_s after it is kept") {
  logger::RecordingPolicy p({"BL_IMAGE", 1, 2, 3});
  std::vector<int64_t> kept;
  const int64_t moment = 20'000'000;
  for (int i = 0; i < 30 * 40; ++i) {
    const int64_t t = i * kFrameUs;
    p.offer(ev("BL_IMAGE", t));
    if (t >= moment && t - kFrameUs < moment) p.moment(t);
    for (auto& e : p.release(t)) kept.push_back(e.utime);
  }
  for (auto& e : p.release_all()) kept.push_back(e.utime);
  int in_window = 0, outside = 0;
  for (int64_t t : kept) (t >= moment - 2'000'000 && t <= moment + 3'000'000 + kFrameUs ? in_window : outside)++;
  CHECK(in_window >= 5 * 30 - 1);  // every frame of the 5 s window
  CHECK(outside >= 33);            // about one a second for the other 35 s
  CHECK(outside <= 37);
  // Held no longer than before_s: a frame leaves once its window's start can no longer move.
  logger::RecordingPolicy q({"BL_IMAGE", 1, 2, 3});
  q.offer(ev("BL_IMAGE", 0));
  CHECK(q.release(1'999'999).empty());
  CHECK(q.release(2'000'000).size() == 1);
}

TEST_CASE("rate 0 keeps every frame and holds nothing, and bad figures are refused") {
  logger::RecordingPolicy p({"BL_IMAGE", 0, 10, 10});
  CHECK_FALSE(p.thins());
  p.offer(ev("BL_IMAGE", 5));
  CHECK(p.release(5).size() == 1);
  CHECK_THROWS_AS(logger::RecordingPolicy({"BL_IMAGE", -1, 10, 10}), std::invalid_argument);
  CHECK_THROWS_AS(logger::RecordingPolicy({"BL_IMAGE", 1, std::nan(""), 10}), std::invalid_argument);
}

TEST_CASE("held bytes are bounded: the oldest leave early") {
  logger::FramePolicyOptions o{"BL_IMAGE", 1, 10, 10};
  o.max_held_bytes = 10 * 39;  // ten events of 39 bytes in a file (28 + "BL_STACK" + 3 data bytes)
  logger::RecordingPolicy p(o);
  for (int i = 0; i < 100; ++i) p.offer(ev("BL_STACK", i));
  const auto out = p.release(0);
  CHECK(out.size() >= 80);
  CHECK(p.held_bytes() <= o.max_held_bytes);
}

namespace {
template <typename T>
logger::Event encoded(const std::string& ch, int64_t arrival, const T& msg) {
  logger::Event e{arrival, ch, std::vector<uint8_t>(static_cast<size_t>(msg.getEncodedSize()))};
  msg.encode(e.data.data(), 0, static_cast<int>(e.data.size()));
  return e;
}
}  // namespace

TEST_CASE("with answer channels, a thinned frame's stack and prediction go with it, and the windows keep all") {
  logger::FramePolicyOptions o{"BL_IMAGE", 2, 2, 3};
  o.answer_channels = {"BL_STACK", "BL_PREDICTION"};
  logger::RecordingPolicy p(o);
  std::vector<logger::Event> out;
  const int64_t moment = 20'000'000, camera_clock = 1'700'000'000'000'000;  // the frames' own clock
  for (int i = 0; i < 30 * 40; ++i) {
    const int64_t t = i * kFrameUs;
    image_t frame{};
    frame.utime = camera_clock + t;
    frame.frame_number = 1000 + i;
    frame.size = 0;
    stack_t stack{};
    stack.utime = frame.utime;
    stack.frame_number = frame.frame_number;
    prediction_t prediction{};
    prediction.utime = frame.utime;
    prediction.frame_number = frame.frame_number;
    p.offer(encoded("BL_IMAGE", t, frame));
    p.offer(encoded("BL_STACK", t + 2000, stack));
    p.offer(encoded("BL_PREDICTION", t + 3000, prediction));
    p.offer(ev("BL_HEARTBEAT", t + 4000));
    if (t >= moment && t - kFrameUs < moment) p.moment(t);
    for (auto& e : p.release(t)) out.push_back(std::move(e));
  }
  // An answer to a frame never seen, and one too short to name a frame: both kept.
  stack_t stray{};
  stray.utime = 5;
  stray.frame_number = 5;
  p.offer(encoded("BL_STACK", 40'000'000, stray));
  p.offer(logger::Event{40'000'001, "BL_PREDICTION", {1, 2, 3}});
  for (auto& e : p.release_all()) out.push_back(std::move(e));

  std::map<std::string, std::set<std::pair<int64_t, int64_t>>> keys;
  std::map<std::string, int> count;
  for (const auto& e : out) {
    ++count[e.channel];
    if (e.channel == "BL_HEARTBEAT" || e.data.size() < 24) continue;
    int64_t utime = 0, number = 0;
    for (int b = 0; b < 8; ++b) utime = (utime << 8) | e.data[8 + b], number = (number << 8) | e.data[16 + b];
    keys[e.channel].insert({utime, number});
  }
  keys["BL_STACK"].erase({5, 5});
  CHECK(count["BL_HEARTBEAT"] == 1200);  // other channels whole
  CHECK(keys["BL_STACK"] == keys["BL_IMAGE"]);
  CHECK(keys["BL_PREDICTION"] == keys["BL_IMAGE"]);
  CHECK(count["BL_STACK"] == p.frames_kept() + 1);
  CHECK(count["BL_PREDICTION"] == p.frames_kept() + 1);
  CHECK(p.answers_thinned() == 2 * p.frames_thinned());
  // The window (2 s before to 3 s after 20 s) kept every frame and so every answer; outside, 2 a second.
  int in_window = 0;
  for (const auto& [utime, number] : keys["BL_STACK"])
    in_window += utime - camera_clock >= moment - 2'000'000 && utime - camera_clock <= moment + 3'000'000;
  CHECK(in_window >= 5 * 30 - 1);
  CHECK(p.frames_kept() <= 5 * 30 + 1 + 2 * 35 + 2);
  CHECK(p.frames_thinned() > 900);
}

TEST_CASE("without answer channels every stack is kept, whatever became of its frame") {
  logger::RecordingPolicy p({"BL_IMAGE", 2, 1, 1});
  for (int i = 0; i < 300; ++i) {
    image_t frame{};
    frame.utime = i;
    frame.frame_number = i;
    stack_t stack{};
    stack.utime = i;
    stack.frame_number = i;
    p.offer(encoded("BL_IMAGE", i * kFrameUs, frame));
    p.offer(encoded("BL_STACK", i * kFrameUs + 1, stack));
  }
  int stacks = 0;
  for (const auto& e : p.release_all()) stacks += e.channel == "BL_STACK";
  CHECK(stacks == 300);
  CHECK(p.answers_thinned() == 0);
  CHECK(p.frames_thinned() > 250);
}

namespace {
// Frames of `bytes` each at 30 a second for `seconds`, a moment every `every_s` seconds (0: none) and an
// exempt one at `mark_s` (< 0: none), through the policy; the bytes kept per frame time.
struct AllowanceRun {
  int64_t kept_bytes = 0, kept_frames = 0;
  std::vector<int64_t> kept_times;
};
logger::FramePolicyOptions with_allowance(double mb_per_hour) {
  logger::FramePolicyOptions o;
  o.rate = 2;
  o.max_mb_per_hour = mb_per_hour;
  return o;
}
AllowanceRun run_allowance(logger::RecordingPolicy& p, double seconds, int bytes, double every_s, double mark_s = -1) {
  AllowanceRun r;
  const int64_t every = static_cast<int64_t>(every_s * 1e6), mark = static_cast<int64_t>(mark_s * 1e6);
  const auto n = static_cast<int64_t>(seconds * 30);
  auto take = [&](std::vector<logger::Event> out) {
    for (const auto& e : out) {
      r.kept_bytes += logger::EventWriter::file_size_of(e);
      ++r.kept_frames;
      r.kept_times.push_back(e.utime);
    }
  };
  for (int64_t i = 0; i < n; ++i) {
    const int64_t t = i * kFrameUs;
    p.offer({t, "BL_IMAGE", std::vector<uint8_t>(static_cast<size_t>(bytes), 7)});
    if (every > 0 && t / every != (t - kFrameUs) / every && i > 0) p.moment(t);
    if (mark >= 0 && t >= mark && t - kFrameUs < mark) p.moment(t, true);
    take(p.release(t));
  }
  take(p.release_all());
  return r;
}
}  // namespace

TEST_CASE("the hourly allowance bounds a busy recording: windows full rate only while it can pay") {
  // 10 kB frames: the reduced rate (2 a second) costs 72 MB an hour, full rate 1080 MB. A moment every
  // 20 s with 10 s windows each side would keep every frame; an allowance of 200 MB an hour holds
  // 3 hours to at most (3 + 1) * 200 MB, and one frame (the last may overdraw it).
  logger::RecordingPolicy capped(with_allowance(200));
  const AllowanceRun r = run_allowance(capped, 3 * 3600, 10'000, 20);
  CHECK(r.kept_bytes <= 4 * 200'000'000LL + 10'100);
  CHECK(r.kept_bytes > 3 * 200'000'000LL);  // the allowance is spent, not wasted
  CHECK(capped.window_frames_refused() > 0);
  // Every frame is in a window but for the first and the last 10 s (moments from 20 s to 10780 s): every
  // one of them is kept or counted as refused.
  CHECK(capped.window_frames_refused() + capped.frames_kept() > 3 * 3600 * 30 - 20 * 30);
  // The reduced rate is never given up: every half second holds a frame.
  for (size_t i = 1; i < r.kept_times.size(); ++i) REQUIRE(r.kept_times[i] - r.kept_times[i - 1] <= 500'000 + kFrameUs);
  // Without the allowance the same day keeps every frame but in its first and last 10 s.
  logger::RecordingPolicy uncapped(with_allowance(0));
  const AllowanceRun all = run_allowance(uncapped, 3 * 3600, 10'000, 20);
  CHECK(all.kept_frames > 3 * 3600 * 30 - 20 * 30);
  CHECK(all.kept_bytes > 3 * 1000'000'000LL);
  CHECK(uncapped.window_frames_refused() == 0);
}

TEST_CASE("an allowance the recording stays within changes nothing, and a quiet hour refills it") {
  // One moment every 10 minutes: 20 s of 1080 MB/hour full rate each, 6 an hour = 36 MB + 72 MB reduced.
  logger::RecordingPolicy p(with_allowance(200));
  logger::RecordingPolicy free_run(with_allowance(0));
  const AllowanceRun a = run_allowance(p, 2 * 3600, 10'000, 600), b = run_allowance(free_run, 2 * 3600, 10'000, 600);
  CHECK(p.window_frames_refused() == 0);
  CHECK(a.kept_times == b.kept_times);
}

TEST_CASE("an operator's mark keeps its whole window when the allowance is spent") {
  // 2 kB frames: 14 MB an hour reduced, 216 at full rate: 30 MB an hour is spent within minutes.
  logger::RecordingPolicy p(with_allowance(30));
  const double mark_s = 1800;
  const AllowanceRun r = run_allowance(p, 3600, 2'000, 20, mark_s);
  CHECK(p.window_frames_refused() > 0);
  int in_mark_window = 0;
  for (int64_t t : r.kept_times)
    if (t >= (mark_s - 10) * 1e6 && t <= (mark_s + 10) * 1e6) ++in_mark_window;
  CHECK(in_mark_window >= 20 * 30 - 2);
  // A window as busy at 1200 s, not exempt: the spent allowance keeps it near the reduced rate.
  int in_other_window = 0;
  for (int64_t t : r.kept_times)
    if (t >= 1190e6 && t <= 1210e6) ++in_other_window;
  CHECK(in_other_window < 20 * 30 / 2);
  // A negative or non-finite allowance is refused.
  CHECK_THROWS_AS(logger::RecordingPolicy(with_allowance(-1)), std::invalid_argument);
}
