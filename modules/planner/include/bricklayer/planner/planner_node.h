// bricklayer-planner's node: how the pile will fall and where the next block should go.
//
// Subscribes: BL_STACK (stack_t): the newest stacks are remembered (the last 16) to match predictions
//             against and to compute hints for; invalid stacks are counted errors.
//             BL_PREDICTION (prediction_t), newest wins: an unbalanced prediction whose stack was seen is
//             answered with a collapse preview; balanced ones need nothing.
//             BL_COMMAND (command_t): REQUEST_HINT asks for a hint for the newest stack (answered as soon as
//             a stack is known); other commands are ignored.
// Publishes:  BL_PREVIEW (collapse_preview_t) carrying the utime and frame_number of the stack it answers.
//             BL_HINT (hint_t) for the newest stack on each REQUEST_HINT.
//             BL_HEARTBEAT once a second ("no predictions for N s" when prediction falls silent).
#pragma once

#include "bricklayer/command_t.hpp"
#include "bricklayer/planner/planner_logic.h"
#include "bricklayer/runtime/node.h"

namespace bricklayer::planner {

class PlannerNode final : public runtime::Node {
 public:
  using Config = PlannerConfig;
  static constexpr const char* kProgram = "bricklayer-planner";
  static constexpr const char* kSummary =
      "Publishes a collapse preview (BL_PREVIEW) for every unbalanced prediction and a next-block hint\n"
      "(BL_HINT) for the newest stack on each REQUEST_HINT command.";
  static constexpr double kStaleAfterS = 5.0;

  PlannerNode(const Config& config, runtime::Bus& bus);

 protected:
  void tick() override;

 private:
  void on_stack(const stack_t& s);
  void on_prediction(const prediction_t& p);

  PlannerLogic logic_;
  std::string preview_channel_, hint_channel_;
  bool hint_requested_ = false;
};

}  // namespace bricklayer::planner
