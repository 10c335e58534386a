// The logic of bricklayer-prediction without the bus: stack_t in, prediction_t out.
// A pure function of the input message (no clock, no state), so the process, bricklayer-replay and the
// tests all compute byte-identical answers.
#pragma once

#include <cstddef>
#include <functional>
#include <string>

#include "bricklayer/core/knife_edge.h"
#include "bricklayer/core/predict.h"
#include "bricklayer/core/program.h"
#include "bricklayer/prediction_t.hpp"
#include "bricklayer/runtime/config.h"
#include "bricklayer/stack_t.hpp"

namespace bricklayer::prediction {

// The least position uncertainty of a measured block, block lengths (each block's half-width is the larger of
// this and vision's own estimate, block_t.x_uncertainty). Simcam frames measure x to a p95 of 0.0015-0.0024 at
// the harshest nuisance level (modules/vision/README.md); 0.003 (0.22 mm of the real block, 0.18 px at 60 px
// per block) covers that p95 with a little room. An operator with a worse camera raises it
// (--uncertainty-floor, e.g. from the calibration self-check's residual in block lengths). Recorded in every
// prediction_t, so a replay judges with the same value.
inline constexpr double kUncertaintyFloor = 0.003;

struct PredictionConfig {
  std::string annotator = "exact";  // exact, paper or balance (core::parse_annotator)
  std::string solver = "clp";       // LP backend passed to core::predict
  double uncertainty_floor = kUncertaintyFloor;  // block lengths; see kUncertaintyFloor
  double position_tolerance = 0.0;  // legacy widening (core::PredictOptions::position_tolerance); 0 = off
  int max_blocks = 1000;            // larger stacks are answered with STATUS_INVALID_STACK

  template <typename Visitor>
  void visit(Visitor& v) {
    v(runtime::param("annotator", annotator, "which blocks are red: exact (initial-acceleration causes), paper, balance")
          .one_of({"exact", "paper", "balance"}));
    v(runtime::param("solver", solver, "LP backend of the core").one_of(core::opt::solver_names()));
    v(runtime::param("max-blocks", max_blocks, "larger stacks get STATUS_INVALID_STACK; larger messages are rejected")
          .range(1, 100000));
    v(runtime::param("uncertainty-floor", uncertainty_floor,
                     "least position uncertainty of a block, block lengths (vision's estimate when larger); "
                     "stable / falls / knife edge are judged with it")
          .range(0, core::kMaxUncertainty));
    v(runtime::param("position-tolerance", position_tolerance,
                     "legacy: widen contact intervals by this and answer stable / falls without knife edges (0 = off)")
          .range(0, core::kMaxPositionTolerance));
  }
};

// Upper bound of an encoded stack_t with max_blocks blocks: larger messages on BL_STACK are rejected
// before decoding (counted errors).
size_t max_stack_message_bytes(size_t max_blocks);

class PredictionLogic {
 public:
  // The core call; replaceable so a test can make it fail (default: core::judge_knife_edge, or with a legacy
  // position tolerance core::predict wrapped as a verdict without knife edges).
  using Predictor = std::function<core::KnifeEdgeVerdict(const core::Stack&, const std::vector<double>& uncertainty,
                                                         const core::PredictOptions&)>;

  // Throws std::invalid_argument for an unknown annotator or solver, a max_blocks of 0, or an uncertainty floor
  // or position tolerance out of range.
  explicit PredictionLogic(PredictionConfig config, Predictor predictor = {});

  // Always answers: failures become a status and a one-line error, never an exception.
  //   stack.status != STATUS_OK            -> STATUS_NO_STACK
  //   num_blocks != blocks.size(), too many blocks, core::StackError, a NaN or negative x_uncertainty
  //                                        -> STATUS_INVALID_STACK
  //   core::SolverError (or any other failure of the core)           -> STATUS_SOLVER_ERROR
  // verdict == raw_verdict here; the node's hysteresis may turn a certain verdict into a knife edge (show()).
  prediction_t answer(const stack_t& stack) const;

  // Each block's half-width: vision's x_uncertainty raised to the floor, capped at core::kMaxUncertainty.
  // Throws core::StackError for a NaN or negative x_uncertainty.
  std::vector<double> uncertainties(const stack_t& stack) const;

  const PredictionConfig& config() const { return config_; }

 private:
  PredictionConfig config_;
  core::PredictOptions options_;
  Predictor predictor_;
};

// Makes `shown` the verdict p shows: verdict, balanced, counts_for_max and the block states (STATE_CAUSE and
// STATE_MOVING only when it certainly falls). shown may only be raw_verdict or VERDICT_KNIFE_EDGE.
void show(prediction_t& p, int8_t shown);

// The LP backend named by a recorded prediction_t.solver ("clp", "clp+nnls", ...), or "" when it
// names none this build knows.
std::string lp_backend_of(const std::string& recorded_solver);

}  // namespace bricklayer::prediction
