// The rectified board frame vision detects in: a pixel grid in which the board is seen straight on, one
// block length is the same number of pixels everywhere, rows are horizontal bands above the surface.
//
// Without calibration the camera image itself is the board frame (identity, BoardGeometry from --board
// or the shared defaults). With a calibration_t the frame is built from the camera intrinsics +
// distortion and the camera_to_board homography, and the remap tables are computed once here (never
// per frame).
#pragma once

#include <array>
#include <optional>

#include <opencv2/core.hpp>

#include "bricklayer/calibration_t.hpp"
#include "bricklayer/board/board_geometry.h"

namespace bricklayer::detection {

class BoardFrame {
 public:
  // Identity: rectified pixels are camera pixels, laid out as `geometry` says.
  explicit BoardFrame(const BoardGeometry& geometry = {});

  // From a calibration. Throws std::invalid_argument with a fixable message when the calibration is
  // unusable (non-finite numbers, singular homographies, non-positive sizes or focal lengths).
  static BoardFrame from_calibration(const calibration_t& calibration);

  bool identity() const { return identity_; }
  const BoardGeometry& geometry() const { return geometry_; }
  // Size of the rectified image (identity: unknown until a frame arrives, returns 0x0).
  cv::Size size() const { return size_; }
  // Camera image size the calibration was made for (identity: 0x0, any size accepted).
  cv::Size camera_size() const { return camera_size_; }

  // Rectifies one channel of a camera frame (identity: returns `camera` itself, no copy).
  cv::Mat rectify(const cv::Mat& camera) const;

  // Rectified pixel -> raw (distorted) camera pixel.
  cv::Point2d to_camera(cv::Point2d rectified) const;

  // Homography from rectified pixels to undistorted camera pixels (identity: eye(3)).
  cv::Matx33d rectified_to_undistorted() const { return rect_to_undist_; }

 private:
  bool identity_ = true;
  BoardGeometry geometry_;
  cv::Size size_{0, 0};
  cv::Size camera_size_{0, 0};
  cv::Matx33d rect_to_undist_ = cv::Matx33d::eye();
  cv::Matx33d camera_matrix_ = cv::Matx33d::eye();
  std::array<double, 5> distortion_{};
  cv::Mat map1_, map2_;  // fixed-point remap tables (CV_16SC2 + CV_16UC1)
};

}  // namespace bricklayer::detection
