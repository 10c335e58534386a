#include "bricklayer/vision/temporal_filter.h"

#include <catch2/catch.hpp>

#include <cmath>
#include <cstring>

using namespace bricklayer::vision;
using bricklayer::detection::DetectedBlock;

namespace {
DetectedBlock at(int row, double x) {
  DetectedBlock b;
  b.row = row;
  b.x = x;
  b.confidence = 1.0;
  return b;
}
}  // namespace

TEST_CASE("a block is published once seen in 2 of the last 3 frames, and keeps its id") {
  TemporalFilter f;  // confirm 2 of 3, hold 3, deadband 0.01
  CHECK(f.update({at(0, -0.5)}).empty());  // seen once: not yet
  auto two = f.update({at(0, -0.5)});
  REQUIRE(two.size() == 1);
  int64_t id = two[0].id;
  auto three = f.update({at(0, -0.502)});
  REQUIRE(three.size() == 1);
  CHECK(three[0].id == id);
  CHECK(three[0].block.x == Approx(-0.5));  // inside the deadband: unchanged
  auto moved = f.update({at(0, -0.45)});
  REQUIRE(moved.size() == 1);
  CHECK(moved[0].block.x == Approx(-0.45));  // beyond the deadband: follows
  CHECK(moved[0].id == id);
}

TEST_CASE("a lost block is held a few frames then dropped, and a one-frame flicker never appears") {
  TemporalFilter f;
  f.update({at(0, 0.1)});
  f.update({at(0, 0.1)});
  for (int k = 1; k <= 3; ++k) {
    auto held = f.update({});
    REQUIRE(held.size() == 1);
    CHECK(held[0].missed == k);
  }
  CHECK(f.update({}).empty());
  // A spurious detection in one frame only is never published.
  TemporalFilter g;
  CHECK(g.update({at(2, 1.0)}).empty());
  CHECK(g.update({}).empty());
  CHECK(g.update({}).empty());
}

TEST_CASE("blocks in different rows are different tracks") {
  TemporalFilter f;
  f.update({at(0, 0.0), at(1, 0.0)});
  auto both = f.update({at(0, 0.0), at(1, 0.0)});
  REQUIRE(both.size() == 2);
  CHECK(both[0].id != both[1].id);
}

TEST_CASE("the lag: how far the published x is from the latest measurement, the deadband while unseen") {
  TemporalFilter filter;  // deadband 0.01
  auto seen = [](double x) {
    DetectedBlock b;
    b.row = 0;
    b.x = x;
    return std::vector<DetectedBlock>{b};
  };
  filter.update(seen(-0.5));
  auto out = filter.update(seen(-0.5));
  REQUIRE(out.size() == 1);
  CHECK(out[0].lag == 0.0);
  out = filter.update(seen(-0.494));  // inside the deadband: published x kept, 0.006 behind
  REQUIRE(out.size() == 1);
  CHECK(out[0].block.x == -0.5);
  CHECK(out[0].lag == Approx(0.006));
  out = filter.update(seen(-0.48));  // outside: published, no lag
  CHECK(out[0].lag == 0.0);
  out = filter.update({});  // unseen, held
  REQUIRE(out.size() == 1);
  CHECK(out[0].lag == 0.01);
}

TEST_CASE("the spread: the standard deviation of a block's recent measured x, started afresh when it is moved") {
  TemporalFilter filter;
  auto seen = [](double x) { return std::vector<DetectedBlock>{at(0, x)}; };
  filter.update(seen(-0.500), {0.001});
  auto out = filter.update(seen(-0.502), {0.002});
  REQUIRE(out.size() == 1);
  CHECK(out[0].spread_samples == 2);
  CHECK(out[0].spread == Approx(std::sqrt(2.0) * 0.001));  // two samples 0.002 apart
  CHECK(out[0].measured_uncertainty == 0.002);             // the latest measurement's
  // Ten frames alternating around -0.501: the window keeps the last kSpreadFrames.
  for (int k = 0; k < 10; ++k) out = filter.update(seen(k % 2 ? -0.500 : -0.502), {0.003});
  CHECK(out[0].spread_samples == kSpreadFrames);
  CHECK(out[0].spread == Approx(0.001 * std::sqrt(8.0 / 7.0)));
  CHECK(out[0].block.x == -0.5);  // inside the deadband throughout
  // Unseen: the spread and the last measurement's uncertainty stay, the lag is the deadband.
  out = filter.update({});
  CHECK(out[0].spread_samples == kSpreadFrames);
  CHECK(out[0].measured_uncertainty == 0.003);
  // Moved by a hand (0.1, within the match distance, beyond the history reset): the history starts again.
  out = filter.update(seen(-0.4), {0.001});
  REQUIRE(out.size() == 1);
  CHECK(out[0].block.x == -0.4);
  CHECK(out[0].spread_samples == 1);
  CHECK(out[0].spread == 0.0);
  CHECK_THROWS_WITH(filter.update(seen(-0.4), {0.001, 0.002}), Catch::Contains("2 uncertainties for 1 detections"));
}

TEST_CASE("the spread depends only on the recent measurements, to the bit, not on how many came before") {
  // The same last kSpreadFrames measurements after histories one frame apart (a replay that sees a frame
  // the live process dropped): the ring holds them at other positions, the spread must not notice.
  auto last_spread = [](int extra) {
    TemporalFilter f;
    FilteredBlock last{};
    for (int i = -extra; i < 40; ++i) {
      const double x = 0.25 + 0.0013 * std::sin(1.7 * i) + 1e-7 * i;
      const auto out = f.update({at(0, x)});
      if (!out.empty()) last = out[0];
    }
    return last;
  };
  const FilteredBlock a = last_spread(0);
  for (int extra = 1; extra < kSpreadFrames; ++extra) {
    const FilteredBlock b = last_spread(extra);
    REQUIRE(b.spread_samples == a.spread_samples);
    CHECK(std::memcmp(&a.spread, &b.spread, sizeof(double)) == 0);
  }
}
