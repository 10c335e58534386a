// The calibration file (calibration.json): a calibration_t as JSON, loaded strictly.
// bricklayer-calibrate writes it; vision and projection load it at start (and validate every
// calibration_t they receive on BL_CALIBRATION with validate_calibration()).
//
// Format: one JSON object with exactly these keys (all required, any other key is an error):
//   "format": "bricklayer-calibration", "version": 1,
//   "utime", "camera_width", "camera_height", "projector_width", "projector_height" (integers),
//   "camera_matrix" [fx, fy, cx, cy], "distortion" [k1, k2, p1, p2, k3],
//   "camera_to_projector" [9], "camera_to_board" [9] (row-major, undistorted camera pixels),
//   "colour_mixing" [9] (row-major, camera BGR per unit projector BGR), "ambient_bgr" [3],
//   "block_height", "reprojection_error_mean_px", "reprojection_error_max_px";
// and one optional key, "board_x_accuracy" [3] (calibration_t.board_x_accuracy), written only when stated
// (not all zero): a file without it loads with the accuracy not stated.
#pragma once

#include <stdexcept>
#include <string>

#include "bricklayer/calibration_t.hpp"

namespace bricklayer::board {

class CalibrationFileError : public std::runtime_error {
 public:
  using std::runtime_error::runtime_error;
};

// Throws CalibrationFileError naming the first problem: sizes outside 16..8192, non-finite numbers,
// a non-positive focal length, a principal point outside the image, a lens distortion that folds
// over inside the image, a singular homography or one whose horizon crosses the camera image, a
// singular or implausible colour mixing matrix, ambient outside 0..255, block height outside
// (0, 10], negative or inconsistent reprojection errors, a board_x_accuracy term outside 0..1.
void validate_calibration(const bricklayer::calibration_t& cal);

// The uncalibrated default (board_geometry.h): a 640x480 camera with no lens distortion looking
// straight at the board, kDefaultCameraToProjector, the default BoardGeometry, and a typical colour
// mixing (diagonal 0.55..0.6, red and blue leaking ~0.1 into green). Valid; utime 0.
bricklayer::calibration_t default_calibration();

// JSON text <-> calibration_t. parse throws CalibrationFileError ("calibration: <what>: <why>") for
// text that is not JSON, more than 1 MB, a missing or unknown key, a wrong type or count, or any
// problem validate_calibration() finds.
bricklayer::calibration_t parse_calibration_json(const std::string& text);
std::string calibration_to_json(const bricklayer::calibration_t& cal);  // validates first

// Files. load names the path in its errors; save validates, writes a temporary file next to the
// target and renames it over the target (a reader never sees half a file).
bricklayer::calibration_t load_calibration(const std::string& path);
void save_calibration(const std::string& path, const bricklayer::calibration_t& cal);

}  // namespace bricklayer::board
