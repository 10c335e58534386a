// Scoring vision against simcam's ground truth, shared by bricklayer-bench-vision and tests/vision.
// Header-only; needs bricklayer::simcam_render.
#pragma once

#include <cmath>
#include <vector>

#include <opencv2/imgproc.hpp>

#include "bricklayer/calibration_t.hpp"
#include "bricklayer/simcam/render.h"
#include "bricklayer/detection/detector.h"

namespace bricklayer::detection::eval {

struct FrameScore {
  int truth = 0;       // visible true blocks
  int detected = 0;    // detections, not counting ones on partly visible blocks
  int matched = 0;     // detections on a true block in the right row
  int row_wrong = 0;   // detections on a true block but in another row
  std::vector<double> dx;  // |x error| of every matched detection, block lengths
};

// A detection is a true block's when within `tolerance` block lengths of it; same row first.
inline FrameScore score(const std::vector<simcam::TrueBlock>& truth, const std::vector<DetectedBlock>& detections,
                        double tolerance = 0.3) {
  FrameScore s;
  for (const auto& t : truth) s.truth += t.visible ? 1 : 0;
  std::vector<bool> used(truth.size(), false);
  for (const DetectedBlock& d : detections) {
    int best = -1, other_row = -1;
    double best_err = tolerance, other_err = tolerance;
    for (size_t i = 0; i < truth.size(); ++i) {
      if (used[i]) continue;
      const double e = std::abs(truth[i].x - d.x);
      if (truth[i].row == d.row && e < best_err) best_err = e, best = static_cast<int>(i);
      if (truth[i].row != d.row && std::abs(truth[i].row - d.row) <= 1 && e < other_err) other_err = e, other_row = static_cast<int>(i);
    }
    if (best >= 0) {
      used[best] = true;
      if (!truth[best].visible) continue;  // partly outside the frame: neither counted nor penalised
      ++s.detected;
      ++s.matched;
      s.dx.push_back(best_err);
    } else {
      ++s.detected;
      if (other_row >= 0 && truth[other_row].visible) {
        ++s.row_wrong;
        used[other_row] = true;
      }
    }
  }
  return s;
}

// What projection would show: every block lit pure blue (255,0,0 BGR), every third pure red (0,0,255),
// in projector pixels.
inline cv::Mat red_blue_projection(const core::Stack& stack, const simcam::CameraSetup& cam,
                                   const simcam::ProjectorSetup& proj) {
  cv::Mat img(proj.size, CV_8UC3, cv::Scalar(0, 0, 0));
  const cv::Matx33d to_proj = proj.projector_to_rectified.inv();
  for (size_t i = 0; i < stack.blocks.size(); ++i) {
    const auto& b = stack.blocks[i];
    const double u0 = cam.board.to_px_x(b.x), u1 = u0 + cam.board.block_length_px;
    const double v1 = cam.board.surface_y_px - b.row * cam.board.block_height_px, v0 = v1 - cam.board.block_height_px;
    std::vector<cv::Point> poly;
    for (auto p : {cv::Point2d(u0, v0), cv::Point2d(u1, v0), cv::Point2d(u1, v1), cv::Point2d(u0, v1)}) {
      const cv::Vec3d q = to_proj * cv::Vec3d(p.x, p.y, 1);
      poly.emplace_back(static_cast<int>(std::lround(q[0] / q[2])), static_cast<int>(std::lround(q[1] / q[2])));
    }
    cv::fillConvexPoly(img, poly, i % 3 == 0 ? cv::Scalar(0, 0, 255) : cv::Scalar(255, 0, 0));
  }
  return img;
}

// The calibration a perfect bricklayer-calibrate would publish for this simulated setup.
inline calibration_t true_calibration(const simcam::CameraSetup& cam, const simcam::ProjectorSetup& proj) {
  calibration_t c{};
  c.camera_width = cam.size.width;
  c.camera_height = cam.size.height;
  c.projector_width = proj.size.width;
  c.projector_height = proj.size.height;
  c.camera_matrix[0] = cam.camera_matrix(0, 0);
  c.camera_matrix[1] = cam.camera_matrix(1, 1);
  c.camera_matrix[2] = cam.camera_matrix(0, 2);
  c.camera_matrix[3] = cam.camera_matrix(1, 2);
  for (int i = 0; i < 5; ++i) c.distortion[i] = cam.distortion[i];
  const BoardGeometry& g = cam.board;
  const cv::Matx33d rect_to_board(1 / g.block_length_px, 0, -g.edge_x_px / g.block_length_px, 0,
                                  -1 / g.block_length_px, g.surface_y_px / g.block_length_px, 0, 0, 1);
  const cv::Matx33d camera_to_rect = cam.rectified_to_camera.inv();
  const cv::Matx33d to_board = rect_to_board * camera_to_rect;
  const cv::Matx33d to_projector = proj.projector_to_rectified.inv() * camera_to_rect;
  for (int i = 0; i < 9; ++i) {
    c.camera_to_board[i] = to_board.val[i];
    c.camera_to_projector[i] = to_projector.val[i];
    c.colour_mixing[i] = proj.mixing.val[i];
  }
  c.block_height = g.block_height_px / g.block_length_px;
  return c;
}

}  // namespace bricklayer::detection::eval
