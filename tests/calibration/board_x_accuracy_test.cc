// The bound the scale step states on board x: its terms, their growth with the fits' residuals, and the
// calibration carrying it.
#include <catch2/catch.hpp>

#include "bricklayer/board/calibration_file.h"
#include "bricklayer/calibration/board_x_accuracy.h"

namespace cal = bricklayer::calibration;

TEST_CASE("the stated board x accuracy grows with the residuals, and without a lean the vertical term is large") {
  const cal::BoardXAccuracy good = cal::board_x_accuracy(0.001, 0.005);
  CHECK(good.base == Approx(cal::kAccuracyBase + 0.002));
  CHECK(good.per_x == Approx(cal::kAccuracyScale + 0.002));
  CHECK(good.per_y == Approx(cal::kAccuracyLean + 0.01));
  CHECK(good.at(-4.0, 0.0) == Approx(good.base + 4 * good.per_x));
  CHECK(good.at(5.0, 3.2) == Approx(good.base + 5 * good.per_x + 3.2 * good.per_y));
  const cal::BoardXAccuracy scattered = cal::board_x_accuracy(0.006, 0.02);
  CHECK(scattered.at(5.0, 3.2) > good.at(5.0, 3.2));
  const cal::BoardXAccuracy no_lean = cal::board_x_accuracy(0.001, -1.0);
  CHECK(no_lean.per_y == cal::kAccuracyNoLean);
  CHECK_THROWS(cal::board_x_accuracy(-0.1, 0.0));
  CHECK_THROWS(cal::board_x_accuracy(0.001, std::nan("")));
}

TEST_CASE("a calibration states the accuracy and it survives the file") {
  const bricklayer::calibration_t c = cal::with_board_x_accuracy(bricklayer::board::default_calibration(), cal::board_x_accuracy(0.002, 0.004));
  CHECK(c.board_x_accuracy[0] > 0);
  const bricklayer::calibration_t back = bricklayer::board::parse_calibration_json(bricklayer::board::calibration_to_json(c));
  for (int i = 0; i < 3; ++i) CHECK(back.board_x_accuracy[i] == c.board_x_accuracy[i]);
}
