// Board scale from blocks: correcting a calibration's board frame with blocks as the ruler.
//
// Why: bricklayer-calibrate takes the board frame's scale from the projector, because an empty board
// shows nothing of scale. A projector mounted bigger or smaller than nominal, or with some keystone,
// therefore makes every x, every overhang and the score read wrong (a projector 10% larger: blocks read
// 10% short; keystone: the error grows along the board). Blocks carry their own ruler: a block's two end
// lines are one block length less one line width apart (each line's centroid lies half a line width
// inside its end). Blocks standing apart on the bottom row, spread along it, measure how long a block
// reads at each place, and fit_board_correction() finds the board correction
//     x' = a x / (c x + h y + 1),  y' = a y / (c x + h y + 1)
// (a homography fixing the surface edge, the origin the shelf sets whatever the scale): a is the scale,
// c a keystone along the board, h one up it (how the scale changes with height; only from blocks on rows
// spanning kMinHeightForVerticalKeystone or more). apply_board_correction() puts it into the calibration.
//
// By default only the bottom row is measured: a wrong scale shifts row k's band by the error times k, and
// the bottom row stays inside its band for errors up to kMaxScaleError. Once a first correction has put
// the bands right, a meter on the corrected calibration may measure every row up to `max_row` (blocks on
// higher rows: the vertical keystone from their lengths, interpolated instead of extrapolated up the
// board). Only blocks at least kMinGap from their row's other lines: the end lines of touching blocks
// merge, and their centroids are not half a width inside.
//
// Each end line is placed by fitting its profile (end_line_fit.h), not at its dip's centroid: blur mixes
// the glass-to-face step beside the line into the dip and pulled the centroid inwards (lengths 0.05-0.25%
// short with mild to harsh blur, 0.3-0.6% under the game's red and blue light at the harsh level, the scale
// that much large). Measured (simcam, the true calibration, 8 mountings, 10 frames of 6 apart blocks): the
// fitted lengths are within +-0.13% in room light at every nuisance level, and -0.08..+0.27% under the
// game's light (clean to harsh); the centroids' were -0.21..+0.10% and -0.60..+0.10%. Blocks whose end line
// does not fit are left out (unfitted()). Corrections smaller than the measurement's noise are not worth
// applying: bricklayer-calibrate --scale-from-blocks applies only larger ones (--scale-min-change).
#pragma once

#include <optional>
#include <string>
#include <vector>

#include <opencv2/core.hpp>

#include "bricklayer/calibration_t.hpp"
#include "bricklayer/detection/detector.h"

namespace bricklayer::detection {

inline constexpr double kMaxScaleError = 0.25;  // largest measurable |block length read - 1|
inline constexpr double kMinGap = 0.1;          // block lengths between a measured block's end lines and any other
inline constexpr double kMaxKeystone = 0.08;    // largest |c| searched, per block length
inline constexpr double kMinSpanForKeystone = 2.0;  // block lengths the measured blocks must span to fit c
inline constexpr double kMinHeightForVerticalKeystone = 1.0;  // block lengths of height they must span to fit h

// One measured block: its end lines in board coordinates of the calibration being checked, and the height
// of its row band's middle there.
struct EndLines {
  double left = 0.0, right = 0.0;
  double y = 0.0;
  int row = 0;
};

struct BoardCorrection {
  double scale = 1.0;     // a: true block lengths per board unit at the surface edge
  double keystone = 0.0;  // c: per block length (0 when the blocks span less than kMinSpanForKeystone)
  double vertical_keystone = 0.0;  // h: per block length up (0 unless their heights span kMinHeightForVerticalKeystone)
  int blocks = 0;         // measurements used (after dropping outliers)
  int outliers = 0;       // measurements dropped (mispaired lines, more than 3% off the fit)
  double residual = 0.0;  // RMS of the corrected block lengths' relative error
  double length_at(double x) const;  // how long a block read at board x on the bottom row before the correction
  double max_change(double half_width) const;  // largest |x' - x| over |x| <= half_width, block lengths
};

// Fits the correction to measured blocks whose end-line centroids should be `1 - line_width` apart.
// Returns nothing with *why saying what to fix: fewer than min_blocks measurements, a residual above
// max_residual, or a scale beyond kMaxScaleError.
std::optional<BoardCorrection> fit_board_correction(const std::vector<EndLines>& measured, double line_width,
                                                    int min_blocks, double max_residual, std::string* why);

class BlockScaleMeter {
 public:
  // `config.line_width` is the blocks' physical end-line width in block lengths (1/40 for the exhibit's
  // blocks and simcam's). Throws std::invalid_argument on an unusable calibration.
  // Rows 0..max_row are measured (see above: only 0 before a first correction).
  explicit BlockScaleMeter(const calibration_t& calibration, DetectorConfig config = {}, int max_row = 0);

  // What the projector shows (the game's red and blue light on the blocks): its leakage into green is
  // subtracted from the following frames, as in bricklayer-vision (Detector::set_projector_image).
  void set_projector_image(const cv::Mat& bgr, cv::Size projector_size) { detector_.set_projector_image(bgr, projector_size); }

  // Measures the blocks standing apart in one camera frame (BGR8 or GRAY8); returns how many.
  int add(const cv::Mat& frame);

  const std::vector<EndLines>& measured() const { return measured_; }
  int unfitted() const { return unfitted_; }  // blocks left out because an end line's profile did not fit
  std::optional<BoardCorrection> result(int min_blocks, double max_residual, std::string* why) const {
    return fit_board_correction(measured_, line_width_, min_blocks, max_residual, why);
  }

 private:
  double line_width_;
  int max_row_;
  Detector detector_;
  std::vector<EndLines> measured_;
  int unfitted_ = 0;
};

// The calibration with its board coordinates corrected: camera_to_board := C * camera_to_board with
// C = [a 0 0; 0 a 0; c h 1]. Throws std::invalid_argument unless scale > 0 and both are finite.
calibration_t apply_board_correction(const calibration_t& calibration, const BoardCorrection& correction);

}  // namespace bricklayer::detection
