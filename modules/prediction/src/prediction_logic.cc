#include "bricklayer/prediction/prediction_logic.h"

#include <algorithm>
#include <stdexcept>

#include "bricklayer/core/program.h"
#include "bricklayer/messages/prediction.h"
#include "bricklayer/messages/stack.h"

namespace bricklayer::prediction {
namespace {

prediction_t empty_answer(const stack_t& stack, const PredictionConfig& config, int8_t status, std::string error) {
  prediction_t p{};
  p.utime = stack.utime;
  p.frame_number = stack.frame_number;
  p.status = status;
  p.error = std::move(error);
  p.balanced = false;
  p.overhang = 0.0;
  p.score = 0;
  p.annotator = config.annotator;
  p.solver = config.solver;
  p.position_tolerance = config.position_tolerance;
  p.num_blocks = 0;
  return p;
}

}  // namespace

size_t max_stack_message_bytes(size_t max_blocks) {
  // fingerprint 8 + utime, frame_number, 3 doubles 40 + status 1 + num_blocks 4; one block_t is
  // id 8 + row 4 + x 8 + corners 64 + confidence 8 = 92 bytes. Slack for future additive fields.
  return 256 + 92 * max_blocks;
}

PredictionLogic::PredictionLogic(PredictionConfig config, Predictor predictor)
    : config_(std::move(config)), predictor_(std::move(predictor)) {
  if (config_.max_blocks < 1) throw std::invalid_argument("--max-blocks must be at least 1");
  options_.annotator = core::parse_annotator(config_.annotator);
  if (lp_backend_of(config_.solver) != config_.solver) {
    std::string known;
    for (const auto& n : core::opt::solver_names()) known += (known.empty() ? "" : ", ") + n;
    throw std::invalid_argument("unknown solver \"" + config_.solver + "\" (expected " + known + ")");
  }
  options_.solver = config_.solver;
  options_.limits.max_blocks = static_cast<size_t>(config_.max_blocks);
  if (!(config_.position_tolerance >= 0.0 && config_.position_tolerance <= core::kMaxPositionTolerance)) {
    throw std::invalid_argument("--position-tolerance must be in [0, " + std::to_string(core::kMaxPositionTolerance) +
                                "] block lengths");
  }
  options_.position_tolerance = config_.position_tolerance;
  if (!predictor_) predictor_ = [](const core::Stack& s, const core::PredictOptions& o) { return core::predict(s, o); };
}

std::string lp_backend_of(const std::string& recorded_solver) {
  const std::string head = recorded_solver.substr(0, recorded_solver.find('+'));
  const auto names = core::opt::solver_names();
  return std::find(names.begin(), names.end(), head) != names.end() ? head : "";
}

prediction_t PredictionLogic::answer(const stack_t& stack) const {
  if (stack.status != stack_t::STATUS_OK) {
    return empty_answer(stack, config_, prediction_t::STATUS_NO_STACK,
                        stack.status == stack_t::STATUS_NO_FRAME   ? "no frame (the camera frame could not be decoded)"
                        : stack.status == stack_t::STATUS_NO_BOARD ? "no board (the board could not be seen)"
                                                                   : "stack status " + std::to_string(stack.status));
  }
  if (stack.num_blocks < 0 || static_cast<size_t>(stack.num_blocks) != stack.blocks.size()) {
    return empty_answer(stack, config_, prediction_t::STATUS_INVALID_STACK,
                        "num_blocks is " + std::to_string(stack.num_blocks) + " but the stack carries " +
                            std::to_string(stack.blocks.size()) + " blocks");
  }
  if (stack.blocks.size() > static_cast<size_t>(config_.max_blocks)) {
    return empty_answer(stack, config_, prediction_t::STATUS_INVALID_STACK,
                        "stack has " + std::to_string(stack.blocks.size()) + " blocks, more than --max-blocks=" +
                            std::to_string(config_.max_blocks));
  }
  core::Prediction verdict;
  try {
    core::Stack s = messages::to_core_stack(stack);
    verdict = predictor_(s, options_);  // validates first (StackError)
  } catch (const core::StackError& e) {
    return empty_answer(stack, config_, prediction_t::STATUS_INVALID_STACK, e.what());
  } catch (const core::SolverError& e) {
    return empty_answer(stack, config_, prediction_t::STATUS_SOLVER_ERROR, e.what());
  } catch (const std::exception& e) {
    return empty_answer(stack, config_, prediction_t::STATUS_SOLVER_ERROR, std::string("unexpected: ") + e.what());
  }
  prediction_t p = empty_answer(stack, config_, prediction_t::STATUS_OK, "");
  messages::put_verdict(verdict, p);
  return p;
}

}  // namespace bricklayer::prediction
