// OutputMatcher: pairs by the input answered, in either order; what stays alone past the window.
#include <catch2/catch.hpp>

#include "bricklayer/prediction_t.hpp"
#include "bricklayer/replay/output_matcher.h"
#include "bricklayer/runtime/codec.h"

using namespace bricklayer;

namespace {
std::vector<uint8_t> answer(int64_t utime, int64_t frame, int32_t score = 0) {
  prediction_t p{};
  p.utime = utime;
  p.frame_number = frame;
  p.score = score;
  return runtime::encode(p);
}
}  // namespace

TEST_CASE("outputs pair by utime and frame number in either order, and the rest is settled after the window") {
  const replay::MessageDiff diff;
  std::vector<replay::Pair> pairs;
  int alone[2] = {0, 0};
  replay::OutputMatcher m(
      diff, [&](const replay::Pair& p) { pairs.push_back(p); }, [&](const replay::MessageKey&, int side) { ++alone[side]; },
      1'000'000);
  m.add(0, "P", answer(10, 1, 5), 100);
  m.add(1, "P", answer(10, 1, 6), 150);  // replayed after recorded
  m.add(1, "P", answer(20, 2), 200);
  m.add(0, "P", answer(20, 2), 250);     // recorded after replayed
  m.add(1, "P", answer(30, 3), 300);     // never recorded (dropped live)
  m.add(0, "Q", answer(30, 3), 310);     // another channel: not its pair
  REQUIRE(pairs.size() == 2);
  CHECK(pairs[0].key.frame_number == 1);
  CHECK(pairs[0].a == answer(10, 1, 5));  // side 0 is a
  CHECK(pairs[0].b == answer(10, 1, 6));
  m.advance(1'000'000);
  CHECK(alone[0] + alone[1] == 0);  // still within the window
  m.advance(1'400'000);
  CHECK(alone[1] == 1);
  CHECK(alone[0] == 1);
  // The same input answered twice (a restart live) pairs twice.
  m.add(0, "P", answer(40, 4), 2'000'000);
  m.add(0, "P", answer(40, 4), 2'000'001);
  m.add(1, "P", answer(40, 4), 2'000'002);
  m.add(1, "P", answer(40, 4), 2'000'003);
  m.finish();
  CHECK(pairs.size() == 4);
  CHECK(alone[0] == 1);
}

namespace {
std::vector<uint8_t> state(int64_t utime, int64_t frame, int32_t score = 0) { return answer(utime, frame, score); }
}  // namespace

TEST_CASE("on a channel stamped at a tick, outputs unpaired by key pair by nearest time, in order, about the same input") {
  const replay::MessageDiff diff;
  std::vector<replay::Pair> pairs;
  int alone[2] = {0, 0};
  replay::OutputMatcher m(
      diff, [&](const replay::Pair& p) { pairs.push_back(p); }, [&](const replay::MessageKey&, int side) { ++alone[side]; },
      10'000'000);
  m.set_nearest({"T"}, 50'000, 1'000'000);
  // Recorded (live ticks) and replayed (the replay's ticks), the stamps a few ms apart.
  m.add(0, "T", state(1'000'000, 1, 1), 1'000'300);
  m.add(1, "T", state(1'002'000, 1, 1), 1'002'000);
  // Two outputs 1 ms apart on each side: paired in order, not crosswise, though the replayed first
  // one is nearer the recorded second.
  m.add(0, "T", state(2'000'000, 2, 20), 2'000'100);
  m.add(0, "T", state(2'001'000, 2, 21), 2'001'100);
  m.add(1, "T", state(2'000'500, 2, 20), 2'000'500);
  m.add(1, "T", state(2'000'900, 2, 21), 2'000'900);
  // The same stamp on both: paired by key at once.
  m.add(0, "T", state(3'000'000, 3), 3'000'000);
  m.add(1, "T", state(3'000'000, 3), 3'000'000);
  REQUIRE(pairs.size() == 1);
  CHECK_FALSE(pairs[0].nearest);
  // Near in time but about another input (another stack drawn): never paired.
  m.add(0, "T", state(4'000'000, 40), 4'000'100);
  m.add(1, "T", state(4'001'000, 41), 4'001'000);
  // About the same input but too far apart.
  m.add(0, "T", state(5'000'000, 5), 5'000'100);
  m.add(1, "T", state(5'060'000, 5), 5'060'000);
  // Not decided while outputs within the tolerance may still come.
  m.advance(1'500'000);
  CHECK(pairs.size() == 1);
  m.advance(7'000'000);
  REQUIRE(pairs.size() == 4);
  CHECK(pairs[1].nearest);
  CHECK(pairs[1].a == state(1'000'000, 1, 1));
  CHECK(pairs[1].b == state(1'002'000, 1, 1));
  CHECK(pairs[1].key.utime == 1'000'000);  // the recorded one's
  CHECK(pairs[1].b_stamp_utime == 1'002'000);
  CHECK(pairs[2].a == state(2'000'000, 2, 20));
  CHECK(pairs[2].b == state(2'000'500, 2, 20));
  CHECK(pairs[3].a == state(2'001'000, 2, 21));
  CHECK(pairs[3].b == state(2'000'900, 2, 21));
  // Settled alone long before the 10-s window: nothing within the tolerance can pair them.
  CHECK(alone[0] == 2);
  CHECK(alone[1] == 2);
  m.finish();
  CHECK(pairs.size() == 4);
  // Another channel still pairs only by key.
  m.add(0, "P", state(8'000'000, 8), 8'000'000);
  m.add(1, "P", state(8'001'000, 8), 8'001'000);
  m.finish();
  CHECK(pairs.size() == 4);
  CHECK(alone[0] == 3);
}
