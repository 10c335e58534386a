// The scale step's second pass: the board frame's correction refitted from blocks on every row.
//
// Why: the first pass (bottom-row block lengths, block_scale.h, and the lean of their end lines,
// line_lean.h) can only use the bottom row, since before it the rows' bands may be a whole row off. What it
// leaves is extrapolated up the board: the vertical keystone h (how the scale changes with height) comes from
// how the leans of bottom-row lines change along the board, each lean measured over a fifth of a block length
// of height where the calibration's own mapping error bends it, and was off by up to 0.002 per block length,
// 0.03 block lengths at x = 5 on row 9. Once the first correction has put the bands right, blocks on higher
// rows can be measured like the bottom row's: their lengths give h directly (a block on row 9 reads 2% shorter
// or longer than one on row 0 on a typical mounting), interpolated wherever the blocks reach, and their lines'
// leans, measured all the way up, give the shear b. So with the first correction applied, the same frames
// are measured again on every row up to `max_row` and
//     x' = (a x + b y) / (g x + h y + 1),   y' = a y / (g x + h y + 1)
// is fitted again: a, g and h to the lengths (block_scale.h), b to the leans given them (fit_shear). It needs
// blocks on rows spanning detection::kMinHeightForVerticalKeystone (3 rows) or more: measured again, the
// bottom row alone says nothing the first pass did not.
#pragma once

#include <optional>
#include <string>
#include <vector>

#include <opencv2/core.hpp>

#include "bricklayer/calibration/line_lean.h"
#include "bricklayer/calibration_t.hpp"
#include "bricklayer/detection/block_scale.h"

namespace bricklayer::calibration {

// A correction of the board frame, camera_to_board := C * camera_to_board with C = [a b 0; 0 a 0; g h 1].
struct FrameCorrection {
  double scale = 1.0, keystone = 0.0, shear = 0.0, vertical_keystone = 0.0;
  // This correction after `first` (C_this * C_first), of the same form.
  FrameCorrection after(const FrameCorrection& first) const;
  calibration_t apply(const calibration_t& calibration) const;
};

// One camera frame of the blocks, and what the projector showed on them (empty: nothing known).
struct RefitFrame {
  cv::Mat bgr;
  cv::Mat projector_image;
  cv::Size projector_size;
};

struct FrameRefit {
  FrameCorrection correction;            // relative to the calibration given
  detection::BoardCorrection lengths;    // the lengths' fit (a, g, h; its residual and counts)
  std::optional<FrameLean> lean;         // the leans' fit (b), nothing when refused (then b = 0)
  std::string lean_why;                  // why it was refused
  int highest_row = 0;                   // the highest row a block was measured on
  double height_span = 0.0;              // block lengths between the lowest and the highest measured row
};

// Measures `frames` on `corrected` (the first pass's result) on rows 0..max_row and fits the correction
// of it. Nothing, with *why, when the measured blocks' rows span less than kMinHeightForVerticalKeystone or
// the lengths cannot be fitted (fewer than min_blocks, a residual above max_residual:
// detection::fit_board_correction's reasons).
std::optional<FrameRefit> refit_board_frame(const calibration_t& corrected, const std::vector<RefitFrame>& frames, int max_row,
                                            int min_blocks, double max_residual, std::string* why);

}  // namespace bricklayer::calibration
