// Calibration against simcam: random camera/projector setups (homography, lens distortion, colour
// mixing) rendered with noise; the recovered camera -> projector mapping and colour mixing are
// compared with the setup's truth. Plus the drift self-check and the rejection paths.
#include <catch2/catch.hpp>

#include <algorithm>
#include <cmath>
#include <iostream>

#include "bricklayer/calibration/calibrator.h"
#include "bricklayer/board/calibration_file.h"
#include "bricklayer/board/mapping.h"
#include "bricklayer/patterns/patterns.h"
#include "bricklayer/simcam/render.h"

namespace cal = bricklayer::calibration;
namespace board = bricklayer::board;
namespace patterns = bricklayer::patterns;
namespace sim = bricklayer::simcam;

namespace {

// The frames calibrate would collect: every step's pattern rendered through the setup.
std::vector<cv::Mat> capture(const sim::Renderer& renderer, const std::vector<cal::CalibrationStep>& steps,
                             const sim::Nuisance& nuisance, uint64_t seed) {
  std::vector<cv::Mat> frames;
  const bricklayer::core::Stack empty;
  for (size_t i = 0; i < steps.size(); ++i) {
    const cv::Mat shown = patterns::render_pattern(steps[i].command, renderer.projector().size);
    frames.push_back(renderer.render(empty, nuisance, &shown, seed * 100 + i).bgr);
  }
  return frames;
}

struct MappingError {
  double mean = 0;
  double max = 0;
  int points = 0;
  cv::Point2d worst_at;  // rectified pixels
};

// Camera pixel -> projector pixel, calibration vs truth, over a grid covering the board (the
// rectified frame 0..640 x 0..480 as the camera sees it).
MappingError mapping_error(const bricklayer::calibration_t& c, const sim::CameraSetup& camera,
                           const sim::ProjectorSetup& projector, cv::Rect2d region = {10, 10, 620, 460}, double step = 20) {
  MappingError e;
  double sum = 0;
  for (double y = region.y; y <= region.br().y + 1e-9; y += step) {
    for (double x = region.x; x <= region.br().x + 1e-9; x += step) {
      const cv::Point2d cam = sim::rectified_to_camera(camera, {x, y});
      if (cam.x < 2 || cam.y < 2 || cam.x > camera.size.width - 3 || cam.y > camera.size.height - 3) continue;
      const cv::Point2d truth = sim::camera_to_projector(camera, projector, cam);
      const double d = cv::norm(board::camera_to_projector(c, cam) - truth);
      sum += d;
      if (d > e.max) e.worst_at = {x, y};
      e.max = std::max(e.max, d);
      ++e.points;
    }
  }
  e.mean = e.points ? sum / e.points : 1e9;
  return e;
}

sim::Nuisance calibration_nuisance() {
  sim::Nuisance n = sim::Nuisance::level(1);  // mild: gradient, vignetting, a player's shadow, blur, noise, JPEG 95
  n.layout_seed = 7;
  return n;
}

}  // namespace

TEST_CASE("Twenty random setups: mapping within 0.5 px mean / 1.5 px max, colour mixing within 5%") {
  cal::CalibrationOptions options;
  const auto steps = cal::calibration_steps(options);
  double worst_mean = 0, worst_max = 0, worst_colour = 0;
  for (uint64_t seed = 1; seed <= 20; ++seed) {
    const sim::CameraSetup camera = sim::CameraSetup::random(seed);
    const sim::ProjectorSetup projector = sim::ProjectorSetup::random(seed);
    const sim::Renderer renderer(camera, projector);
    const auto frames = capture(renderer, steps, calibration_nuisance(), seed);
    const cal::CalibrationResult result = cal::compute_calibration(frames, options, 1000);
    INFO("seed " << seed << ": " << result.message);
    REQUIRE(result.status == cal::CalibrationStatus::kOk);
    REQUIRE_NOTHROW(board::validate_calibration(result.calibration));
    CHECK(result.shelf.found);

    const MappingError e = mapping_error(result.calibration, camera, projector);
    INFO("mapping error mean " << e.mean << " max " << e.max << " over " << e.points << " grid points");
    CHECK(e.points > 500);
    CHECK(e.mean < 0.5);
    CHECK(e.max < 1.5);
    worst_mean = std::max(worst_mean, e.mean);
    worst_max = std::max(worst_max, e.max);

    // Colour: every entry within 5% of the largest (the diagonal), and the diagonal within 5% of itself.
    const cv::Matx33d m = board::colour_mixing(result.calibration);
    const double scale = std::max({projector.mixing(0, 0), projector.mixing(1, 1), projector.mixing(2, 2)});
    for (int i = 0; i < 3; ++i) {
      for (int j = 0; j < 3; ++j) {
        const double err = std::abs(m(i, j) - projector.mixing(i, j));
        INFO("mixing(" << i << "," << j << ") = " << m(i, j) << ", truth " << projector.mixing(i, j));
        CHECK(err < 0.05 * scale);
        if (i == j) CHECK(err < 0.05 * projector.mixing(i, i));
        worst_colour = std::max(worst_colour, err / scale);
      }
    }
  }
  std::cout << "calibration over 20 random setups: worst mean " << worst_mean << " px, worst max " << worst_max
            << " px, worst colour error " << 100 * worst_colour << "% of full scale\n";
}

TEST_CASE("Self-check catches a moved camera and passes an unmoved one") {
  cal::CalibrationOptions options;
  const uint64_t seed = 5;
  const sim::CameraSetup camera = sim::CameraSetup::random(seed);
  const sim::ProjectorSetup projector = sim::ProjectorSetup::random(seed);
  const sim::Renderer renderer(camera, projector);
  const auto result = cal::compute_calibration(capture(renderer, cal::calibration_steps(options), calibration_nuisance(), seed), options, 1);
  REQUIRE(result.status == cal::CalibrationStatus::kOk);

  const cv::Mat check = patterns::render_pattern(cal::self_check_command(), projector.size);
  const bricklayer::core::Stack empty;
  const auto unmoved = cal::self_check(result.calibration, renderer.render(empty, calibration_nuisance(), &check, 99).bgr);
  INFO(unmoved.message);
  REQUIRE(unmoved.measured);
  CHECK(unmoved.markers_found == 5);
  CHECK(unmoved.drift_mean_px < 0.5);
  CHECK(unmoved.drift_max_px < 1.5);

  // Knock the camera: 4 px right, 2 px down and 0.5 degrees of rotation.
  sim::CameraSetup moved = camera;
  const double a = 0.5 * M_PI / 180;
  const cv::Matx33d knock(std::cos(a), -std::sin(a), 4, std::sin(a), std::cos(a), 2, 0, 0, 1);
  moved.rectified_to_camera = knock * camera.rectified_to_camera;
  const sim::Renderer moved_renderer(moved, projector);
  const auto drifted = cal::self_check(result.calibration, moved_renderer.render(empty, calibration_nuisance(), &check, 99).bgr);
  INFO(drifted.message);
  REQUIRE(drifted.measured);
  CHECK(drifted.drift_mean_px > 3.0);

  // Nothing projected: not measured, with a message saying why.
  const auto dark = cal::self_check(result.calibration, renderer.render(empty, calibration_nuisance(), nullptr, 99).bgr);
  CHECK_FALSE(dark.measured);
  CHECK(dark.message.find("no self-check marker") != std::string::npos);
}

TEST_CASE("Calibrations that cannot be trusted are rejected with a clear message") {
  cal::CalibrationOptions options;
  const uint64_t seed = 3;
  const sim::CameraSetup camera = sim::CameraSetup::random(seed);
  const sim::ProjectorSetup projector = sim::ProjectorSetup::random(seed);
  const sim::Renderer renderer(camera, projector);
  const auto steps = cal::calibration_steps(options);

  SECTION("reprojection error above --max-error-px") {
    // A blurred, noisy camera: corners still found, but less precisely than a strict threshold allows.
    sim::Nuisance bad = sim::Nuisance::level(3);
    bad.blur_sigma = 1.5;
    bad.noise = 8;
    cal::CalibrationOptions strict = options;
    strict.max_error_px = 0.05;
    const auto result = cal::compute_calibration(capture(renderer, steps, bad, seed), strict, 1);
    INFO(result.message);
    CHECK(result.status == cal::CalibrationStatus::kErrorTooHigh);
    CHECK(result.message.find("exceeds --max-error-px") != std::string::npos);
  }
  SECTION("projector off: no markers") {
    std::vector<cv::Mat> frames;
    for (size_t i = 0; i < steps.size(); ++i) frames.push_back(renderer.render({}, calibration_nuisance(), nullptr, i).bgr);
    const auto result = cal::compute_calibration(frames, options, 1);
    INFO(result.message);
    CHECK(result.status == cal::CalibrationStatus::kTooFewPoints);
    CHECK(result.message.find("markers detected") != std::string::npos);
  }
  SECTION("wrong number of frames, empty frames") {
    auto frames = capture(renderer, steps, calibration_nuisance(), seed);
    frames.pop_back();
    CHECK(cal::compute_calibration(frames, options, 1).status == cal::CalibrationStatus::kBadFrames);
    frames.push_back(cv::Mat());
    const auto result = cal::compute_calibration(frames, options, 1);
    CHECK(result.status == cal::CalibrationStatus::kBadFrames);
    CHECK(result.message.find("step 6") != std::string::npos);
  }
  SECTION("saturated camera") {
    cal::CalibrationOptions bright = options;
    bright.colour_drive = 255;
    const auto result = cal::compute_calibration(capture(renderer, cal::calibration_steps(bright), calibration_nuisance(), seed), bright, 1);
    INFO(result.message);
    CHECK(result.status == cal::CalibrationStatus::kSaturated);
  }
}

namespace {
// Board coordinates (block lengths) of a camera pixel, as the setup defines them.
cv::Point2d true_board(const sim::CameraSetup& camera, cv::Point2d camera_px) {
  const cv::Point2d r = sim::camera_to_rectified(camera, camera_px);
  return {(r.x - camera.board.edge_x_px) / camera.board.block_length_px,
          (camera.board.surface_y_px - r.y) / camera.board.block_length_px};
}
}  // namespace

TEST_CASE("The board frame: exact with a square projector, shelf-anchored with a tilted one") {
  cal::CalibrationOptions options;
  const auto steps = cal::calibration_steps(options);
  for (uint64_t seed = 1; seed <= 4; ++seed) {
    const sim::CameraSetup camera = sim::CameraSetup::random(seed);
    SECTION("square projector, seed " + std::to_string(seed)) {
      const sim::ProjectorSetup projector;  // mounted square: projector pixel = 1.6 rectified pixels
      const sim::Renderer renderer(camera, projector);
      const auto result = cal::compute_calibration(capture(renderer, steps, calibration_nuisance(), seed), options, 1);
      INFO(result.message);
      REQUIRE(result.status == cal::CalibrationStatus::kOk);
      CHECK(result.shelf.found);
      double worst = 0;
      for (double y = 10; y <= 470; y += 20) {
        for (double x = 10; x <= 630; x += 20) {
          const cv::Point2d p = sim::rectified_to_camera(camera, {x, y});
          if (p.x < 2 || p.y < 2 || p.x > 637 || p.y > 477) continue;
          worst = std::max(worst, cv::norm(board::camera_to_board(result.calibration, p) - true_board(camera, p)));
        }
      }
      INFO("worst board error " << worst << " block lengths");
      CHECK(worst < 0.02);
    }
    SECTION("random projector, seed " + std::to_string(seed)) {
      const sim::ProjectorSetup projector = sim::ProjectorSetup::random(seed);
      const sim::Renderer renderer(camera, projector);
      const auto result = cal::compute_calibration(capture(renderer, steps, calibration_nuisance(), seed), options, 1);
      INFO(result.message);
      REQUIRE(result.status == cal::CalibrationStatus::kOk);
      REQUIRE(result.shelf.found);
      // The surface edge is the board origin and the surface top is level; the scale is the
      // projector's (not observable on an empty board).
      const auto at = [&](double bx, double by) {
        const cv::Point2d r(camera.board.to_px_x(bx), camera.board.to_px_y(by));
        return board::camera_to_board(result.calibration, sim::rectified_to_camera(camera, r));
      };
      const cv::Point2d origin = at(0, 0);
      INFO("origin maps to " << origin);
      CHECK(std::abs(origin.x) < 0.03);
      CHECK(std::abs(origin.y) < 0.03);
      for (double bx = -4; bx <= 4; bx += 1) CHECK(std::abs(at(bx, 0).y) < 0.03);
    }
  }
}

TEST_CASE("Under harsh nuisance the shelf is found whole: its top's columns scatter by a few pixels without ending it") {
  // Mountings 4 and 6 at the harsh level (the bench's frames: layout seed 7): single columns' steps scatter by
  // 3-5 px, and judged against the previous column alone the shelf top ended a few blocks in, its end was
  // not seen and the board frame stayed as given (the true origin 0.45 and 0.14 block lengths off). Judged
  // against the median of the last few columns the run goes on to the real end (measured: the origin within
  // 0.0127 over 20 harsh mountings).
  cal::CalibrationOptions options;
  const auto steps = cal::calibration_steps(options);
  for (const uint64_t seed : {uint64_t{4}, uint64_t{6}}) {
    DYNAMIC_SECTION("mounting " << seed) {
      const sim::CameraSetup camera = sim::CameraSetup::random(seed);
      const sim::Renderer renderer(camera, sim::ProjectorSetup::random(seed));
      sim::Nuisance harsh = sim::Nuisance::named("harsh");
      harsh.layout_seed = 7;
      const auto result = cal::compute_calibration(capture(renderer, steps, harsh, seed), options, 1);
      INFO(result.message << "; shelf: " << result.shelf.message);
      REQUIRE(result.status == cal::CalibrationStatus::kOk);
      CHECK(result.shelf.found);
      const cv::Point2d origin = board::camera_to_board(
          result.calibration, sim::rectified_to_camera(camera, {camera.board.edge_x_px, camera.board.surface_y_px}));
      INFO("the true origin maps to " << origin);
      CHECK(cv::norm(origin) < 0.015);
    }
  }
}

namespace {
// The setup the shelf sweep renders: a square projector (projector pixel = 1.6 rectified pixels, as
// a squarely mounted one), a random camera pose and lens, and the shelf's top edge `below_px`
// projector pixels below the lower corners of the bottom marker row.
sim::CameraSetup camera_with_shelf_below_markers(uint64_t seed, double below_px) {
  sim::CameraSetup camera = sim::CameraSetup::random(seed);
  const sim::ProjectorSetup projector;
  double lowest = 0;
  for (const auto& m : patterns::marker_layout(patterns::kMarkerSetGrid, projector.size))
    lowest = std::max(lowest, static_cast<double>(m.corners[2].y));
  camera.board.surface_y_px = (lowest + below_px) / 1.6;
  return camera;
}
}  // namespace

// Where the markers are: the hull of the registration grids in the rectified frame (projector
// 63..961 x 63..705 at 1024x768 through a square projector). Outside it, towards the frame corners,
// the mapping is extrapolated (in simcam up to 0.45-0.77 projector px with or without a shelf nearby).
const cv::Rect2d kMarkerHull(40, 40, 560, 400);

TEST_CASE("The shelf edge just below the bottom marker row: corners whose refinement window meets it are left out") {
  cal::CalibrationOptions options;
  const auto steps = cal::calibration_steps(options);
  const sim::ProjectorSetup projector;
  double worst = 0;
  for (uint64_t seed = 1; seed <= 3; ++seed) {
    for (double below = 2; below <= 10; below += 2) {
      const sim::CameraSetup camera = camera_with_shelf_below_markers(seed, below);
      const sim::Renderer renderer(camera, projector);
      const auto frames = capture(renderer, steps, calibration_nuisance(), seed);
      const cal::CalibrationResult result = cal::compute_calibration(frames, options, 1);
      INFO("seed " << seed << ", shelf " << below << " projector px below the corners: " << result.message);
      REQUIRE(result.status == cal::CalibrationStatus::kOk);
      CHECK(result.shelf.found);
      CHECK(result.near_shelf > 0);
      const MappingError e = mapping_error(result.calibration, camera, projector, kMarkerHull, 10);
      INFO("mapping error mean " << e.mean << " max " << e.max << " at rectified " << e.worst_at);
      CHECK(e.max < 0.5);
      CHECK(result.calibration.reprojection_error_max_px < options.max_point_error_px);
      worst = std::max(worst, e.max);
    }
  }
  std::cout << "shelf swept 2..10 projector px below the bottom marker row: worst max mapping error " << worst << " px\n";
}

TEST_CASE("A fit bent by the shelf edge is rejected on its largest error, not accepted on its mean") {
  // Measured: with every corner kept, the shelf 4 projector px below the corners bends this setup's
  // fit to 0.68 px (truth) near the shelf while the mean stays 0.27 px.
  const uint64_t seed = 6;
  const sim::ProjectorSetup projector;
  const sim::CameraSetup camera = camera_with_shelf_below_markers(seed, 4);
  const sim::Renderer renderer(camera, projector);
  cal::CalibrationOptions keep_all;
  keep_all.shelf_clearance_camera_px = 0;
  const auto frames = capture(renderer, cal::calibration_steps(keep_all), calibration_nuisance(), seed);
  const cal::CalibrationResult bent = cal::compute_calibration(frames, keep_all, 1);
  INFO(bent.message);
  CHECK(bent.status == cal::CalibrationStatus::kErrorTooHigh);
  CHECK(bent.calibration.reprojection_error_mean_px < keep_all.max_error_px);
  CHECK(bent.calibration.reprojection_error_max_px > keep_all.max_point_error_px);
  CHECK(bent.message.find("largest reprojection error") != std::string::npos);
  CHECK(bent.message.find("--max-point-error-px") != std::string::npos);
  CHECK(bent.message.find("at the marker drawn at projector pixel") != std::string::npos);
  const MappingError bent_error = mapping_error(bent.calibration, camera, projector, kMarkerHull, 10);
  CHECK(bent_error.max > 0.5);

  // The same frames with the default clearance: accepted, and right.
  const cal::CalibrationResult clear = cal::compute_calibration(frames, cal::CalibrationOptions{}, 1);
  INFO(clear.message);
  REQUIRE(clear.status == cal::CalibrationStatus::kOk);
  CHECK(mapping_error(clear.calibration, camera, projector, kMarkerHull, 10).max < 0.5);

  SECTION("a stricter --max-point-error-px") {
    cal::CalibrationOptions strict;
    strict.max_point_error_px = 0.3;
    const cal::CalibrationResult result = cal::compute_calibration(frames, strict, 1);
    INFO(result.message);
    CHECK(result.status == cal::CalibrationStatus::kErrorTooHigh);
    CHECK(result.message.find("exceeds --max-point-error-px 0.300") != std::string::npos);
  }
}
