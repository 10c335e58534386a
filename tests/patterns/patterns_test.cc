// The projected calibration patterns: Gray code identical to OpenCV's structured_light sequence,
// markers detectable exactly where marker_layout() says, solid colours and range checks.
#include <catch2/catch.hpp>

#include <opencv2/aruco.hpp>
#include <opencv2/calib3d.hpp>
#include <opencv2/imgproc.hpp>
#include <opencv2/structured_light.hpp>

#include <algorithm>
#include <map>
#include <set>

#include "bricklayer/patterns/patterns.h"

using bricklayer::command_t;
namespace patterns = bricklayer::patterns;

namespace {
command_t pattern_command(int32_t pattern, int32_t index) {
  command_t cmd{};
  cmd.command = command_t::SHOW_PATTERN;
  cmd.pattern = pattern;
  cmd.index = index;
  cmd.argument = "";
  return cmd;
}
}  // namespace

TEST_CASE("Gray-code images equal OpenCV's structured_light sequence") {
  for (const cv::Size size : {cv::Size(1024, 768), cv::Size(800, 600), cv::Size(37, 19)}) {
    auto gcp = cv::structured_light::GrayCodePattern::create(size.width, size.height);
    std::vector<cv::Mat> expected;
    REQUIRE(gcp->generate(expected));
    REQUIRE(static_cast<int>(expected.size()) == patterns::gray_code_image_count(size));
    REQUIRE(static_cast<int>(gcp->getNumberOfPatternImages()) == patterns::gray_code_image_count(size));
    for (int i = 0; i < patterns::gray_code_image_count(size); ++i) {
      const cv::Mat bgr = patterns::render_pattern(pattern_command(command_t::PATTERN_GRAY_CODE, i), size);
      REQUIRE(bgr.type() == CV_8UC3);
      REQUIRE(bgr.size() == size);
      cv::Mat gray;
      cv::cvtColor(bgr, gray, cv::COLOR_BGR2GRAY);
      INFO("size " << size << " image " << i);
      REQUIRE(cv::countNonZero(gray != expected[i]) == 0);
    }
  }
}

TEST_CASE("Gray-code images decode to every projector pixel with OpenCV's decoder") {
  const cv::Size size(64, 32);
  auto gcp = cv::structured_light::GrayCodePattern::create(size.width, size.height);
  std::vector<cv::Mat> captured;
  for (int i = 0; i < patterns::gray_code_image_count(size); ++i) {
    cv::Mat gray;
    cv::cvtColor(patterns::render_pattern(pattern_command(command_t::PATTERN_GRAY_CODE, i), size), gray, cv::COLOR_BGR2GRAY);
    captured.push_back(gray);
  }
  for (int y = 0; y < size.height; y += 3) {
    for (int x = 0; x < size.width; x += 5) {
      cv::Point p;
      REQUIRE_FALSE(gcp->getProjPixel(captured, x, y, p));  // true means error
      REQUIRE(p == cv::Point(x, y));
    }
  }
  CHECK_THROWS_AS(patterns::render_pattern(pattern_command(command_t::PATTERN_GRAY_CODE, patterns::gray_code_image_count(size)), size),
                  std::invalid_argument);
  CHECK_THROWS_AS(patterns::render_pattern(pattern_command(command_t::PATTERN_GRAY_CODE, -1), size), std::invalid_argument);
}

TEST_CASE("Every marker set is detected at its layout position") {
  const cv::Size size(1024, 768);
  auto dict = cv::aruco::getPredefinedDictionary(cv::aruco::DICT_4X4_250);
  auto params = cv::aruco::DetectorParameters::create();
  params->cornerRefinementMethod = cv::aruco::CORNER_REFINE_SUBPIX;
  for (int set = 0; set < patterns::kMarkerSetCount; ++set) {
    const auto layout = patterns::marker_layout(set, size);
    REQUIRE(layout.size() >= 5);
    cv::Mat image = patterns::render_pattern(pattern_command(command_t::PATTERN_MARKERS, set), size);
    std::vector<int> ids;
    std::vector<std::vector<cv::Point2f>> corners;
    cv::aruco::detectMarkers(image, dict, corners, ids, params);
    INFO("set " << set);
    REQUIRE(ids.size() == layout.size());
    std::map<int, std::vector<cv::Point2f>> found;
    for (size_t i = 0; i < ids.size(); ++i) found[ids[i]] = corners[i];
    for (const auto& m : layout) {
      REQUIRE(found.count(m.id) == 1);
      for (int k = 0; k < 4; ++k) {
        // Both at the pixel-edge position of the black border (measured bias of the detector ~0.06 px).
        CHECK(cv::norm(found[m.id][k] - m.corners[k]) < 0.2);
      }
    }
  }
  CHECK_THROWS_AS(patterns::marker_layout(patterns::kMarkerSetCount, size), std::invalid_argument);
}

TEST_CASE("The registration grids at 1024x768: 10 x 7 and 9 x 6 markers, 124 in all, as the READMEs say") {
  const cv::Size size(1024, 768);
  const auto grid = patterns::marker_layout(patterns::kMarkerSetGrid, size);
  const auto shifted = patterns::marker_layout(patterns::kMarkerSetShiftedGrid, size);
  std::set<int> xs, ys;
  for (const auto& m : grid) xs.insert(m.pixels.x), ys.insert(m.pixels.y);
  CHECK(xs.size() == 10);
  CHECK(ys.size() == 7);
  CHECK(grid.size() == 70);
  CHECK(shifted.size() == 54);
  CHECK(grid.size() + shifted.size() == 124);
  // The lowest corners, which the default setup's shelf top (row 704) comes close to.
  float lowest = 0;
  for (const auto& m : grid) lowest = std::max(lowest, m.corners[2].y);
  CHECK(lowest == Approx(704.5));
}

TEST_CASE("Solid colours, chessboard corners and bad commands") {
  const cv::Size size(320, 240);
  command_t cmd = pattern_command(command_t::PATTERN_SOLID, 0);
  cmd.red = 300;
  cmd.green = 10;
  cmd.blue = -4;
  const cv::Mat solid = patterns::render_pattern(cmd, size);
  CHECK(solid.at<cv::Vec3b>(100, 100) == cv::Vec3b(0, 10, 255));

  const cv::Mat chess = patterns::render_pattern(pattern_command(command_t::PATTERN_CHESSBOARD, 0), size);
  std::vector<cv::Point2f> corners;
  REQUIRE(cv::findChessboardCorners(chess, patterns::chessboard_inner_corners(size), corners));
  const auto expected = patterns::chessboard_corner_positions(size);
  REQUIRE(corners.size() == expected.size());
  // Either order (OpenCV may report it reversed: see NOTES); the positions as a set must agree.
  const bool forward = cv::norm(corners.front() - expected.front()) < 1.0;
  for (size_t i = 0; i < corners.size(); ++i) {
    const cv::Point2f e = forward ? expected[i] : expected[expected.size() - 1 - i];
    CHECK(cv::norm(corners[i] - e) < 1.0);
  }

  CHECK_THROWS_AS(patterns::render_pattern(pattern_command(99, 0), size), std::invalid_argument);
  CHECK_THROWS_AS(patterns::render_pattern(pattern_command(command_t::PATTERN_SOLID, 0), cv::Size(0, 0)), std::invalid_argument);
}
