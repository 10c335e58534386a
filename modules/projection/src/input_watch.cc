#include "bricklayer/projection/input_watch.h"

namespace bricklayer::projection {

const char* input_problem_words(InputProblem problem) {
  switch (problem) {
    case InputProblem::kCameraNotSeeing: return "camera not seeing";
    case InputProblem::kWaitingForOtherMachine: return "waiting for the other machine";
    case InputProblem::kNone: break;
  }
  return "";
}

InputProblem InputWatch::problem(int64_t now) const {
  if (after_ <= 0) return InputProblem::kNone;
  if (stacks_silent_us(now) > after_) return InputProblem::kCameraNotSeeing;
  // Predictions answer stacks: silence only counts once stacks flow (checked above).
  if (predictions_silent_us(now) > after_) return InputProblem::kWaitingForOtherMachine;
  return InputProblem::kNone;
}

std::string InputWatch::status(int64_t now) const {
  const InputProblem p = problem(now);
  if (p == InputProblem::kNone) return "";
  const int64_t silent = p == InputProblem::kCameraNotSeeing ? stacks_silent_us(now) : predictions_silent_us(now);
  return std::string(input_problem_words(p)) + ": no " +
         (p == InputProblem::kCameraNotSeeing ? "stacks" : "predictions") + " for " +
         std::to_string(silent / 1000000) + " s";
}

}  // namespace bricklayer::projection
