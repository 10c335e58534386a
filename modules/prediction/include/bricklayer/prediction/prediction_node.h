// bricklayer-prediction's node: the collapse prediction on the bus.
//
// Subscribes: BL_STACK (stack_t), newest wins: a stack that arrives while one waits replaces it (counted
//             as dropped). Messages larger than --max-blocks allows, malformed bytes and other types are
//             counted errors.
// Publishes:  BL_PREDICTION (prediction_t) for every stack handled, carrying the stack's utime and
//             frame_number; a pure function of that stack (PredictionLogic) except `verdict`, which the
//             hysteresis derives from the answers in order (replays of the same log reproduce it).
//             BL_TIMING (timing_t, stage "predict"): the run-to-run timing, kept out of prediction_t.
//             BL_HEARTBEAT once a second (status "no stacks for N s" when vision falls silent).
#pragma once

#include "bricklayer/prediction/prediction_logic.h"
#include "bricklayer/prediction/verdict_hysteresis.h"
#include "bricklayer/runtime/node.h"

namespace bricklayer::prediction {

class PredictionNode final : public runtime::Node {
 public:
  using Config = PredictionConfig;
  static constexpr const char* kProgram = "bricklayer-prediction";
  static constexpr const char* kSummary =
      "Answers every stack_t on BL_STACK with a prediction_t on BL_PREDICTION (newest stack wins),\n"
      "timings on BL_TIMING, a heartbeat on BL_HEARTBEAT every second.";
  // A stack channel silent this long turns the status to "no stacks for N s".
  static constexpr double kStaleAfterS = 5.0;

  // Throws std::invalid_argument for a bad configuration.
  PredictionNode(const Config& config, runtime::Bus& bus);

  const PredictionLogic& logic() const { return logic_; }

 private:
  void on_stack(const stack_t& stack);

  PredictionLogic logic_;
  VerdictHysteresis hysteresis_;
  std::string prediction_channel_, timing_channel_;
};

}  // namespace bricklayer::prediction
