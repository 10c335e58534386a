// The recording policy: frames thinned to the reduced rate, every frame in the window around a moment
// (before it too), every other channel whole, everything in arrival order.
#include <catch2/catch.hpp>

#include "bricklayer/logger/recording_policy.h"

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
