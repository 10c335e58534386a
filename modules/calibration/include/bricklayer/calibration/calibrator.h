// Calibration as pure computation (no bus): which patterns to show, and from the camera frames that
// saw them, the camera -> projector mapping with lens distortion, the board frame, and the colour
// mixing; plus the drift self-check. bricklayer-calibrate drives it over LCM; tests drive it with
// simcam frames.
//
// Method (see modules/calibration/README.md for the measurements behind the choices):
// - Registration: two ArUco grids (marker sets 0 and 1), every marker detected with sub-pixel
//   corner refinement and matched by id; its four corners (and their diagonal intersection, the
//   centre) are paired with their known projector positions.
// - Lens: a single Levenberg-Marquardt fit to the corners of a homography, radial distortion k1, k2,
//   the distortion centre (principal point) and a corner bias (blur pulls detected corners towards
//   the marker's centre). The focal length is nominal (0.875 x width): with one plane only k1/f^2
//   and k2/f^4 are observable, and any consistent set undistorts identically. Residuals are in camera
//   pixels, where the detection noise lives; markers with a corner more than 3 px off the fit are
//   dropped and the fit repeated.
// - Shelf clearance: the shelf's top edge and end are a strong step in the light; a corner whose
//   refinement window meets them is pulled towards the step and bends the lens fit. Corners within
//   shelf_clearance_camera_px of the shelf seen after the first fit are left out and the fit is made
//   again; their markers' centres do not count in the reported error.
// - Board frame: the projector image defines a rectified frame (rectified pixel = projector pixel
//   x camera_width / projector_width, the default setup of board/board_geometry.h) in which the
//   BoardGeometry (--board FILE or defaults) gives the block size. The shelf's top edge and its end
//   are found in the projector's light (colour frames minus black: no shadows, no ambient), and
//   the frame is rotated and shifted so that the shelf top is horizontal and its corner lands on the
//   geometry's (edge_x_px, surface_y_px). Scale cannot be seen on an empty board: it is the
//   projector's (bricklayer-calibrate --scale-from-blocks corrects it with blocks).
// - Rejection: on the mean and on the largest reprojection error over the markers used, both in
//   projector pixels: one badly placed marker region is as bad for the exhibit as a poor mean.
// - Colour: projector black, red, green and blue at a known drive level; the median camera BGR
//   over the central part of the frame, black subtracted, divided by the drive.
#pragma once

#include <opencv2/core.hpp>

#include <array>
#include <string>
#include <vector>

#include "bricklayer/calibration_t.hpp"
#include "bricklayer/command_t.hpp"
#include "bricklayer/board/board_geometry.h"

namespace bricklayer::calibration {

struct CalibrationOptions {
  cv::Size projector_size{kDefaultProjectorWidth, kDefaultProjectorHeight};
  BoardGeometry board;          // in rectified pixels (see above)
  double max_error_px = 1.0;    // mean reprojection error (projector pixels) above which a calibration is rejected
  // Largest reprojection error of one marker (projector pixels) above which a calibration is rejected.
  // Measured over good fits (bricklayer-bench-calibration, 4 x 20 setups): up to 1.07 (clean frames,
  // no blur), p99 0.82-0.97; fits bent by the shelf edge: 1.0-1.7 in simcam, 1.3-2.3 elsewhere.
  double max_point_error_px = 1.25;
  // Markers with a corner this close (camera pixels) to the shelf's top edge or end are left out of
  // the fit: the corner refinement window (+-4 px) plus the blur's reach. 0: keep every marker.
  double shelf_clearance_camera_px = 8.0;
  int colour_drive = 80;        // projector level (0..255) of the red/green/blue frames; low enough not to saturate
  int min_correspondences = 30; // fewer detected markers: rejected
  // Find the shelf (the stacking surface, darker than the glass) and take the surface edge, the
  // surface top and the rotation of the board frame from it; block sizes stay from `board`.
  bool board_from_shelf = true;
};

// One pattern to show and what the operator is told about it.
struct CalibrationStep {
  bricklayer::command_t command;  // SHOW_PATTERN with pattern/index/colour; sequence and utime left 0
  std::string description;
};
std::vector<CalibrationStep> calibration_steps(const CalibrationOptions& options);

struct Correspondence {
  cv::Point2d camera;     // camera pixel as captured (distorted)
  cv::Point2d projector;  // projector pixel
  std::array<cv::Point2d, 4> camera_corners{};     // the marker's detected corners (camera pixels)
  std::array<cv::Point2d, 4> projector_corners{};  // and where they are in the projector image
  bool has_corners = false;
  // Corners the lens fit uses (compute_calibration leaves out those whose refinement window meets the
  // shelf). A marker with a corner left out has a spoiled centre: it is not counted in the error.
  std::array<bool, 4> corner_used{true, true, true, true};
  bool all_corners_used() const { return corner_used[0] && corner_used[1] && corner_used[2] && corner_used[3]; }
};

// Detects marker set `set` in a camera frame (BGR or grey) and returns one correspondence per
// detected marker of the set: its four refined corners and the centre (intersection of the
// diagonals). Blur pulls detected corners ~0.5 camera px towards the marker's inside (measured), a
// bias that does not average out (the lens fit models it), while the centre stays where it is.
std::vector<Correspondence> detect_marker_correspondences(const cv::Mat& frame, int set, cv::Size projector_size);

struct LensFit {
  cv::Matx33d camera_matrix = cv::Matx33d::eye();
  cv::Vec<double, 5> distortion{0, 0, 0, 0, 0};
  cv::Matx33d camera_to_projector = cv::Matx33d::eye();  // undistorted camera px -> projector px
  std::vector<bool> inlier;                              // per correspondence
  double rms_camera_px = 0.0;                            // fit residual over inliers, camera pixels
  double corner_bias_px = 0.0;                           // detected corners' pull towards the marker centre
};
// Throws std::runtime_error when there are fewer than 8 correspondences.
// Recomputes every camera centre as the diagonal intersection of the corners undistorted with cal's
// lens (exact under a homography, where the distorted diagonals are slightly curved), distorted back.
void recentre_undistorted(std::vector<Correspondence>& points, const bricklayer::calibration_t& cal);

LensFit fit_lens_and_homography(const std::vector<Correspondence>& points, cv::Size camera_size);

struct ColourMeasurement {
  cv::Matx33d mixing;  // camera BGR per unit projector BGR (column j = projector channel j)
  cv::Vec3d ambient;   // camera BGR with the projector black
  bool saturated = false;
};
ColourMeasurement measure_colour_mixing(const cv::Mat& black, const cv::Mat& blue, const cv::Mat& green,
                                        const cv::Mat& red, int drive);

// The shelf corner in a rectified image of the projector's light (CV_32F, negative = unseen).
struct ShelfCorner {
  bool found = false;
  cv::Point2d corner;      // rectified pixels: the shelf's top right corner (surface edge, surface top)
  double angle_rad = 0.0;  // slope of the shelf top (positive: falls to the right in image rows)
  int columns = 0;         // columns that saw the shelf top
  std::string message;
};
ShelfCorner find_shelf_corner(const cv::Mat& light_rectified, const BoardGeometry& nominal);

enum class CalibrationStatus { kOk, kBadFrames, kTooFewPoints, kSaturated, kErrorTooHigh, kInvalid };
const char* to_string(CalibrationStatus status);

struct CalibrationResult {
  CalibrationStatus status = CalibrationStatus::kBadFrames;
  std::string message;                 // operator-readable: what happened and how to fix it
  bricklayer::calibration_t calibration{};  // filled whenever the fit ran (even when rejected)
  int correspondences = 0;
  int inliers = 0;
  int near_shelf = 0;  // markers with a corner left out of the fit because its refinement window met the shelf
  ShelfCorner shelf;  // what the board frame was anchored on (found = false: the --board geometry as is)
};

// frames: one camera frame (CV_8UC3) per step of calibration_steps(options), in order.
// utime: stamped into the result (no wall clock inside).
CalibrationResult compute_calibration(const std::vector<cv::Mat>& frames, const CalibrationOptions& options, int64_t utime);

// The drift self-check: a frame showing marker set kMarkerSetSelfCheck, compared with where the
// calibration puts those markers. Drift in projector pixels over every detected corner.
struct SelfCheckResult {
  bool measured = false;      // false: no self-check marker found (board not empty? projector off?)
  int markers_found = 0;
  double drift_mean_px = 0.0;
  double drift_max_px = 0.0;
  std::string message;
};
bricklayer::command_t self_check_command();
SelfCheckResult self_check(const bricklayer::calibration_t& cal, const cv::Mat& frame);

}  // namespace bricklayer::calibration
