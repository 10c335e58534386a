// Verdicts on measured piles: stable, falls or knife edge, from each block's position uncertainty, with a
// stability margin. Computed from the model (two small LPs in the common case, never by sampling); the
// method and every approximation are in modules/core/README.md "Knife edges".
#pragma once

#include <cstddef>
#include <cstdint>
#include <vector>

#include "bricklayer/core/predict.h"
#include "bricklayer/core/stack.h"

namespace bricklayer::core {

// Same values as prediction_t::VERDICT_*.
enum class Certainty {
  kStable = 0,     // stands for every placement of the blocks within their uncertainty (proved)
  kFalls = 1,      // falls for every such placement (proved)
  kKnifeEdge = 2,  // neither could be proved: within the uncertainty it may stand or fall
};
const char* to_string(Certainty certainty);

// Margins are reported up to this many block lengths (3.75 mm of a 7.5 cm block); a larger one reads as this.
inline constexpr double kMaxMargin = 0.05;
// Largest accepted position uncertainty, block lengths.
inline constexpr double kMaxUncertainty = 0.05;
// Above this many blocks no LP is solved (a cold CLP start costs 50-550 ms at 200-500 blocks): what the
// greedy certificate, the cuts and the witnesses cannot settle is a knife edge. See README "Knife edges".
inline constexpr size_t kMaxLpBlocks = 150;
// Length of the real block, millimetres (the 7.5 cm face lies on the board).
inline constexpr double kBlockLengthMm = 75.0;

struct KnifeEdgeVerdict {
  Certainty certainty = Certainty::kStable;
  // Signed, block lengths (a lower bound of the true value). > 0: the measured pile stands, and every
  // placement with each block moved by at most `margin` stands. < 0: the measured pile falls, and every
  // placement with each block moved by at most `-margin` falls. 0: no such bound (a pile exactly on its edge).
  // Clamped to [-kMaxMargin, kMaxMargin].
  double margin = 0.0;
  double uncertainty = 0.0;            // the largest per-block half-width used, block lengths
  std::vector<int64_t> deciding;       // ids of the blocks that decide it (the causes if it falls); empty when stable
  Prediction nominal;                  // the measured positions judged as exact (PredictOptions as given, no widening)
  int linear_programs = 0;             // how many LPs were solved (diagnostics and the benchmark)
  double margin_mm() const { return margin * kBlockLengthMm; }
};

// uncertainty: one half-width per block (block lengths, in [0, kMaxUncertainty]); each block may be anywhere
// in [x - u, x + u]. options: the nominal prediction's (annotator, solver, qp, limits); its
// position_tolerance must be 0 (the uncertainty replaces the widening). Throws StackError (invalid stack),
// std::invalid_argument (uncertainty of the wrong size, NaN, negative or too large; a nonzero
// position_tolerance), SolverError (a backend failed). Deterministic.
// max_lp_blocks: piles with more blocks are judged without LPs.
KnifeEdgeVerdict judge_knife_edge(const Stack& stack, const std::vector<double>& uncertainty,
                                  const PredictOptions& options = {}, size_t max_lp_blocks = kMaxLpBlocks);

}  // namespace bricklayer::core
