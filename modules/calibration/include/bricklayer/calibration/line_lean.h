// How the board frame's vertical leans: shear and vertical keystone from the tilt of blocks' end lines.
//
// Why: bricklayer-calibrate takes the board frame from the projector's image, anchored on the shelf
// (origin and the surface's direction). Block lengths on the bottom row (detection/block_scale.h) then
// fix the scale a and the keystone g along the board, but a projector mounted with keystone also leans
// the frame's vertical (a shear b: x off by b * y) and makes the scale change with height (a vertical
// keystone h). Neither shows on the bottom row, and both grow with the height: measured over 20 random
// simcam mountings, board x on row 9 was off by 0.10 block lengths (median) after the scale step while
// the bottom row was within 0.01. Blocks carry the vertical too: their end lines stand square to the
// surface. In the calibration's frame a physically vertical line at board x0 leans by
//     dx/dy = x0 h - b (g x0 + 1) / a
// so the lean of the bottom-row end lines across the board gives b and h. The full correction of the
// board frame is then
//     x' = (a x + b y) / (g x + h y + 1),   y' = a y / (g x + h y + 1).
//
// A line's lean is measured in the camera frame through the calibration: horizontal profiles across the
// line at heights inside its block (clear of the block's top and bottom edges), each profile's darkness
// centroid, and a least-squares line through the centroids.
#pragma once

#include <optional>
#include <string>
#include <vector>

#include <opencv2/core.hpp>

#include "bricklayer/calibration_t.hpp"

namespace bricklayer::calibration {

// One end line: where it stands (board x in the calibration's frame, and the height it was measured at:
// its row band's middle) and its lean dx/dy.
struct LineLean {
  double x = 0.0;
  double lean = 0.0;
  double y = 0.0;
};

// The lean of the dark end line near board x between heights y0 < y1 (block lengths, the calibration's
// frame) in a grey camera frame (CV_8UC1). Nothing when the line is not seen clearly at enough heights
// (out of view, too faint, a profile with two dips).
std::optional<double> measure_line_lean(const cv::Mat& grey, const calibration_t& calibration, double x, double y0,
                                        double y1);

struct FrameLean {
  double shear = 0.0;              // b
  double vertical_keystone = 0.0;  // h, per block length
  int lines = 0;                   // leans used
  int outliers = 0;                // leans dropped (more than 4 robust deviations off the fit)
  double residual = 0.0;           // RMS lean residual after the fit
};

// Fits b and h to measured leans, given the scale a and keystone g along the board (block_scale.h).
// h only when the lines span at least min_span_for_keystone block lengths. Nothing, with *why, below
// min_lines leans or when they scatter by more than max_residual (RMS) about the fit: measured, good
// frames scatter by 0.002-0.007 (mild nuisance) and 0.011-0.023 (harsh); one harsh setup whose
// shadows spoiled the lines scattered by 0.046 and would have made board x worse, not better.
inline constexpr double kMaxLeanResidual = 0.03;
std::optional<FrameLean> fit_frame_lean(const std::vector<LineLean>& leans, double scale, double keystone, int min_lines,
                                        std::string* why, double min_span_for_keystone = 2.0,
                                        double max_residual = kMaxLeanResidual);

// The shear b alone, given a, g and h (h from block lengths on several rows, block_scale.h), from leans
// measured at any height: a vertical line at (x, y) leans by (N h - b D) / (a D - N g) with N = a x + b y,
// D = g x + h y + 1, so each lean gives b = a (x h - lean (h y + 1)) / (g x + 1 - lean g y); leans more than
// 4 robust deviations off dropped, the rest averaged. The result's vertical_keystone is h as given; its
// residual is the leans' RMS about the fit. Nothing, with *why, as fit_frame_lean.
std::optional<FrameLean> fit_shear(const std::vector<LineLean>& leans, double scale, double keystone, double vertical_keystone,
                                   int min_lines, std::string* why, double max_residual = kMaxLeanResidual);

// The calibration with camera_to_board := C * camera_to_board, C = [a b 0; 0 a 0; g h 1].
// Throws std::invalid_argument unless a > 0 and all are finite.
calibration_t apply_frame_correction(const calibration_t& calibration, double scale, double keystone, double shear,
                                     double vertical_keystone);

// Largest |x' - x| of the correction over |x| <= half_width on heights 0..height (block lengths).
double frame_correction_change(double scale, double keystone, double shear, double vertical_keystone, double half_width,
                               double height);

}  // namespace bricklayer::calibration
