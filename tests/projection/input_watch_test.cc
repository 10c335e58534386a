// Input staleness on a stepped clock: silence from the start, stacks stopping (camera not seeing),
// predictions stopping while stacks flow (waiting for the other machine), recovery, and "never".
#include "bricklayer/projection/input_watch.h"

#include <catch2/catch.hpp>

using namespace bricklayer::projection;

namespace {
constexpr int64_t kS = 1'000'000;
}

TEST_CASE("no stacks for longer than the limit: camera not seeing, no predictions: waiting for the other machine") {
  const int64_t t0 = 1'781'000'000'000'000;
  InputWatch w(t0, 3 * kS);
  CHECK(w.problem(t0 + 3 * kS) == InputProblem::kNone);  // at the limit: not yet
  CHECK(w.problem(t0 + 3 * kS + 1) == InputProblem::kCameraNotSeeing);  // nothing since the start
  CHECK(w.status(t0 + 7 * kS) == "camera not seeing: no stacks for 7 s");
  w.stack_seen(t0 + 8 * kS);
  w.prediction_seen(t0 + 8 * kS);
  CHECK(w.problem(t0 + 9 * kS) == InputProblem::kNone);
  CHECK(w.status(t0 + 9 * kS).empty());
  // Stacks keep coming, predictions stop.
  for (int k = 9; k <= 15; ++k) w.stack_seen(t0 + k * kS);
  CHECK(w.problem(t0 + 11 * kS) == InputProblem::kNone);
  CHECK(w.problem(t0 + 15 * kS) == InputProblem::kWaitingForOtherMachine);
  CHECK(w.status(t0 + 15 * kS) == "waiting for the other machine: no predictions for 7 s");
  CHECK(std::string(input_problem_words(w.problem(t0 + 15 * kS))) == "waiting for the other machine");
  // Both stop: the camera side is what is missing first.
  CHECK(w.problem(t0 + 20 * kS) == InputProblem::kCameraNotSeeing);
  w.stack_seen(t0 + 21 * kS);
  w.prediction_seen(t0 + 21 * kS);
  CHECK(w.problem(t0 + 21 * kS) == InputProblem::kNone);
}

TEST_CASE("a limit of 0 never reports staleness") {
  InputWatch w(0, 0);
  CHECK(w.problem(1000 * kS) == InputProblem::kNone);
  CHECK(w.status(1000 * kS).empty());
  CHECK(std::string(input_problem_words(InputProblem::kNone)).empty());
}
