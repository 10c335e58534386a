#include "bricklayer/calibration/board_x_accuracy.h"

#include <cmath>
#include <stdexcept>

namespace bricklayer::calibration {

double BoardXAccuracy::at(double x, double y) const { return base + per_x * std::abs(x) + per_y * std::max(0.0, y); }

BoardXAccuracy board_x_accuracy(double length_residual, double lean_residual, bool vertical_from_rows) {
  if (!std::isfinite(length_residual) || length_residual < 0 || !std::isfinite(lean_residual))
    throw std::invalid_argument("board_x_accuracy: residuals must be finite, the length residual non-negative");
  BoardXAccuracy a;
  a.base = kAccuracyBase + kAccuracyResidualFactor * length_residual;
  a.per_x = kAccuracyScale + kAccuracyResidualFactor * length_residual;
  // Without the lean the shear is uncorrected whatever the rows said of h.
  a.per_y = lean_residual < 0          ? kAccuracyNoLean
            : vertical_from_rows      ? kAccuracyRows + kAccuracyRowsLeanFactor * lean_residual
                                      : kAccuracyLean + kAccuracyResidualFactor * lean_residual;
  return a;
}

calibration_t with_board_x_accuracy(const calibration_t& calibration, const BoardXAccuracy& accuracy) {
  calibration_t out = calibration;
  out.board_x_accuracy[0] = accuracy.base;
  out.board_x_accuracy[1] = accuracy.per_x;
  out.board_x_accuracy[2] = accuracy.per_y;
  return out;
}

}  // namespace bricklayer::calibration
