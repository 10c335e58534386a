#include "bricklayer/board/board_to_projector.h"

#include <catch2/catch.hpp>

#include "bricklayer/board/board_geometry.h"

using namespace bricklayer;
using namespace bricklayer::board;

TEST_CASE("the uncalibrated default puts the surface edge where simcam and vision expect it") {
  BoardToProjector m;
  CHECK_FALSE(m.calibrated());
  // Board (0,0) -> camera (320,440) -> projector x1.6 = (512,704).
  Point2 edge = m.map(0, 0);
  CHECK(edge.x == Approx(512));
  CHECK(edge.y == Approx(704));
  // One block length right and one block height (1/3) up: 60 and 20 camera px -> 96 and 32 projector px.
  Point2 corner = m.map(1, 1.0 / 3.0);
  CHECK(corner.x == Approx(512 + 96));
  CHECK(corner.y == Approx(704 - 32));
}

TEST_CASE("a calibration composes camera->projector with the inverse of camera->board") {
  // Camera->projector: scale 2 and shift (10, 20). Camera->board: the default board.
  const std::array<double, 9> c2p = {2, 0, 10, 0, 2, 20, 0, 0, 1};
  BoardToProjector m = BoardToProjector::from_homographies(c2p, BoardGeometry{}.camera_to_board());
  CHECK(m.calibrated());
  Point2 p = m.map(0.5, 0);
  CHECK(p.x == Approx(2 * (320 + 30) + 10));
  CHECK(p.y == Approx(2 * 440 + 20));

  calibration_t cal{};
  for (int k = 0; k < 9; ++k) {
    cal.camera_to_projector[k] = c2p[k];
    cal.camera_to_board[k] = BoardGeometry{}.camera_to_board()[k];
  }
  Point2 q = BoardToProjector::from_calibration(cal).map(0.5, 0);
  CHECK(q.x == Approx(p.x));
  CHECK(q.y == Approx(p.y));
}

TEST_CASE("a perspective mapping round-trips through its inverse") {
  const std::array<double, 9> h = {1.1, 0.05, 3, -0.02, 0.95, 7, 1e-4, 2e-4, 1};
  const auto product = multiply3(h, invert3(h));
  for (int r = 0; r < 3; ++r)
    for (int c = 0; c < 3; ++c) CHECK(product[r * 3 + c] == Approx(r == c ? 1.0 : 0.0).margin(1e-12));
}

TEST_CASE("singular or non-finite calibrations are rejected with a message") {
  const std::array<double, 9> singular = {1, 2, 3, 2, 4, 6, 0, 0, 1};
  CHECK_THROWS_WITH(BoardToProjector::from_homographies({1, 0, 0, 0, 1, 0, 0, 0, 1}, singular),
                    Catch::Contains("singular"));
  CHECK_THROWS_WITH(BoardToProjector::from_homographies({1, 0, NAN, 0, 1, 0, 0, 0, 1}, BoardGeometry{}.camera_to_board()),
                    Catch::Contains("non-finite"));
  calibration_t zero{};
  CHECK_THROWS(BoardToProjector::from_calibration(zero));
}

TEST_CASE("a calibration made for another projector resolution is scaled to ours") {
  calibration_t cal{};
  const std::array<double, 9> c2p = {1.6, 0, 12, 0, 1.6, -8, 0, 0, 1};
  for (int k = 0; k < 9; ++k) {
    cal.camera_to_projector[k] = c2p[k];
    cal.camera_to_board[k] = BoardGeometry{}.camera_to_board()[k];
  }
  cal.projector_width = 1024;
  cal.projector_height = 768;
  const Point2 same = BoardToProjector::for_projector(cal, 1024, 768).map(0.5, 1.0);
  const Point2 direct = BoardToProjector::from_calibration(cal).map(0.5, 1.0);
  CHECK(same.x == Approx(direct.x));
  CHECK(same.y == Approx(direct.y));
  // The same projector calibrated at 2048x1536, shown at 1024x768: every pixel halves.
  calibration_t big = cal;
  big.projector_width = 2048;
  big.projector_height = 1536;
  for (int k = 0; k < 6; ++k) big.camera_to_projector[k] *= 2;
  const Point2 scaled = BoardToProjector::for_projector(big, 1024, 768).map(0.5, 1.0);
  CHECK(scaled.x == Approx(direct.x));
  CHECK(scaled.y == Approx(direct.y));
  // Different aspect: x and y scale separately.
  const Point2 wide = BoardToProjector::for_projector(cal, 2048, 768).map(0.5, 1.0);
  CHECK(wide.x == Approx(2 * direct.x));
  CHECK(wide.y == Approx(direct.y));
}
