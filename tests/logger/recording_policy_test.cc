// The recording policy: frames thinned to the reduced rate, every frame in the window around a moment
// (before it too), every other channel whole, everything in arrival order; answers to a frame thinned
// with it when asked.
#include <catch2/catch.hpp>

#include <map>
#include <set>

#include "bricklayer/image_t.hpp"
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
