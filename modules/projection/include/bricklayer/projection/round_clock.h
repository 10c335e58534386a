// The round: a countdown (3 minutes by default) started and reset by command or keyboard, the
// current score and MAX, the best balanced score seen while the round runs. Pure: time comes from an
// injected clock (milliseconds, any epoch), so tests step it without waiting.
#pragma once

#include <cstdint>
#include <functional>

namespace bricklayer::projection {

class RoundClock {
 public:
  enum class State : int8_t { kIdle = 0, kRunning = 1, kEnded = 2 };  // = round_t::STATE_*
  using Clock = std::function<int64_t()>;  // milliseconds, monotonic

  // Throws std::invalid_argument unless duration_ms > 0.
  RoundClock(int64_t duration_ms, Clock clock);

  // START: a fresh round (timer full, MAX 0), also when one is running. RESET: idle, timer full, MAX 0.
  void start();
  void reset();
  // Advances the state with the clock (RUNNING -> ENDED when time is up). Returns true when anything a
  // display or round_t shows changed since the previous call (state, whole seconds left, score, MAX).
  bool update();

  // The pile now: its score and whether the newest prediction for it says balanced. MAX takes the
  // score only while the round runs and only when balanced.
  void set_pile(int score, bool balanced);

  State state() const { return state_; }
  int64_t duration_ms() const { return duration_ms_; }
  int64_t remaining_ms() const;
  int score() const { return score_; }
  int max_score() const { return max_score_; }

 private:
  void advance();  // RUNNING -> ENDED when due; notes a change of the whole seconds shown

  int64_t duration_ms_;
  Clock clock_;
  State state_ = State::kIdle;
  int64_t started_ms_ = 0;
  int score_ = 0;
  int max_score_ = 0;
  bool changed_ = true;
  int64_t shown_seconds_ = -1;
};

}  // namespace bricklayer::projection
