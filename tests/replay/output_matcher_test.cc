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
