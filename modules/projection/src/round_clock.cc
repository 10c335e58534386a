#include "bricklayer/projection/round_clock.h"

#include <algorithm>
#include <stdexcept>
#include <string>

namespace bricklayer::projection {

RoundClock::RoundClock(int64_t duration_ms, Clock clock) : duration_ms_(duration_ms), clock_(std::move(clock)) {
  if (duration_ms <= 0) throw std::invalid_argument("round duration must be positive, got " + std::to_string(duration_ms) + " ms");
  if (!clock_) throw std::invalid_argument("round clock needs a clock");
}

void RoundClock::start() {
  state_ = State::kRunning;
  started_ms_ = clock_();
  max_score_ = 0;
  changed_ = true;
}

void RoundClock::reset() {
  state_ = State::kIdle;
  max_score_ = 0;
  changed_ = true;
}

int64_t RoundClock::remaining_ms() const {
  switch (state_) {
    case State::kIdle: return duration_ms_;
    case State::kEnded: return 0;
    case State::kRunning: break;
  }
  return std::clamp<int64_t>(duration_ms_ - (clock_() - started_ms_), 0, duration_ms_);
}

void RoundClock::advance() {
  if (state_ == State::kRunning && clock_() - started_ms_ >= duration_ms_) {
    state_ = State::kEnded;
    changed_ = true;
  }
  // Whole seconds as displayed (rounded up: "0:01" until the very end).
  const int64_t seconds = (remaining_ms() + 999) / 1000;
  if (seconds != shown_seconds_) {
    shown_seconds_ = seconds;
    changed_ = true;
  }
}

bool RoundClock::update() {
  advance();
  const bool out = changed_;
  changed_ = false;
  return out;
}

void RoundClock::set_pile(int score, bool balanced) {
  advance();  // a round that has just ended must not take a late score
  if (score != score_) {
    score_ = score;
    changed_ = true;
  }
  if (state_ == State::kRunning && balanced && score > max_score_) {
    max_score_ = score;
    changed_ = true;
  }
}

}  // namespace bricklayer::projection
