#include "bricklayer/projection/round_clock.h"

#include <catch2/catch.hpp>

using namespace bricklayer::projection;
using State = RoundClock::State;

TEST_CASE("a round counts down three minutes and ends, keeping MAX until reset") {
  int64_t now = 1000;
  RoundClock round(180000, [&] { return now; });
  CHECK(round.update());  // first call: everything is new
  CHECK(round.state() == State::kIdle);
  CHECK(round.remaining_ms() == 180000);

  round.start();
  CHECK(round.update());
  CHECK(round.state() == State::kRunning);
  now += 400;
  CHECK_FALSE(round.update());  // still "3:00" shown (seconds round up)
  now += 700;
  CHECK(round.update());  // 2:59
  CHECK(round.remaining_ms() == 180000 - 1100);

  round.set_pile(120, true);
  CHECK(round.max_score() == 120);
  round.set_pile(180, false);  // unbalanced: shown as score, not MAX
  CHECK(round.score() == 180);
  CHECK(round.max_score() == 120);
  round.set_pile(90, true);
  CHECK(round.max_score() == 120);

  now += 178900;
  CHECK(round.update());
  CHECK(round.state() == State::kEnded);
  CHECK(round.remaining_ms() == 0);
  round.set_pile(300, true);  // after the end: no more MAX
  CHECK(round.max_score() == 120);
  CHECK(round.score() == 300);

  round.reset();
  CHECK(round.update());
  CHECK(round.state() == State::kIdle);
  CHECK(round.max_score() == 0);
  CHECK(round.remaining_ms() == 180000);
}

TEST_CASE("MAX is not recorded while idle, and START begins a fresh round") {
  int64_t now = 0;
  RoundClock round(5000, [&] { return now; });
  round.set_pile(200, true);
  CHECK(round.max_score() == 0);
  round.start();
  round.set_pile(200, true);
  CHECK(round.max_score() == 200);
  now += 3000;
  round.start();  // restart while running
  CHECK(round.max_score() == 0);
  CHECK(round.remaining_ms() == 5000);
  round.set_pile(150, true);
  CHECK(round.max_score() == 150);
  now += 5000;
  round.update();
  CHECK(round.state() == State::kEnded);
}

TEST_CASE("a score that arrives after the deadline does not count even without an update in between") {
  int64_t now = 0;
  RoundClock round(1000, [&] { return now; });
  round.start();
  now = 1500;
  round.set_pile(500, true);
  CHECK(round.max_score() == 0);
  CHECK(round.state() == State::kEnded);
}

TEST_CASE("a round needs a positive duration") {
  CHECK_THROWS(RoundClock(0, [] { return int64_t{0}; }));
}
