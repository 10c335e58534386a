// The collapse prediction: is the pile balanced, which blocks move, which start the collapse.
// See shared DESIGN.md "The physics" and modules/core/README.md for the tolerance policy.
#pragma once

#include <cstdint>
#include <stdexcept>
#include <string>
#include <vector>

#include <nlohmann/json_fwd.hpp>

#include "bricklayer/core/dynamics.h"
#include "bricklayer/core/stack.h"

namespace bricklayer::core {

enum class BlockState { kStable = 0, kMoving = 1, kCause = 2 };  // same values as block_prediction_t::STATE_*

enum class Annotator {
  kExact,    // causes from the initial-acceleration QP (default)
  kPaper,    // the seed paper's fictitious-force LP
  kBalance,  // Paterson & Zwick feasibility only: every block of an unbalanced pile is a cause candidate
};

// A pile is balanced when the smallest total violation of the equilibrium equations (sum of absolute force
// and moment residuals over all blocks, units of block weight and block weight x block length) that
// nonnegative contact forces can reach is at most this. See modules/core/README.md "Tolerance policy".
inline constexpr double kBalanceTolerance = 1e-6;
// A fictitious force (paper annotator) above this (units of block weight) makes its block red.
inline constexpr double kFictitiousTolerance = 1e-6;

struct PredictOptions {
  Annotator annotator = Annotator::kExact;
  std::string solver = "clp";  // LP backend: "clp" or "nlopt"
  QpMethod qp = QpMethod::kNnls;  // exact annotator's QP
  // Exact annotator: ask the LP backend whether the pile is balanced before any QP. Off by default: the
  // O(n) two-point certificate answers most balanced piles and the warm-started NNLS is faster than CLP
  // for the rest (README "Choices by measurement").
  bool lp_first = false;
  // How far a measured block position may be off, block lengths (0 <= t <= kMaxPositionTolerance): contact
  // intervals are widened by t at both ends (build_contacts), so a zero-margin pile measured a little past its
  // knife edge still reads balanced. 0 (the default) judges the positions as exact. bricklayer-prediction
  // sets it for measured stacks; see modules/core/README.md "Tolerance policy".
  double position_tolerance = 0.0;
  StackLimits limits;
};

// Larger tolerances would call clearly overhanging blocks balanced; predict() refuses them.
inline constexpr double kMaxPositionTolerance = 0.05;

struct BlockVerdict {
  int64_t id = 0;
  BlockState state = BlockState::kStable;
  double accel = 0.0;  // initial vertical acceleration of the centre, units of g (exact annotator)
  double alpha = 0.0;  // initial angular acceleration, g per block length (exact annotator)
};

struct Prediction {
  bool balanced = true;
  std::vector<BlockVerdict> blocks;  // same order as the stack's blocks
  double overhang = 0.0;             // block lengths beyond the surface edge
  int32_t score = 0;                 // round(100 * overhang)
  std::string annotator;
  std::string solver;
  std::string qp;  // exact annotator: "nnls" or "nlopt"; empty when no QP was solved
  double position_tolerance = 0.0;  // the PredictOptions::position_tolerance it was judged with

  std::vector<int64_t> causes() const;  // ids of red blocks
  std::vector<int64_t> moving() const;  // ids with a nonzero initial acceleration (causes included)
};

// Thrown when a backend fails (not for "unbalanced", which is a verdict).
class SolverError : public std::runtime_error {
 public:
  using std::runtime_error::runtime_error;
};

// Validates (StackError) and predicts (SolverError on backend failure; std::invalid_argument for a
// position_tolerance outside [0, kMaxPositionTolerance]). Deterministic: the same stack and options give
// bit-identical output.
Prediction predict(const Stack& stack, const PredictOptions& options = {});

// Minimum total equilibrium violation (see kBalanceTolerance) with the given LP backend; blocks whose free
// flag is 0 are held fixed. Throws SolverError when the backend fails.
double balance_violation(const ContactGraph& graph, const std::string& solver, const std::vector<char>& free = {});

// The exact annotator's block states on a contact graph the caller built (predict() builds it from the stack;
// the knife-edge judgement builds narrowed ones). Throws SolverError when the QP fails.
std::vector<BlockState> exact_states(const ContactGraph& graph, QpMethod qp = QpMethod::kNnls);

// Overhang in block lengths and the score, without solving anything.
double overhang(const Stack& stack);
int32_t score_of(double overhang_in_block_lengths);

// bricklayer-predict's output object.
nlohmann::json to_json(const Prediction& prediction);

Annotator parse_annotator(const std::string& name);  // throws std::invalid_argument
std::string to_string(Annotator annotator);

}  // namespace bricklayer::core
