#include "bricklayer/prediction/prediction_logic.h"

#include <algorithm>
#include <stdexcept>

#include "bricklayer/block_prediction_t.hpp"
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
  p.verdict = prediction_t::VERDICT_KNIFE_EDGE;  // no verdict: nothing is certain
  p.raw_verdict = prediction_t::VERDICT_KNIFE_EDGE;
  p.margin = 0.0;
  p.margin_mm = 0.0;
  p.uncertainty = 0.0;
  p.uncertainty_floor = config.uncertainty_floor;
  p.counts_for_max = false;
  p.num_blocks = 0;
  return p;
}

}  // namespace

size_t max_stack_message_bytes(size_t max_blocks) {
  // fingerprint 8 + utime, frame_number, 3 doubles 40 + status 1 + num_blocks 4; one block_t is
  // id 8 + row 4 + x 8 + corners 64 + confidence 8 + x_uncertainty 8 = 100 bytes. Slack for future additive
  // fields.
  return 256 + 100 * max_blocks;
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
  if (!(config_.uncertainty_floor >= 0.0 && config_.uncertainty_floor <= core::kMaxUncertainty)) {
    throw std::invalid_argument("--uncertainty-floor must be in [0, " + std::to_string(core::kMaxUncertainty) +
                                "] block lengths");
  }
  if (predictor_) return;
  if (config_.position_tolerance > 0.0) {
    // Legacy: the widened verdict, stable or falls, no knife edges and no margin.
    predictor_ = [](const core::Stack& s, const std::vector<double>&, const core::PredictOptions& o) {
      core::KnifeEdgeVerdict v;
      v.nominal = core::predict(s, o);
      v.certainty = v.nominal.balanced ? core::Certainty::kStable : core::Certainty::kFalls;
      if (!v.nominal.balanced) v.deciding = v.nominal.causes();
      return v;
    };
  } else {
    predictor_ = [](const core::Stack& s, const std::vector<double>& u, const core::PredictOptions& o) {
      return core::judge_knife_edge(s, u, o);
    };
  }
}

std::vector<double> PredictionLogic::uncertainties(const stack_t& stack) const {
  std::vector<double> u(stack.blocks.size());
  const double length = stack.block_length;
  for (size_t i = 0; i < u.size(); ++i) {
    const double own = stack.blocks[i].x_uncertainty;
    if (!(own >= 0.0)) {
      throw core::StackError("block " + std::to_string(i) + " (id " + std::to_string(stack.blocks[i].id) +
                             "): x_uncertainty " + std::to_string(own) + " is not a half-width >= 0");
    }
    (void)length;  // x_uncertainty is in block lengths whatever unit x uses
    u[i] = std::min(core::kMaxUncertainty, std::max(config_.uncertainty_floor, own));
  }
  return u;
}

void show(prediction_t& p, int8_t shown) {
  p.verdict = shown;
  p.balanced = shown != prediction_t::VERDICT_FALLS;
  p.counts_for_max = shown != prediction_t::VERDICT_FALLS;
  if (shown == prediction_t::VERDICT_FALLS) return;
  for (auto& b : p.blocks) b.state = block_prediction_t::STATE_STABLE;
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
  core::KnifeEdgeVerdict verdict;
  std::vector<double> u;
  try {
    core::Stack s = messages::to_core_stack(stack);
    u = uncertainties(stack);
    verdict = predictor_(s, u, options_);  // validates first (StackError)
  } catch (const core::StackError& e) {
    return empty_answer(stack, config_, prediction_t::STATUS_INVALID_STACK, e.what());
  } catch (const core::SolverError& e) {
    return empty_answer(stack, config_, prediction_t::STATUS_SOLVER_ERROR, e.what());
  } catch (const std::exception& e) {
    return empty_answer(stack, config_, prediction_t::STATUS_SOLVER_ERROR, std::string("unexpected: ") + e.what());
  }
  prediction_t p = empty_answer(stack, config_, prediction_t::STATUS_OK, "");
  messages::put_verdict(verdict.nominal, p);
  static_assert(static_cast<int>(core::Certainty::kStable) == prediction_t::VERDICT_STABLE &&
                static_cast<int>(core::Certainty::kFalls) == prediction_t::VERDICT_FALLS &&
                static_cast<int>(core::Certainty::kKnifeEdge) == prediction_t::VERDICT_KNIFE_EDGE);
  p.raw_verdict = static_cast<int8_t>(verdict.certainty);
  p.margin = verdict.margin;
  p.margin_mm = verdict.margin_mm();
  p.uncertainty = verdict.uncertainty;
  for (size_t i = 0; i < p.blocks.size() && i < u.size(); ++i) {
    p.blocks[i].uncertainty = u[i];
    p.blocks[i].deciding =
        std::find(verdict.deciding.begin(), verdict.deciding.end(), p.blocks[i].id) != verdict.deciding.end();
  }
  show(p, p.raw_verdict);
  return p;
}

}  // namespace bricklayer::prediction
