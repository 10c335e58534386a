// Whether what projection draws is still live. Without it a camera that stops or a host that goes
// away leaves the last verdict on the board for as long as the outage lasts, and players read a
// frozen red or blue as the truth. Pure: times are the runtime clock's, passed in.
//
//   no stack for stale_after          -> kCameraNotSeeing ("camera not seeing")
//   stacks, but no prediction for it  -> kWaitingForOtherMachine ("waiting for the other machine")
// Before the first message the silence counts from the start.
#pragma once

#include <cstdint>
#include <optional>
#include <string>

namespace bricklayer::projection {

enum class InputProblem : int8_t { kNone = 0, kCameraNotSeeing = 1, kWaitingForOtherMachine = 2 };

// The words on the board: "camera not seeing", "waiting for the other machine", "".
const char* input_problem_words(InputProblem problem);

class InputWatch {
 public:
  // stale_after_us <= 0: never stale. Throws nothing.
  InputWatch(int64_t start_utime, int64_t stale_after_us) : start_(start_utime), after_(stale_after_us) {}

  void stack_seen(int64_t now) { last_stack_ = now; }
  void prediction_seen(int64_t now) { last_prediction_ = now; }

  InputProblem problem(int64_t now) const;
  // Microseconds since the last stack / prediction (or since the start).
  int64_t stacks_silent_us(int64_t now) const { return now - last_stack_.value_or(start_); }
  int64_t predictions_silent_us(int64_t now) const { return now - last_prediction_.value_or(start_); }
  // For the heartbeat: "camera not seeing: no stacks for 7 s", or "".
  std::string status(int64_t now) const;

 private:
  int64_t start_;
  int64_t after_;
  std::optional<int64_t> last_stack_;
  std::optional<int64_t> last_prediction_;
};

}  // namespace bricklayer::projection
