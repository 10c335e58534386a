// The lean of blocks' end lines and the board-frame correction it gives (calibration/line_lean.h):
// the fit on exact leans, the measurement on simcam frames of a camera whose view of the board is
// sheared against the calibration, and the corrected board x up the board.
#include <catch2/catch.hpp>

#include <opencv2/imgproc.hpp>

#include <cmath>

#include "bricklayer/board/calibration_file.h"
#include "bricklayer/board/mapping.h"
#include "bricklayer/calibration/line_lean.h"
#include "bricklayer/simcam/render.h"

namespace cal = bricklayer::calibration;
namespace board = bricklayer::board;
namespace sim = bricklayer::simcam;

TEST_CASE("fit_frame_lean recovers shear and vertical keystone from exact leans, and drops a wrong one") {
  const double a = 1.08, g = 0.006, b = 0.025, h = -0.005;
  std::vector<cal::LineLean> leans;
  for (double x = -4; x <= 0.6; x += 0.5) leans.push_back({x, x * h - b * (g * x + 1) / a});
  leans.push_back({-1.0, 0.3});  // a shadow edge taken for a line
  std::string why;
  const auto fit = cal::fit_frame_lean(leans, a, g, 5, &why);
  INFO(why);
  REQUIRE(fit);
  CHECK(fit->shear == Approx(b).margin(1e-9));
  CHECK(fit->vertical_keystone == Approx(h).margin(1e-9));
  CHECK(fit->outliers == 1);

  // Lines spanning less than 2 block lengths: the shear only.
  const std::vector<cal::LineLean> close = {{-1.0, -b / a}, {-0.5, -b / a}, {0.0, -b / a}};
  const auto near = cal::fit_frame_lean(close, a, 0.0, 3, &why);
  REQUIRE(near);
  CHECK(near->shear == Approx(b).margin(1e-9));
  CHECK(near->vertical_keystone == 0.0);

  // Leans that scatter (lines spoiled by shadows): refused rather than trusted.
  std::vector<cal::LineLean> scattered;
  for (int i = 0; i < 20; ++i) scattered.push_back({-4.0 + 0.25 * i, (i % 2 ? 0.05 : -0.05)});
  CHECK_FALSE(cal::fit_frame_lean(scattered, a, g, 5, &why));
  CHECK(why.find("scatter") != std::string::npos);

  CHECK_FALSE(cal::fit_frame_lean({{0.0, 0.0}}, a, g, 2, &why));
  CHECK(why.find("need 2") != std::string::npos);
  CHECK_THROWS_AS(cal::apply_frame_correction(board::default_calibration(), 0.0, 0, 0, 0), std::invalid_argument);
}

TEST_CASE("End lines seen through a sheared view: their lean measured, board x right up the board after the correction") {
  // The camera sees the board sheared about the surface row (x moves by k px per px up): in the default
  // calibration's frame a vertical line leans by dx/dy = -k.
  const double k = 0.03;
  sim::CameraSetup camera;
  const double surface = camera.board.surface_y_px;
  camera.rectified_to_camera = cv::Matx33d(1, k, -k * surface, 0, 1, 0, 0, 0, 1);
  const sim::Renderer renderer(camera, sim::ProjectorSetup{});
  const bricklayer::calibration_t calibration = board::default_calibration();
  bricklayer::core::Stack stack;
  stack.blocks = {{1, 0, -3.6}, {2, 0, -2.2}, {3, 0, -0.8}, {4, 0, 0.4}, {5, 1, -3.3}};
  sim::Nuisance nuisance = sim::Nuisance::level(1);
  nuisance.layout_seed = 3;
  std::vector<cal::LineLean> leans;
  const double w = camera.line_width;
  const double h = calibration.block_height;
  for (uint64_t frame = 0; frame < 4; ++frame) {
    cv::Mat green;
    cv::extractChannel(renderer.render(stack, nuisance, nullptr, 40 + frame).bgr, green, 1);
    for (int i = 0; i < 4; ++i) {
      const double left = stack.blocks[i].x;
      for (double x : {left + w / 2, left + 1 - w / 2}) {
        const auto lean = cal::measure_line_lean(green, calibration, x, 0.2 * h, 0.75 * h);
        INFO("line at " << x);
        REQUIRE(lean);
        CHECK(*lean == Approx(-k).margin(0.006));
        leans.push_back({x, *lean});
      }
    }
  }
  // Nothing where no line is.
  cv::Mat empty;
  cv::extractChannel(renderer.render({}, nuisance, nullptr, 9).bgr, empty, 1);
  CHECK_FALSE(cal::measure_line_lean(empty, calibration, -2.0, 0.2 * h, 0.75 * h));

  std::string why;
  const auto fit = cal::fit_frame_lean(leans, 1.0, 0.0, 8, &why);
  INFO(why);
  REQUIRE(fit);
  CHECK(fit->shear == Approx(k).margin(0.003));
  const bricklayer::calibration_t corrected = cal::apply_frame_correction(calibration, 1.0, 0.0, fit->shear, fit->vertical_keystone);
  double before = 0, after = 0;
  for (double y = 0.2; y <= 3.2; y += 1.0) {
    for (double x = -4; x <= 4; x += 1.0) {
      const cv::Point2d p = sim::rectified_to_camera(camera, {camera.board.to_px_x(x), camera.board.to_px_y(y)});
      before = std::max(before, std::abs(board::camera_to_board(calibration, p).x - x));
      after = std::max(after, std::abs(board::camera_to_board(corrected, p).x - x));
    }
  }
  INFO("board x error up to 3.2 block lengths above the surface: " << before << " before, " << after << " after");
  CHECK(before > 0.08);
  CHECK(after < 0.015);
  CHECK(cal::frame_correction_change(1.0, 0.0, fit->shear, fit->vertical_keystone, 4, 3) > 0.08);
}
