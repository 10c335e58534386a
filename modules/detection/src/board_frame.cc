#include "bricklayer/detection/board_frame.h"

#include <cmath>
#include <stdexcept>
#include <string>

#include <opencv2/calib3d.hpp>
#include <opencv2/imgproc.hpp>

namespace bricklayer::detection {
namespace {

void require_finite(const double* v, int n, const char* field) {
  for (int i = 0; i < n; ++i) {
    if (!std::isfinite(v[i])) {
      throw std::invalid_argument(std::string("calibration: ") + field + "[" + std::to_string(i) +
                                  "] is not a finite number");
    }
  }
}

cv::Matx33d matx(const double* v) {
  return cv::Matx33d(v[0], v[1], v[2], v[3], v[4], v[5], v[6], v[7], v[8]);
}

cv::Point2d apply(const cv::Matx33d& h, cv::Point2d p) {
  cv::Vec3d q = h * cv::Vec3d(p.x, p.y, 1.0);
  return {q[0] / q[2], q[1] / q[2]};
}

}  // namespace

BoardFrame::BoardFrame(const BoardGeometry& geometry) : geometry_(geometry) {}

BoardFrame BoardFrame::from_calibration(const calibration_t& c) {
  require_finite(c.camera_matrix, 4, "camera_matrix");
  require_finite(c.distortion, 5, "distortion");
  require_finite(c.camera_to_board, 9, "camera_to_board");
  if (!std::isfinite(c.block_height) || c.block_height <= 0 || c.block_height > 10)
    throw std::invalid_argument("calibration: block_height must be a positive number of block lengths");
  if (c.camera_width <= 0 || c.camera_height <= 0 || c.camera_width > 8192 || c.camera_height > 8192)
    throw std::invalid_argument("calibration: camera_width/camera_height must be in 1..8192");
  const double fx = c.camera_matrix[0], fy = c.camera_matrix[1], cx = c.camera_matrix[2], cy = c.camera_matrix[3];
  if (fx <= 0 || fy <= 0) throw std::invalid_argument("calibration: focal lengths fx, fy must be positive");
  const cv::Matx33d cam_to_board = matx(c.camera_to_board);
  if (std::abs(cv::determinant(cam_to_board)) < 1e-15)
    throw std::invalid_argument("calibration: camera_to_board is singular");

  BoardFrame f;
  f.identity_ = false;
  f.camera_size_ = {c.camera_width, c.camera_height};
  f.camera_matrix_ = cv::Matx33d(fx, 0, cx, 0, fy, cy, 0, 0, 1);
  for (int i = 0; i < 5; ++i) f.distortion_[i] = c.distortion[i];

  // Board extent seen by the camera: undistort the image border and map it onto the board.
  std::vector<cv::Point2d> border;
  const int steps = 16;
  for (int i = 0; i <= steps; ++i) {
    const double s = static_cast<double>(i) / steps;
    border.push_back({s * (c.camera_width - 1), 0});
    border.push_back({s * (c.camera_width - 1), c.camera_height - 1.0});
    border.push_back({0, s * (c.camera_height - 1)});
    border.push_back({c.camera_width - 1.0, s * (c.camera_height - 1)});
  }
  std::vector<cv::Point2d> undistorted;
  cv::undistortPoints(border, undistorted, cv::Mat(f.camera_matrix_), cv::Mat(1, 5, CV_64F, f.distortion_.data()),
                      cv::noArray(), cv::Mat(f.camera_matrix_));
  double bx0 = 1e300, bx1 = -1e300, by0 = 1e300, by1 = -1e300;
  for (const auto& p : undistorted) {
    const cv::Point2d b = apply(cam_to_board, p);
    if (!std::isfinite(b.x) || !std::isfinite(b.y))
      throw std::invalid_argument("calibration: camera_to_board maps the image border to infinity");
    bx0 = std::min(bx0, b.x), bx1 = std::max(bx1, b.x), by0 = std::min(by0, b.y), by1 = std::max(by1, b.y);
  }
  // Scale: keep the camera's own resolution at the image centre (pixels per block length).
  const cv::Point2d centre(cx, cy);
  const cv::Point2d b0 = apply(cam_to_board, centre), bx = apply(cam_to_board, centre + cv::Point2d(1, 0)),
                    by = apply(cam_to_board, centre + cv::Point2d(0, 1));
  const double area = std::abs((bx.x - b0.x) * (by.y - b0.y) - (bx.y - b0.y) * (by.x - b0.x));
  if (!(area > 0)) throw std::invalid_argument("calibration: camera_to_board is degenerate at the image centre");
  const double length_px = 1.0 / std::sqrt(area);
  const int width = static_cast<int>(std::ceil((bx1 - bx0) * length_px));
  const int height = static_cast<int>(std::ceil((by1 - by0) * length_px));
  if (width <= 0 || height <= 0 || width > 2 * 8192 || height > 2 * 8192 ||
      static_cast<double>(width) * height > 4.0 * c.camera_width * c.camera_height)
    throw std::invalid_argument("calibration: the board frame would be " + std::to_string(width) + "x" +
                                std::to_string(height) + " pixels (is camera_to_board in block lengths?)");
  f.size_ = {width, height};
  f.geometry_.block_length_px = length_px;
  f.geometry_.block_height_px = c.block_height * length_px;
  f.geometry_.edge_x_px = -bx0 * length_px;
  f.geometry_.surface_y_px = by1 * length_px;
  const cv::Matx33d rect_to_board(1 / length_px, 0, bx0, 0, -1 / length_px, by1, 0, 0, 1);
  f.rect_to_undist_ = cam_to_board.inv() * rect_to_board;

  cv::Mat mapx(height, width, CV_32F), mapy(height, width, CV_32F);
  for (int y = 0; y < height; ++y) {
    float* mx = mapx.ptr<float>(y);
    float* my = mapy.ptr<float>(y);
    for (int x = 0; x < width; ++x) {
      const cv::Point2d p = f.to_camera({static_cast<double>(x), static_cast<double>(y)});
      mx[x] = static_cast<float>(p.x);
      my[x] = static_cast<float>(p.y);
    }
  }
  cv::convertMaps(mapx, mapy, f.map1_, f.map2_, CV_16SC2);
  return f;
}

cv::Mat BoardFrame::rectify(const cv::Mat& camera) const {
  if (identity_) return camera;
  cv::Mat out;
  // Beyond the camera's view the board is unknown, not black: replicating the border keeps a black wall
  // from merging with the end line of a block just inside the view into one wide (rejected) dip.
  cv::remap(camera, out, map1_, map2_, cv::INTER_LINEAR, cv::BORDER_REPLICATE);
  return out;
}

cv::Point2d BoardFrame::to_camera(cv::Point2d rectified) const {
  if (identity_) return rectified;
  const cv::Point2d u = apply(rect_to_undist_, rectified);
  const double fx = camera_matrix_(0, 0), fy = camera_matrix_(1, 1), cx = camera_matrix_(0, 2),
               cy = camera_matrix_(1, 2);
  const double x = (u.x - cx) / fx, y = (u.y - cy) / fy;
  const double k1 = distortion_[0], k2 = distortion_[1], p1 = distortion_[2], p2 = distortion_[3],
               k3 = distortion_[4];
  const double r2 = x * x + y * y;
  const double radial = 1 + r2 * (k1 + r2 * (k2 + r2 * k3));
  const double xd = x * radial + 2 * p1 * x * y + p2 * (r2 + 2 * x * x);
  const double yd = y * radial + p1 * (r2 + 2 * y * y) + 2 * p2 * x * y;
  return {fx * xd + cx, fy * yd + cy};
}

}  // namespace bricklayer::detection
