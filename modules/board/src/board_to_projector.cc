#include "bricklayer/board/board_to_projector.h"

#include <cmath>
#include <limits>
#include <stdexcept>

#include "bricklayer/board/board_geometry.h"

namespace bricklayer::board {

std::array<double, 9> multiply3(const std::array<double, 9>& a, const std::array<double, 9>& b) {
  std::array<double, 9> c{};
  for (int r = 0; r < 3; ++r)
    for (int k = 0; k < 3; ++k)
      for (int j = 0; j < 3; ++j) c[r * 3 + j] += a[r * 3 + k] * b[k * 3 + j];
  return c;
}

std::array<double, 9> invert3(const std::array<double, 9>& m) {
  const double a = m[0], b = m[1], c = m[2], d = m[3], e = m[4], f = m[5], g = m[6], h = m[7], i = m[8];
  const double A = e * i - f * h, B = -(d * i - f * g), C = d * h - e * g;
  const double det = a * A + b * B + c * C;
  double scale = 0;
  for (double v : m) scale = std::max(scale, std::abs(v));
  if (!std::isfinite(det) || scale == 0 || std::abs(det) <= 1e-12 * scale * scale * scale)
    throw std::invalid_argument("homography is singular (determinant " + std::to_string(det) + ")");
  const double inv = 1.0 / det;
  return {A * inv, -(b * i - c * h) * inv, (b * f - c * e) * inv,
          B * inv, (a * i - c * g) * inv,  -(a * f - c * d) * inv,
          C * inv, -(a * h - b * g) * inv, (a * e - b * d) * inv};
}

namespace {
void check_finite(const std::array<double, 9>& m, const char* what) {
  for (double v : m)
    if (!std::isfinite(v)) throw std::invalid_argument(std::string(what) + " has a non-finite entry");
}
}  // namespace

BoardToProjector::BoardToProjector()
    : BoardToProjector(multiply3(kDefaultCameraToProjector, invert3(BoardGeometry{}.camera_to_board())), false) {}

BoardToProjector BoardToProjector::from_homographies(const std::array<double, 9>& camera_to_projector,
                                                     const std::array<double, 9>& camera_to_board) {
  check_finite(camera_to_projector, "camera_to_projector");
  check_finite(camera_to_board, "camera_to_board");
  invert3(camera_to_projector);  // a singular camera->projector map is as useless as a singular board map
  return BoardToProjector(multiply3(camera_to_projector, invert3(camera_to_board)), true);
}

BoardToProjector BoardToProjector::from_calibration(const calibration_t& calibration) {
  std::array<double, 9> c2p{}, c2b{};
  for (int k = 0; k < 9; ++k) {
    c2p[k] = calibration.camera_to_projector[k];
    c2b[k] = calibration.camera_to_board[k];
  }
  return from_homographies(c2p, c2b);
}

BoardToProjector BoardToProjector::for_projector(const calibration_t& calibration, int width, int height) {
  if (calibration.projector_width <= 0 || calibration.projector_height <= 0 ||
      (calibration.projector_width == width && calibration.projector_height == height))
    return from_calibration(calibration);
  const double sx = static_cast<double>(width) / calibration.projector_width;
  const double sy = static_cast<double>(height) / calibration.projector_height;
  std::array<double, 9> c2p{}, c2b{};
  for (int k = 0; k < 9; ++k) {
    c2p[k] = calibration.camera_to_projector[k];
    c2b[k] = calibration.camera_to_board[k];
  }
  return from_homographies(multiply3({sx, 0, 0, 0, sy, 0, 0, 0, 1}, c2p), c2b);
}

Point2 BoardToProjector::map(double board_x, double board_y) const {
  const double w = h_[6] * board_x + h_[7] * board_y + h_[8];
  if (!(std::abs(w) > 1e-12)) return {std::numeric_limits<double>::quiet_NaN(), std::numeric_limits<double>::quiet_NaN()};
  return {(h_[0] * board_x + h_[1] * board_y + h_[2]) / w, (h_[3] * board_x + h_[4] * board_y + h_[5]) / w};
}

}  // namespace bricklayer::board
