#include "bricklayer/board/mapping.h"

#include <cmath>

namespace bricklayer::board {

cv::Matx33d camera_matrix(const bricklayer::calibration_t& cal) {
  return {cal.camera_matrix[0], 0, cal.camera_matrix[2], 0, cal.camera_matrix[1], cal.camera_matrix[3], 0, 0, 1};
}

cv::Vec<double, 5> distortion(const bricklayer::calibration_t& cal) {
  return {cal.distortion[0], cal.distortion[1], cal.distortion[2], cal.distortion[3], cal.distortion[4]};
}

namespace {
cv::Matx33d matx(const double* a) { return {a[0], a[1], a[2], a[3], a[4], a[5], a[6], a[7], a[8]}; }

// Normalised ideal -> normalised distorted (OpenCV's k1, k2, p1, p2, k3 model).
cv::Point2d distort_normalised(const double* d, cv::Point2d p) {
  const double r2 = p.x * p.x + p.y * p.y;
  const double radial = 1 + r2 * (d[0] + r2 * (d[1] + r2 * d[4]));
  return {p.x * radial + 2 * d[2] * p.x * p.y + d[3] * (r2 + 2 * p.x * p.x),
          p.y * radial + d[2] * (r2 + 2 * p.y * p.y) + 2 * d[3] * p.x * p.y};
}
}  // namespace

cv::Matx33d camera_to_projector_h(const bricklayer::calibration_t& cal) { return matx(cal.camera_to_projector); }
cv::Matx33d camera_to_board_h(const bricklayer::calibration_t& cal) { return matx(cal.camera_to_board); }
cv::Matx33d colour_mixing(const bricklayer::calibration_t& cal) { return matx(cal.colour_mixing); }

cv::Point2d distort_point(const bricklayer::calibration_t& cal, cv::Point2d u) {
  const double* k = cal.camera_matrix;
  const cv::Point2d n((u.x - k[2]) / k[0], (u.y - k[3]) / k[1]);
  const cv::Point2d d = distort_normalised(cal.distortion, n);
  return {d.x * k[0] + k[2], d.y * k[1] + k[3]};
}

cv::Point2d undistort_point(const bricklayer::calibration_t& cal, cv::Point2d c) {
  // Fixed-point iteration to 1e-12 (OpenCV's undistortPoints stops after 5 iterations by default,
  // which leaves ~0.1 px at the corners of a k1 = -0.12 webcam).
  const double* k = cal.camera_matrix;
  const cv::Point2d target((c.x - k[2]) / k[0], (c.y - k[3]) / k[1]);
  cv::Point2d n = target;
  for (int i = 0; i < 100; ++i) {
    const cv::Point2d d = distort_normalised(cal.distortion, n);
    const cv::Point2d step = target - d;
    n += step;
    if (std::abs(step.x) + std::abs(step.y) < 1e-13) break;
  }
  return {n.x * k[0] + k[2], n.y * k[1] + k[3]};
}

std::vector<cv::Point2d> undistort_points(const bricklayer::calibration_t& cal, const std::vector<cv::Point2d>& camera_px) {
  std::vector<cv::Point2d> out;
  out.reserve(camera_px.size());
  for (const auto& p : camera_px) out.push_back(undistort_point(cal, p));
  return out;
}

cv::Point2d apply_homography(const cv::Matx33d& h, cv::Point2d p) {
  const double w = h(2, 0) * p.x + h(2, 1) * p.y + h(2, 2);
  return {(h(0, 0) * p.x + h(0, 1) * p.y + h(0, 2)) / w, (h(1, 0) * p.x + h(1, 1) * p.y + h(1, 2)) / w};
}

cv::Point2d camera_to_projector(const bricklayer::calibration_t& cal, cv::Point2d camera_px) {
  return apply_homography(camera_to_projector_h(cal), undistort_point(cal, camera_px));
}

cv::Point2d projector_to_camera(const bricklayer::calibration_t& cal, cv::Point2d projector_px) {
  return distort_point(cal, apply_homography(camera_to_projector_h(cal).inv(), projector_px));
}

cv::Point2d camera_to_board(const bricklayer::calibration_t& cal, cv::Point2d camera_px) {
  return apply_homography(camera_to_board_h(cal), undistort_point(cal, camera_px));
}

}  // namespace bricklayer::board
