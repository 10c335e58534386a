// How far board x may still be off after the scale step (--scale-from-blocks), as the calibration states it
// to vision (calibration_t.board_x_accuracy: [0] + [1] |x| + [2] y, block lengths, a half-width).
//
// Why: vision's knife-edge verdict needs the whole of a block's x uncertainty, and after the scale step the
// calibration's board frame is the largest part of it away from the edge: the bench
// (bricklayer-bench-calibration, 20 random mountings per nuisance level) leaves board x off by median
// 0.008-0.016 and p99 up to 0.055 (mild) or 0.105 (harsh) block lengths, growing along the board (the scale
// reads 0.1-0.4% large, blur pulling the end-line centroids inwards, and the keystone is extrapolated beyond
// the blocks) and up it (shear and vertical keystone from the end lines' lean). A bound linear in |x| and y
// with terms that grow with what the measurement itself showed (the block lengths' and the leans' scatter
// about their fits) covers that; without a measured lean the vertical term is what the bench shows
// uncorrected (0.15 at 3.2 block lengths up, p99). The constants are the bench's (README, Method 7), a
// bound, not a standard deviation.
#pragma once

#include "bricklayer/calibration_t.hpp"

namespace bricklayer::calibration {

struct BoardXAccuracy {
  double base = 0.0;   // block lengths anywhere (the origin from the shelf, the lines' own scatter)
  double per_x = 0.0;  // block lengths per block length from the edge (scale, keystone)
  double per_y = 0.0;  // block lengths per block length above the surface (shear, vertical keystone)
  double at(double x, double y) const;
};

inline constexpr double kAccuracyBase = 0.008;         // the origin from the shelf: p99 0.006 (mild), 0.010 (strong), block lengths
inline constexpr double kAccuracyScale = 0.0025;       // the scale and the keystone along the board, per block length out
inline constexpr double kAccuracyLean = 0.006;         // shear and vertical keystone from bottom-row leans, per block length up
inline constexpr double kAccuracyRows = 0.002;         // the vertical keystone from lengths on rows up the board, per block length up
inline constexpr double kAccuracyNoLean = 0.05;        // the vertical uncorrected, per block length up
inline constexpr double kAccuracyResidualFactor = 2.0; // per unit of the fits' RMS residuals
inline constexpr double kAccuracyRowsLeanFactor = 0.5; // per unit of the leans' RMS residual when h came from the rows

// The bound from the scale step's fits: `length_residual` is BoardCorrection::residual (relative), and
// `lean_residual` FrameLean::residual, negative when the lean was not measured (corrected along the board only).
// `vertical_from_rows`: the vertical keystone came from block lengths on rows spanning
// detection::kMinHeightForVerticalKeystone or more (board_frame_refit.h), the leans gave the shear alone.
BoardXAccuracy board_x_accuracy(double length_residual, double lean_residual, bool vertical_from_rows = false);

// The calibration stating it (calibration_t.board_x_accuracy).
calibration_t with_board_x_accuracy(const calibration_t& calibration, const BoardXAccuracy& accuracy);

}  // namespace bricklayer::calibration
