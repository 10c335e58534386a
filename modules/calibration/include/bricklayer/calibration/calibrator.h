// Calibration as pure computation (no bus): which patterns to show, and from the camera frames that
// saw them, the camera -> projector mapping with lens distortion, the board frame, and the colour
// mixing; plus the drift self-check. bricklayer-calibrate drives it over LCM; tests drive it with
// simcam frames.
//
// Method (see modules/calibration/README.md for the measurements behind the choices):
// - Registration: two ArUco grids (marker sets 0 and 1), every marker detected with sub-pixel
//   corner refinement, matched by id, its centre paired with its known projector position.
// - Lens: a single Levenberg-Marquardt fit of a homography and radial distortion k1, k2 to those
//   correspondences (principal point at the image centre, nominal focal length 0.875 x width:
//   with one plane only the product of focal length and k1 is observable, and any consistent pair
//   undistorts identically). Residuals are in camera pixels, where the detection noise lives;
//   correspondences more than 3 px off after the first fit are dropped and the fit repeated.
// - Board frame: the projector image defines a rectified frame (rectified pixel = projector pixel
//   x camera_width / projector_width, the default setup of board/board_geometry.h) in which the
//   BoardGeometry (--board FILE or defaults) gives the block size. The shelf's top edge and its end
//   are found in the projector's light (colour frames minus black: no shadows, no ambient), and
//   the frame is rotated and shifted so that the shelf top is horizontal and its corner lands on the
//   geometry's (edge_x_px, surface_y_px). Scale cannot be seen on an empty board: it is the
//   projector's.
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
};

// Detects marker set `set` in a camera frame (BGR or grey) and returns one correspondence per
// detected marker of the set: the centre (intersection of the diagonals through its four refined
// corners). Centres, not corners: blur pulls detected corners ~0.5 camera px towards the marker's
// inside (measured), a bias that does not average out, while the centre stays where it is.
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
