// Point mappings a calibration_t defines (the conventions of lcmtypes/calibration_t.lcm):
// camera pixel (distorted, as captured) -> undistorted camera pixel (camera_matrix, distortion)
// -> projector pixel (camera_to_projector) or board coordinates (camera_to_board).
#pragma once

#include <opencv2/core.hpp>

#include <vector>

#include "bricklayer/calibration_t.hpp"

namespace bricklayer::board {

cv::Matx33d camera_matrix(const bricklayer::calibration_t& cal);
cv::Vec<double, 5> distortion(const bricklayer::calibration_t& cal);
cv::Matx33d camera_to_projector_h(const bricklayer::calibration_t& cal);
cv::Matx33d camera_to_board_h(const bricklayer::calibration_t& cal);
cv::Matx33d colour_mixing(const bricklayer::calibration_t& cal);

// Lens model (OpenCV): undistort is iterative (cv::undistortPoints with P = camera matrix).
cv::Point2d undistort_point(const bricklayer::calibration_t& cal, cv::Point2d camera_px);
std::vector<cv::Point2d> undistort_points(const bricklayer::calibration_t& cal, const std::vector<cv::Point2d>& camera_px);
cv::Point2d distort_point(const bricklayer::calibration_t& cal, cv::Point2d undistorted_px);

cv::Point2d apply_homography(const cv::Matx33d& h, cv::Point2d p);

cv::Point2d camera_to_projector(const bricklayer::calibration_t& cal, cv::Point2d camera_px);
cv::Point2d projector_to_camera(const bricklayer::calibration_t& cal, cv::Point2d projector_px);  // distorted px
cv::Point2d camera_to_board(const bricklayer::calibration_t& cal, cv::Point2d camera_px);

}  // namespace bricklayer::board
