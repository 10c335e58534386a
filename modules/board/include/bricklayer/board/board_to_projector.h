// Where a point of the board lands in the projector image.
//
// Board coordinates: block lengths, x rightwards from the surface edge, y upwards from the surface top
// (the convention of calibration_t.camera_to_board and BoardGeometry). Calibration gives two
// homographies on undistorted camera pixels, so board -> projector = camera_to_projector *
// inverse(camera_to_board); lens distortion does not enter. Until a calibration arrives the shared
// uncalibrated default (board_geometry.h) is used, the same one simcam renders and vision assumes.
#pragma once

#include <array>
#include <string>

#include "bricklayer/calibration_t.hpp"

namespace bricklayer::board {

struct Point2 {
  double x = 0;
  double y = 0;
};

class BoardToProjector {
 public:
  // The uncalibrated default: kDefaultCameraToProjector * inverse(BoardGeometry{}.camera_to_board()).
  BoardToProjector();

  // board -> projector = camera_to_projector * inverse(camera_to_board), both row-major 3x3.
  // Throws std::invalid_argument when an entry is not finite or camera_to_board is singular.
  static BoardToProjector from_homographies(const std::array<double, 9>& camera_to_projector,
                                            const std::array<double, 9>& camera_to_board);
  // Same, from a calibration message (validated the same way).
  static BoardToProjector from_calibration(const calibration_t& calibration);
  // From a calibration, for a projector showing width x height pixels: a calibration made for the same
  // projector at another resolution (projector_width x projector_height) is scaled to ours.
  static BoardToProjector for_projector(const calibration_t& calibration, int width, int height);

  // Projector pixel of a board point. A point on the horizon (w = 0) maps to NaN.
  Point2 map(double board_x, double board_y) const;
  Point2 map(Point2 p) const { return map(p.x, p.y); }

  const std::array<double, 9>& matrix() const { return h_; }
  bool calibrated() const { return calibrated_; }

 private:
  explicit BoardToProjector(const std::array<double, 9>& h, bool calibrated) : h_(h), calibrated_(calibrated) {}
  std::array<double, 9> h_{};
  bool calibrated_ = false;
};

// Row-major 3x3 helpers (exposed for tests).
std::array<double, 9> multiply3(const std::array<double, 9>& a, const std::array<double, 9>& b);
// Throws std::invalid_argument when |det| is tiny relative to the entries.
std::array<double, 9> invert3(const std::array<double, 9>& m);

}  // namespace bricklayer::board
