// The logic of bricklayer-prediction without the bus: stack_t in, prediction_t out.
// A pure function of the input message (no clock, no state), so the process, bricklayer-replay and the
// tests all compute byte-identical answers.
#pragma once

#include <cstddef>
#include <functional>
#include <string>

#include "bricklayer/core/predict.h"
#include "bricklayer/core/program.h"
#include "bricklayer/prediction_t.hpp"
#include "bricklayer/runtime/config.h"
#include "bricklayer/stack_t.hpp"

namespace bricklayer::prediction {

// How far vision's measured positions may be off, block lengths. Simcam frames measure to a p95 of 0.0015-0.0024
// at the harshest nuisance level (modules/vision/README.md); zero-margin optima (every known optimum, every
// harmonic stack) measured that far past their knife edge would otherwise flicker red while the real pile stands.
// 0.005 is about twice that p95 (0.3 px at 60 px per block) and well under the smallest push a player can make
// on purpose. Recorded in every prediction_t, so a replay judges with the same value.
inline constexpr double kMeasuredPositionTolerance = 0.005;

struct PredictionConfig {
  std::string annotator = "exact";  // exact, paper or balance (core::parse_annotator)
  std::string solver = "clp";       // LP backend passed to core::predict
  double position_tolerance = kMeasuredPositionTolerance;  // core::PredictOptions::position_tolerance
  int max_blocks = 1000;            // larger stacks are answered with STATUS_INVALID_STACK

  template <typename Visitor>
  void visit(Visitor& v) {
    v(runtime::param("annotator", annotator, "which blocks are red: exact (initial-acceleration causes), paper, balance")
          .one_of({"exact", "paper", "balance"}));
    v(runtime::param("solver", solver, "LP backend of the core").one_of(core::opt::solver_names()));
    v(runtime::param("max-blocks", max_blocks, "larger stacks get STATUS_INVALID_STACK; larger messages are rejected")
          .range(1, 100000));
    v(runtime::param("position-tolerance", position_tolerance,
                     "block lengths a measured position may be off; contact intervals are widened by this (0 = exact)")
          .range(0, core::kMaxPositionTolerance));
  }
};

// Upper bound of an encoded stack_t with max_blocks blocks: larger messages on BL_STACK are rejected
// before decoding (counted errors).
size_t max_stack_message_bytes(size_t max_blocks);

class PredictionLogic {
 public:
  // The core call; replaceable so a test can make it fail (default: core::predict).
  using Predictor = std::function<core::Prediction(const core::Stack&, const core::PredictOptions&)>;

  // Throws std::invalid_argument for an unknown annotator or solver, a max_blocks of 0, or a position
  // tolerance outside [0, core::kMaxPositionTolerance].
  explicit PredictionLogic(PredictionConfig config, Predictor predictor = {});

  // Always answers: failures become a status and a one-line error, never an exception.
  //   stack.status != STATUS_OK            -> STATUS_NO_STACK
  //   num_blocks != blocks.size(), too many blocks, core::StackError -> STATUS_INVALID_STACK
  //   core::SolverError (or any other failure of the core)           -> STATUS_SOLVER_ERROR
  prediction_t answer(const stack_t& stack) const;

  const PredictionConfig& config() const { return config_; }

 private:
  PredictionConfig config_;
  core::PredictOptions options_;
  Predictor predictor_;
};

// The LP backend named by a recorded prediction_t.solver ("clp", "clp+nnls", ...), or "" when it
// names none this build knows.
std::string lp_backend_of(const std::string& recorded_solver);

}  // namespace bricklayer::prediction
