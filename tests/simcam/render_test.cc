// The simulated camera's renderer: determinism, geometry truth, nuisances and projector light.
#include "bricklayer/simcam/render.h"

#include <catch2/catch.hpp>

#include <cmath>

#include <opencv2/imgproc.hpp>

#include "bricklayer/piles/random_pile.h"

using namespace bricklayer;
using namespace bricklayer::simcam;

namespace {

core::Stack three_blocks() {
  core::Stack s;
  s.blocks = {{1, 0, -0.8}, {2, 0, 0.45}, {3, 1, -0.3}};
  return s;
}

cv::Mat green(const cv::Mat& bgr) {
  cv::Mat g;
  cv::extractChannel(bgr, g, 1);
  g.convertTo(g, CV_64F);
  return g;
}

double bilinear(const cv::Mat& g, cv::Point2d p) {
  cv::Mat out;
  cv::Mat f;
  g.convertTo(f, CV_32F);
  cv::getRectSubPix(f, cv::Size(1, 1), cv::Point2f(static_cast<float>(p.x), static_cast<float>(p.y)), out, CV_32F);
  return out.at<float>(0, 0);
}

// Sub-pixel centre of the dark end line crossing image row v near column u, from the line's coverage
// of each pixel: from the brightness without the line on each side (bare board outside the
// block, tinted block inside) and the line's own brightness.
double line_centre(const cv::Mat& g, int v, double u, double left_bg, double right_bg, double line_level) {
  // Exact area coverage: the first touched pixel is covered on its right side only, so the line's left
  // edge is (i + 0.5 - coverage) and its centre half the total coverage further right.
  double sum = 0, left_edge = 0;
  bool first = true;
  for (int i = static_cast<int>(std::round(u)) - 3; i <= static_cast<int>(std::round(u)) + 3; ++i) {
    double bg = i < u ? left_bg : right_bg;
    double c = std::clamp((bg - g.at<double>(v, i)) / (bg - line_level), 0.0, 1.0);
    if (c < 0.01) continue;
    if (first) left_edge = i + 0.5 - c;
    first = false;
    sum += c;
  }
  return left_edge + sum / 2;
}

}  // namespace

TEST_CASE("render: the same inputs and seed give identical frames, another seed other noise") {
  core::Stack s = piles::random_pile(3, {.blocks = 25});
  Nuisance n = Nuisance::level(3);
  Renderer r(CameraSetup::random(11), ProjectorSetup::random(11));
  cv::Mat light(200, 300, CV_8UC3, cv::Scalar(255, 0, 0));
  Rendered a = r.render(s, n, &light, 42), b = r.render(s, n, &light, 42), c = r.render(s, n, &light, 43);
  CHECK(cv::norm(a.bgr, b.bgr, cv::NORM_INF) == 0);
  CHECK(cv::norm(a.bgr, c.bgr, cv::NORM_L1) > 0);
  // A fresh renderer (and the one-shot function) agree bit for bit.
  Rendered d = render(s, CameraSetup::random(11), n, &light, ProjectorSetup::random(11), 42);
  CHECK(cv::norm(a.bgr, d.bgr, cv::NORM_INF) == 0);
  REQUIRE(a.truth.size() == s.blocks.size());
}

TEST_CASE("render: truth corners sit on the rendered end lines to sub-pixel accuracy (default setup)") {
  core::Stack s = three_blocks();
  s.blocks.push_back({4, 2, 0.123456});
  s.blocks.push_back({5, 3, 0.0});
  CameraSetup cam;
  Rendered out = render(s, cam, Nuisance::level(0), nullptr, {}, 1);
  cv::Mat g = green(out.bgr);
  const double w = cam.line_width * cam.board.block_length_px;
  for (const auto& t : out.truth) {
    REQUIRE(t.visible);
    const auto& b = *std::find_if(s.blocks.begin(), s.blocks.end(), [&](const core::Block& k) { return k.id == t.id; });
    CHECK(t.x == Approx(b.x));
    CHECK(t.corners[0].x == Approx(cam.board.to_px_x(b.x)));
    CHECK(t.corners[0].y == Approx(cam.board.surface_y_px - b.row * cam.board.block_height_px));
    CHECK(t.corners[2].y == Approx(cam.board.surface_y_px - (b.row + 1) * cam.board.block_height_px));
    int v = static_cast<int>(std::round((t.corners[0].y + t.corners[3].y) / 2));
    double inside = g.at<double>(v, static_cast<int>(std::round(t.corners[0].x + 10)));  // block interior
    double board = g.at<double>(v, 5);                                                     // bare glass
    double line = 0.07 * inside;  // the line's reflectance times the block's
    double left = line_centre(g, v, t.corners[0].x + w / 2, board, inside, line);
    double right = line_centre(g, v, t.corners[1].x - w / 2, inside, board, line);
    CHECK(left == Approx(t.corners[0].x + w / 2).margin(0.03));
    CHECK(right == Approx(t.corners[1].x - w / 2).margin(0.03));
    CHECK(g.at<double>(v, static_cast<int>(std::round(left))) < 0.4 * inside);  // the line is dark
  }
}

TEST_CASE("render: truth corners follow homography and lens distortion (random setups)") {
  for (uint64_t seed : {1, 2, 3, 4, 5}) {
    CameraSetup cam = CameraSetup::random(seed);
    REQUIRE(cam.has_lens_distortion());
    core::Stack s = three_blocks();
    Rendered out = render(s, cam, Nuisance::level(0), nullptr, {}, 1);
    cv::Mat g = green(out.bgr);
    const double w = cam.line_width * cam.board.block_length_px;
    for (const auto& t : out.truth) {
      // Line centre at mid-height in rectified pixels, mapped like the truth.
      cv::Point2d rect_mid_left = camera_to_rectified(cam, (t.corners[0] + t.corners[3]) / 2) + cv::Point2d(w / 2, 0);
      cv::Point2d line = rectified_to_camera(cam, rect_mid_left);
      cv::Point2d inside = rectified_to_camera(cam, rect_mid_left + cv::Point2d(10, 0));
      INFO("seed " << seed << " block " << t.id);
      CHECK(bilinear(g, line) < 0.6 * bilinear(g, inside));
    }
    // The mapping helpers are inverse to each other.
    for (cv::Point2d p : {cv::Point2d(5, 7), cv::Point2d(320, 240), cv::Point2d(630, 470)}) {
      cv::Point2d q = rectified_to_camera(cam, camera_to_rectified(cam, p));
      CHECK(cv::norm(q - p) < 1e-6);
      cv::Point2d pr = camera_to_projector(cam, ProjectorSetup{}, p);
      CHECK(cv::norm(projector_to_camera(cam, ProjectorSetup{}, pr) - p) < 1e-6);
    }
  }
}

TEST_CASE("render: named nuisance levels and bad names") {
  CHECK(Nuisance::level(0).name == "clean");
  CHECK(Nuisance::named("harsh").shadow_count == 3);
  CHECK(Nuisance::named("2").name == "strong");
  CHECK_THROWS_WITH(Nuisance::level(4), Catch::Contains("0..3"));
  CHECK_THROWS_WITH(Nuisance::named("foggy"), Catch::Contains("clean, mild, strong, harsh"));
}

TEST_CASE("render: each nuisance changes the image as specified") {
  core::Stack empty;
  CameraSetup cam;
  Nuisance base;  // everything off
  base.unevenness = 0;
  auto frame = [&](const Nuisance& n, uint64_t seed = 1) { return green(render(empty, cam, n, nullptr, {}, seed).bgr); };
  cv::Mat clean = frame(base);
  const double centre = clean.at<double>(240, 320);
  CHECK(centre == Approx(cam.board_brightness).margin(1.0));
  CHECK(clean.at<double>(20, 20) == Approx(centre).margin(1.0));  // flat without nuisances

  SECTION("vignetting darkens the corners to 1 - vignetting") {
    Nuisance n = base;
    n.vignetting = 0.3;
    cv::Mat g = frame(n);
    CHECK(g.at<double>(240, 320) == Approx(centre).margin(1.5));
    CHECK(g.at<double>(0, 0) / centre == Approx(0.7).margin(0.02));
  }
  SECTION("the gradient spans +-gradient/2") {
    Nuisance n = base;
    n.gradient = 0.4;
    cv::Mat g = frame(n);
    double lo, hi;
    cv::minMaxLoc(g(cv::Rect(0, 0, 640, 400)), &lo, &hi);
    CHECK(hi / lo > 1.2);
    CHECK(hi / lo < 1.5);
    CHECK(g.at<double>(240, 320) == Approx(centre).margin(1.5));
  }
  SECTION("shadows darken part of the board by up to their strength, softly") {
    Nuisance n = base;
    n.shadow_count = 2;
    n.shadow_strength = 0.5;
    cv::Mat g = frame(n)(cv::Rect(0, 0, 640, 430));
    double lo, hi;
    cv::minMaxLoc(g, &lo, &hi);
    CHECK(lo / centre < 0.75);
    CHECK(lo / centre > 0.45);
    CHECK(hi == Approx(centre).margin(1.5));
    // Soft: neighbouring pixels never jump by more than a few levels.
    cv::Mat dx;
    cv::Sobel(g, dx, CV_64F, 1, 0, 1);
    double max_step;
    cv::minMaxLoc(cv::abs(dx), nullptr, &max_step);
    CHECK(max_step < 6);
    // Shadows move smoothly with time_s: a little later, a little different.
    Nuisance later = n;
    later.time_s = 0.1;
    later.layout_seed = n.layout_seed = 99;
    double moved = cv::norm(frame(n), frame(later), cv::NORM_INF);
    CHECK(moved < 15);
  }
  SECTION("noise grows with brightness and is zero-mean") {
    Nuisance n = base;
    n.noise = 4.0;
    cv::Mat g = frame(n) - clean;
    cv::Scalar m_bright, s_bright, m_dark, s_dark;
    cv::meanStdDev(g(cv::Rect(100, 100, 400, 200)), m_bright, s_bright);
    cv::meanStdDev(g(cv::Rect(10, 445, 280, 30)), m_dark, s_dark);  // the shelf
    CHECK(s_bright[0] == Approx(4.0 * std::sqrt(centre / 255.0)).epsilon(0.1));
    CHECK(s_dark[0] < 0.8 * s_bright[0]);
    CHECK(std::abs(m_bright[0]) < 0.1);
  }
  SECTION("blur softens the end lines") {
    core::Stack s = three_blocks();
    Nuisance sharp = base, blurred = base;
    blurred.blur_sigma = 1.5;
    cv::Mat a = green(render(s, cam, sharp, nullptr, {}, 1).bgr), b = green(render(s, cam, blurred, nullptr, {}, 1).bgr);
    int v = static_cast<int>(cam.board.surface_y_px - 10);
    double lo_a, lo_b;
    cv::minMaxLoc(a.row(v), &lo_a);
    cv::minMaxLoc(b.row(v), &lo_b);
    CHECK(lo_b > lo_a + 20);
  }
  SECTION("levels disturb the frame more as they get harsher") {
    core::Stack s = three_blocks();
    cv::Mat ref = green(render(s, cam, Nuisance::level(0), nullptr, {}, 5).bgr);
    double previous = 0;
    for (int level = 1; level <= 3; ++level) {
      double diff = cv::norm(ref, green(render(s, cam, Nuisance::level(level), nullptr, {}, 5).bgr), cv::NORM_L1);
      CHECK(diff > previous);
      previous = diff;
    }
  }
}

TEST_CASE("render: projector light appears through the mixing matrix, red and blue leaking into green") {
  core::Stack empty;
  CameraSetup cam;
  ProjectorSetup proj;
  Nuisance n;
  n.unevenness = 0;
  cv::Mat off = render(empty, cam, n, nullptr, proj, 1).bgr;
  auto added = [&](cv::Scalar colour) {
    cv::Mat light(proj.size, CV_8UC3, colour);
    cv::Mat on = render(empty, cam, n, &light, proj, 1).bgr;
    cv::Mat diff;
    cv::subtract(on, off, diff, cv::noArray(), CV_64FC3);
    return cv::mean(diff(cv::Rect(200, 150, 240, 180)));
  };
  for (int ch = 0; ch < 3; ++ch) {
    cv::Scalar colour(0, 0, 0);
    colour[ch] = 100;  // not 255: a full drive on the lit board saturates the camera
    cv::Scalar d = added(colour);
    for (int cam_ch = 0; cam_ch < 3; ++cam_ch) {
      INFO("projector channel " << ch << " camera channel " << cam_ch);
      CHECK(d[cam_ch] == Approx(proj.mixing(cam_ch, ch) * 100 + proj.ambient[cam_ch]).margin(0.6));
    }
  }
  cv::Scalar black = added(cv::Scalar(0, 0, 0));
  CHECK(black[1] == Approx(proj.ambient[1]).margin(0.6));
  // Red and blue both leak into green noticeably.
  CHECK(proj.mixing(1, 2) > 0.05);
  CHECK(proj.mixing(1, 0) > 0.05);

  // Geometry: a projector image lit only in its left half lights the camera's left half (default 1.6 scale),
  // also when the image arrives downscaled (as on BL_PROJECTOR).
  cv::Mat half(proj.size.height / 4, proj.size.width / 4, CV_8UC3, cv::Scalar(0, 0, 0));
  half(cv::Rect(0, 0, half.cols / 2, half.rows)).setTo(cv::Scalar(0, 0, 255));
  cv::Mat on = render(empty, cam, n, &half, proj, 1).bgr;
  CHECK(int{on.at<cv::Vec3b>(240, 300)[2]} > int{off.at<cv::Vec3b>(240, 300)[2]} + 60);
  CHECK(int{on.at<cv::Vec3b>(240, 340)[2]} < int{off.at<cv::Vec3b>(240, 340)[2]} + 10);

  // Random setups: the camera pixel projector_to_camera(p) shows projector pixel p.
  for (uint64_t seed : {3, 4}) {
    CameraSetup rc = CameraSetup::random(seed);
    ProjectorSetup rp = ProjectorSetup::random(seed);
    cv::Mat dot(rp.size, CV_8UC3, cv::Scalar(0, 0, 0));
    cv::Point2d p(400, 300);
    cv::circle(dot, cv::Point(400, 300), 12, cv::Scalar(255, 255, 255), cv::FILLED);
    cv::Mat lit = render(empty, rc, n, &dot, rp, 1).bgr, dark = render(empty, rc, n, nullptr, rp, 1).bgr;
    cv::Point2d c = projector_to_camera(rc, rp, p);
    cv::Mat diff = green(lit) - green(dark);
    cv::Moments mo = cv::moments(cv::max(diff - 20, 0));
    REQUIRE(mo.m00 > 0);
    CHECK(cv::norm(cv::Point2d(mo.m10 / mo.m00, mo.m01 / mo.m00) - c) < 0.3);
  }
}

TEST_CASE("render: bad input is an exception with a message, not a crash") {
  core::Stack s = three_blocks();
  s.blocks[1].x = std::nan("");
  CHECK_THROWS_WITH(render(s, {}, {}, nullptr, {}, 1), Catch::Contains("block 2"));
  cv::Mat gray(10, 10, CV_8UC1, cv::Scalar(0));
  CHECK_THROWS_WITH(render(three_blocks(), {}, {}, &gray, {}, 1), Catch::Contains("CV_8UC3"));
  CameraSetup tiny;
  tiny.size = {2, 2};
  CHECK_THROWS(Renderer(tiny));
}

TEST_CASE("random piles: exact count, no overlaps within a row, deterministic") {
  for (int n : {10, 40, 80}) {
    core::Stack a = piles::random_pile(static_cast<uint64_t>(n), {.blocks = n}), b = piles::random_pile(static_cast<uint64_t>(n), {.blocks = n});
    REQUIRE(static_cast<int>(a.blocks.size()) == n);
    for (size_t i = 0; i < a.blocks.size(); ++i) CHECK(a.blocks[i].x == b.blocks[i].x);
    for (const auto& p : a.blocks)
      for (const auto& q : a.blocks)
        if (p.id != q.id && p.row == q.row) CHECK(std::abs(p.x - q.x) >= 1.0 + 0.1 - 1e-9);
  }
}
