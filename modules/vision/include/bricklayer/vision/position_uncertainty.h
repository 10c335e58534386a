// A block's position uncertainty: the half-width (block lengths) around its published left end within which
// the true one lies, as block_t.x_uncertainty carries it to prediction's knife-edge verdict.
//
// It is measured per block, per frame, from the pixels the detector's x came from: the two end lines, each
// re-read row by row in the rectified frame (a narrow window around the line, the band the detector averaged):
//   - line fit: the scatter of the per-row centroids about their straight fit (noise, JPEG blocks, texture
//     seen directly), as the standard error of the line's centre;
//   - contrast: the line's darkness against the row-to-row noise of its background, which predicts the same
//     standard error from the profile's shape;
//   - blur: the line's width at half depth beyond its printed width, and how close another block's line comes
//     within the reach of its blur (biases no row or frame shows: see frame_uncertainty);
//   - the pair: how far the two lines are from the spacing one block implies (a line moved by e moves the
//     midpoint by e/2, and nothing else in the frame says so);
//   - sampling: where a line falls within its pixels moves the detector's centroid of it, most for sharp lines
//     (a bound computed from the frame's printed line width and blur), never less than JPEG's floor.
// The temporal filter adds the spread of the block's x over its recent frames (temporal_filter.h), and how far
// the published x lags the latest measurement. The result is never below the calibration's residual
// (calibration_t.reprojection_error_mean_px carried to board x through the calibration's own mappings, plus the
// board x accuracy the scale step states, calibration_t.board_x_accuracy) nor the
// operator's setting (VisionConfig "min-uncertainty").
// The constants are calibrated on simcam frames against simcam's truth (tests/vision/position_uncertainty_
// coverage_test.cc; figures in the vision README "Position uncertainty").
#pragma once

#include <optional>
#include <vector>

#include <opencv2/core.hpp>

#include "bricklayer/calibration_t.hpp"
#include "bricklayer/detection/board_frame.h"
#include "bricklayer/detection/detector.h"

namespace bricklayer::vision {

// One end line re-read in the rectified frame (pixels).
struct LineEvidence {
  bool measured = false;       // false: the window left the image or held no dip (see frame_uncertainty)
  double scatter_px = 0.0;     // standard error of the line's centre from the rows' scatter about their fit
  double depth = 0.0;          // darkness of the band-averaged dip against its background, 0..1
  double noise = 0.0;          // relative noise of one background pixel (std of pixel / background - 1)
  double width_px = 0.0;       // full width at half depth of the band-averaged dip
  double rows_effective = 0.0; // rows read, discounted for their correlation (blur and JPEG spread noise over rows)
  // Distance to the nearest other line the detector found in this row (another block's end; a line shared by two
  // touching blocks is not its own neighbour); infinity when none.
  double neighbour_px = 0.0;
};

// Everything measured about one block in one frame.
struct BlockEvidence {
  LineEvidence left, right;
  double pair_residual_px = 0.0;  // |line spacing - the spacing this pair's kind implies|
  double line_width_px = 0.0;     // the frame's printed line width as the detector measures it (lone pairs' shortfall)
  double frame_width_px = 0.0;    // the frame's median line width at half depth (print and blur): how far a dip reaches
  // The largest error the detector's centroid makes on a line of the frame's printed width and blur from where
  // the line falls within its pixels (pixels; see frame_uncertainty).
  double phase_px = 0.0;
};

// Reads the evidence for each block of one detection. `frame` is the camera frame (BGR8 or GRAY8) the
// detection came from, `board` the board frame it was measured in. Pure function of its inputs.
std::vector<BlockEvidence> measure_evidence(const cv::Mat& frame, const detection::BoardFrame& board,
                                            const std::vector<detection::DetectedBlock>& blocks);

// Constants of the model, calibrated on simcam (see the file comment): the smallest that keep 95% coverage in
// every kind of scene there.
struct UncertaintyModel {
  // Multiplies the random part (the midpoint's standard error) to a half-width.
  double coverage_factor = 2.0;
  // The contrast prediction of a line centre's standard error: snr_factor x sqrt(width) x noise / (depth x
  // sqrt(rows)).
  double snr_factor = 0.5;
  // Multiplies the pair residual's e/2.
  double pair_factor = 0.25;
  // Pixels: the sampling floor of a line centre (pixel phase, JPEG quantisation), the same in every row and frame.
  double sampling_px = 0.02;
  // Multiplies the pixel-phase bound (BlockEvidence::phase_px): 1, a bound, not fitted.
  double phase_factor = 1.0;
  // Pixels of half-width per pixel the lines are wider (at half depth) than the frame's printed line width.
  double blur_factor = 0.01;
  // Pixels of half-width per pixel a neighbouring line comes closer than two line widths (at half depth).
  double crowding_factor = 0.08;
  // A line that could not be re-read: the block's half-width is this (block lengths).
  double unmeasured = 0.01;
};

// Half-width (block lengths) of this frame's measurement of a block.
double frame_uncertainty(const BlockEvidence& evidence, double block_length_px, const UncertaintyModel& model = {});

// Half-width covering the spread of a block's x over its recent measurements (block lengths): the sample
// standard deviation times Student's t for 95% with n - 1 degrees of freedom; 0 for fewer than 3.
double temporal_uncertainty(double spread, int samples);

// The calibration's residual as a half-width of board x (block lengths) at board point (x, y) in block lengths:
// reprojection_error_mean_px is in projector pixels; the projector -> undistorted camera -> board mapping
// (inverse camera_to_projector, then camera_to_board) gives how many block lengths of x one projector pixel is
// there, in the direction that moves x most; plus the bound the scale step states on board x there
// (calibration_t.board_x_accuracy: [0] + [1] |x| + [2] y). 0 when both are 0 (e.g. board::default_calibration).
// Throws std::invalid_argument for a singular camera_to_projector.
double calibration_floor(const calibration_t& calibration, double x, double y);

// The published half-width: the measurement (the larger of this frame's and the temporal one) plus the lag
// (how far the published x is from that measurement), never below either floor.
double published_uncertainty(double frame, double temporal, double lag, double calibration_floor, double operator_floor);

}  // namespace bricklayer::vision
