// The rounds' state machine on a stepped clock: every transition (auto start after the hold, the
// hand that passes, the gap in the stacks, time up, board cleared, START and RESET at any state), MAX
// only balanced and only while running, the history and the day's best, restore after a restart.
#include "bricklayer/projection/round_referee.h"

#include <cmath>
#include <ctime>

#include <catch2/catch.hpp>

using namespace bricklayer::projection;
using State = RoundState;

namespace {
constexpr int64_t kS = 1'000'000;  // one second in microseconds
constexpr int64_t kMs = 1'000;

// Local noon of a day, microseconds: day arithmetic stays inside one calendar day in any time zone.
int64_t local_noon(int year, int month, int day) {
  std::tm tm{};
  tm.tm_year = year - 1900;
  tm.tm_mon = month - 1;
  tm.tm_mday = day;
  tm.tm_hour = 12;
  tm.tm_isdst = -1;
  return static_cast<int64_t>(std::mktime(&tm)) * kS;
}

// Stacks at 10 Hz from `from` for `seconds`, each with `blocks` blocks; returns the time after the last.
int64_t feed(RoundReferee& r, int64_t from, double seconds, int blocks) {
  const int64_t end = from + std::llround(seconds * kS);
  int64_t t = from;
  for (; t < end; t += 100 * kMs) r.board_seen(t, blocks);
  return t;
}

RoundRules quick_rules() {
  RoundRules rules;
  rules.duration_us = 60 * kS;
  rules.start_hold_us = 2 * kS;
  rules.arm_empty_us = 1 * kS;
  rules.end_empty_us = 10 * kS;
  rules.max_gap_us = 1 * kS;
  return rules;
}
}  // namespace

TEST_CASE("blocks held on a board seen empty start a round by themselves") {
  const int64_t t0 = local_noon(2026, 6, 15);
  RoundReferee r(quick_rules());
  CHECK(r.update(t0));
  CHECK(r.state() == State::kIdle);
  int64_t t = feed(r, t0, 1.5, 0);  // empty for 1.5 s: armed
  t = feed(r, t, 2.0, 2);           // blocks seen for 1.9 s: still holding
  CHECK(r.state() == State::kIdle);
  r.board_seen(t, 2);  // 2.0 s: it starts
  CHECK(r.state() == State::kRunning);
  REQUIRE(r.running());
  CHECK(r.running()->start_utime == t);
  CHECK(r.running()->most_blocks == 2);
  CHECK(r.update(t));
  CHECK(r.remaining_ms(t) == 60000);
  CHECK(r.rounds_today(t) == 1);
}

TEST_CASE("a hand passing by does not start a round") {
  const int64_t t0 = local_noon(2026, 6, 15);
  RoundReferee r(quick_rules());
  int64_t t = feed(r, t0, 1.5, 0);
  t = feed(r, t, 0.6, 1);  // seen for 0.6 s
  t = feed(r, t, 0.3, 0);  // gone again
  t = feed(r, t, 1.5, 1);  // back, but the hold starts again: 1.5 s < 2 s
  CHECK(r.state() == State::kIdle);
  t = feed(r, t, 0.6, 1);
  CHECK(r.state() == State::kRunning);
  (void)t;
}

TEST_CASE("a board never seen empty does not start a round, nor does a pile left from the last one") {
  const int64_t t0 = local_noon(2026, 6, 15);
  RoundReferee r(quick_rules());
  int64_t t = feed(r, t0, 10, 3);  // blocks since the start: not "appearing on an empty board"
  CHECK(r.state() == State::kIdle);
  t = feed(r, t, 0.5, 0);  // empty only 0.5 s (a flicker): not armed
  t = feed(r, t, 5, 3);
  CHECK(r.state() == State::kIdle);
  t = feed(r, t, 1.1, 0);
  t = feed(r, t, 2.1, 3);
  CHECK(r.state() == State::kRunning);
  // Time up with the pile still standing: ended, and that pile does not start the next round.
  t = feed(r, t, 61, 3);
  CHECK(r.state() == State::kEnded);
  REQUIRE(r.last_round());
  CHECK(r.last_round()->end == RoundEnd::kTimeUp);
  t = feed(r, t, 30, 3);
  CHECK(r.state() == State::kEnded);
  t = feed(r, t, 1.1, 0);
  t = feed(r, t, 2.1, 1);
  CHECK(r.state() == State::kRunning);
  CHECK(r.rounds_today(t) == 2);
}

TEST_CASE("a gap in the stacks is neither an empty board nor a steady pile") {
  const int64_t t0 = local_noon(2026, 6, 15);
  RoundReferee r(quick_rules());
  int64_t t = feed(r, t0, 1.5, 0);
  r.board_seen(t, 2);
  r.board_seen(t + 5 * kS, 2);  // the camera was gone for 5 s: the hold starts again here
  CHECK(r.state() == State::kIdle);
  t = feed(r, t + 5 * kS, 2.1, 2);
  REQUIRE(r.state() == State::kRunning);
  // During the round: the camera goes away with an empty board seen; no stacks is not "empty".
  t = feed(r, t, 3, 0);
  r.board_seen(t + 20 * kS, 0);  // 20 s later, one empty stack: the empty time restarts
  CHECK(r.state() == State::kRunning);
  // Nor does a gap arm the next round: ended by time, a gap, then blocks.
  RoundReferee q(quick_rules());
  int64_t u = feed(q, t0, 1.5, 0);
  u = feed(q, u, 2.1, 1);
  REQUIRE(q.state() == State::kRunning);
  u = feed(q, u, 60, 1);
  REQUIRE(q.state() == State::kEnded);
  q.board_seen(u, 0);
  q.board_seen(u + 3 * kS, 0);  // "empty" across a 3 s gap: not seen empty for 1 s
  u = feed(q, u + 3 * kS + 100 * kMs, 0.5, 0);
  u = feed(q, u, 2.5, 1);
  CHECK(q.state() == State::kEnded);
}

TEST_CASE("a round lasts its duration, and ends early when the board stays empty") {
  const int64_t t0 = local_noon(2026, 6, 15);
  RoundReferee r(quick_rules());
  int64_t t = feed(r, t0, 1.5, 0);
  t = feed(r, t, 2.1, 4);
  REQUIRE(r.state() == State::kRunning);
  const int64_t start = r.running()->start_utime;
  CHECK(r.remaining_ms(start + 20 * kS) == 40000);
  r.update(start + 20 * kS);
  CHECK_FALSE(r.update(start + 20 * kS + 300 * kMs));
  CHECK(r.update(start + 21 * kS + 1));  // the shown seconds changed
  CHECK(r.update(start + 60 * kS));
  CHECK(r.state() == State::kEnded);
  REQUIRE(r.last_round());
  CHECK(r.last_round()->end_utime == start + 60 * kS);  // the scheduled end, not when it was noticed
  CHECK(r.remaining_ms(start + 61 * kS) == 0);

  // Early end: players leave; 9.9 s of empty board is not enough, 10 s is.
  RoundReferee e(quick_rules());
  int64_t u = feed(e, t0, 1.5, 0);
  u = feed(e, u, 2.1, 3);
  REQUIRE(e.state() == State::kRunning);
  u = feed(e, u, 5, 3);
  const int64_t cleared = u;
  u = feed(e, u, 9.95, 0);
  CHECK(e.state() == State::kRunning);
  e.board_seen(cleared + 10 * kS, 0);
  CHECK(e.state() == State::kEnded);
  CHECK(e.last_round()->end == RoundEnd::kBoardCleared);
  CHECK(e.last_round()->end_utime == cleared + 10 * kS);
  CHECK(e.last_round()->most_blocks == 3);
}

TEST_CASE("MAX takes only balanced scores while a round runs, the history keeps it with its blocks") {
  const int64_t t0 = local_noon(2026, 6, 15);
  RoundReferee r(quick_rules());
  r.pile(t0, 200, true, 3);  // idle: shown as score, not MAX
  CHECK(r.score() == 200);
  CHECK(r.max_score() == 0);
  int64_t t = feed(r, t0, 1.5, 0);
  t = feed(r, t, 2.1, 2);
  REQUIRE(r.state() == State::kRunning);
  const uint64_t before = r.revision();
  r.pile(t, 120, true, 3);
  CHECK(r.max_score() == 120);
  CHECK(r.revision() > before);  // a new MAX is worth saving
  r.pile(t, 180, false, 4);  // unbalanced
  CHECK(r.score() == 180);
  CHECK(r.max_score() == 120);
  r.pile(t, 90, true, 2);
  CHECK(r.max_score() == 120);
  t = feed(r, t, 3, 5);
  CHECK(r.running()->most_blocks == 5);
  r.pile(r.running()->start_utime + 60 * kS, 300, true, 5);  // at the end: too late
  CHECK(r.state() == State::kEnded);
  CHECK(r.max_score() == 120);  // between rounds: the last round's MAX
  REQUIRE(r.last_round());
  CHECK(r.last_round()->max_score == 120);
  CHECK(r.last_round()->blocks == 3);
  CHECK(r.last_round()->most_blocks == 5);
}

TEST_CASE("START and RESET work in every state and are recorded") {
  const int64_t t0 = local_noon(2026, 6, 15);
  RoundReferee r(quick_rules());
  r.start(t0);  // idle -> running, even on a board never seen
  CHECK(r.state() == State::kRunning);
  r.pile(t0 + kS, 150, true, 2);
  r.start(t0 + 3 * kS);  // running -> a fresh round; the old one recorded as restarted
  CHECK(r.state() == State::kRunning);
  CHECK(r.max_score() == 0);
  CHECK(r.remaining_ms(t0 + 3 * kS) == 60000);
  REQUIRE(r.history().size() == 1);
  CHECK(r.history()[0].end == RoundEnd::kRestarted);
  CHECK(r.history()[0].max_score == 150);
  CHECK(r.history()[0].end_utime == t0 + 3 * kS);
  r.pile(t0 + 4 * kS, 90, true, 2);
  r.reset(t0 + 5 * kS);  // running -> idle, MAX 0
  CHECK(r.state() == State::kIdle);
  CHECK(r.max_score() == 0);
  REQUIRE(r.history().size() == 2);
  CHECK(r.history()[1].end == RoundEnd::kReset);
  CHECK(r.day_best(t0 + 5 * kS) == 150);  // every recorded round counts for the day
  r.reset(t0 + 6 * kS);  // idle -> idle: nothing recorded
  CHECK(r.history().size() == 2);
  // After START the next automatic round needs a cleared board again.
  r.start(t0 + 7 * kS);
  r.board_seen(t0 + 7 * kS, 0);
  r.update(t0 + 67 * kS);
  CHECK(r.state() == State::kEnded);
  r.start(t0 + 70 * kS);  // ended -> running
  CHECK(r.state() == State::kRunning);
  CHECK(r.history().size() == 3);
  // Without automatic rounds only START starts one.
  RoundRules manual = quick_rules();
  manual.auto_start = false;
  RoundReferee m(manual);
  int64_t t = feed(m, t0, 2, 0);
  t = feed(m, t, 5, 3);
  CHECK(m.state() == State::kIdle);
}

TEST_CASE("the day's best is the best MAX of the rounds that started today") {
  const int64_t day1 = local_noon(2026, 6, 15), day2 = local_noon(2026, 6, 16);
  RoundReferee r(quick_rules());
  auto play = [&r](int64_t at, int score) {
    r.start(at);
    r.pile(at + kS, score, true, 3);
    r.update(at + 61 * kS);
  };
  play(day1, 250);
  play(day1 + 600 * kS, 180);
  CHECK(r.day_best(day1 + 700 * kS) == 250);
  CHECK(r.rounds_today(day1 + 700 * kS) == 2);
  CHECK(r.day_best(day2) == 0);  // a new day
  CHECK(r.rounds_today(day2) == 0);
  CHECK(r.update(day2));  // the day's best shown changed at midnight
  play(day2, 120);
  CHECK(r.day_best(day2 + 100 * kS) == 120);
  r.start(day2 + 200 * kS);
  r.pile(day2 + 201 * kS, 300, true, 4);
  CHECK(r.day_best(day2 + 202 * kS) == 300);  // the running round counts
  CHECK(r.rounds_today(day2 + 202 * kS) == 2);
  CHECK(local_day(day2) == 20260616);
}

TEST_CASE("restore after a restart: history kept, a round in time runs on, one past its time is closed") {
  const int64_t t0 = local_noon(2026, 6, 15);
  RoundRecord done{t0, t0 + 60 * kS, 240, 4, 5, RoundEnd::kTimeUp};
  RoundRecord running{t0 + 100 * kS, 0, 130, 2, 3, RoundEnd::kTimeUp};
  {
    RoundReferee r(quick_rules());
    r.restore({done}, running, t0 + 130 * kS);
    CHECK(r.state() == State::kRunning);
    CHECK(r.max_score() == 130);
    CHECK(r.remaining_ms(t0 + 130 * kS) == 30000);
    CHECK(r.day_best(t0 + 130 * kS) == 240);
    r.update(t0 + 160 * kS);
    CHECK(r.state() == State::kEnded);
    CHECK(r.history().back().end_utime == t0 + 160 * kS);
  }
  {
    RoundReferee r(quick_rules());
    r.restore({done}, running, t0 + 500 * kS);  // down for longer than the round
    CHECK(r.state() == State::kEnded);
    REQUIRE(r.history().size() == 2);
    CHECK(r.history().back().end_utime == t0 + 160 * kS);
    CHECK(r.history().back().max_score == 130);
    CHECK(r.max_score() == 130);  // between rounds: the last round's MAX
  }
  {
    RoundReferee r(quick_rules());
    RoundRecord reset = done;
    reset.end = RoundEnd::kReset;
    r.restore({reset}, std::nullopt, t0 + 500 * kS);
    CHECK(r.state() == State::kIdle);
    CHECK(r.max_score() == 0);
    CHECK(r.day_best(t0 + 500 * kS) == 240);
  }
  {
    RoundRules rules = quick_rules();
    rules.history_limit = 2;
    RoundReferee r(rules);
    r.restore({done, done, done}, std::nullopt, t0 + 500 * kS);
    CHECK(r.history().size() == 2);
  }
}

TEST_CASE("round rules are checked, and end names read back") {
  RoundRules bad;
  bad.duration_us = 0;
  CHECK_THROWS_AS(RoundReferee(bad), std::invalid_argument);
  bad = RoundRules{};
  bad.start_hold_us = -1;
  CHECK_THROWS_AS(RoundReferee(bad), std::invalid_argument);
  for (RoundEnd e : {RoundEnd::kTimeUp, RoundEnd::kBoardCleared, RoundEnd::kRestarted, RoundEnd::kReset})
    CHECK(parse_round_end(round_end_name(e)) == e);
  CHECK_FALSE(parse_round_end("lunch"));
}
