// The position uncertainty's parts on frames whose answers are known: synthetic end lines of a known width,
// depth and noise (what measure_evidence must read back), and the model's terms one at a time (each grows
// with what it stands for), the pixel-phase bound against the detector's own error, the temporal term, the
// calibration floor and how they combine.
#include "bricklayer/vision/position_uncertainty.h"

#include <catch2/catch.hpp>

#include <cmath>

#include <opencv2/imgproc.hpp>

#include "bricklayer/board/calibration_file.h"

using namespace bricklayer;
using namespace bricklayer::vision;
using detection::BoardFrame;
using detection::DetectedBlock;

namespace {

const BoardGeometry kBoard;  // 60 px blocks, 20 px rows, edge at 320, surface at 440
constexpr double kLineWidth = 1.5;  // px

// A board at `level` with one block (row 0, left end at x) drawn as two dark end lines of kLineWidth px that
// absorb `depth` of the light, exact column coverage; then Gaussian blur `sigma` and noise `noise` (8-bit levels,
// a fixed seed).
cv::Mat frame_with_block(double x, double level, double depth, double sigma, double noise, uint64_t seed = 1) {
  cv::Mat f(480, 640, CV_32F, cv::Scalar(level));
  const double left = kBoard.to_px_x(x), right = left + kBoard.block_length_px;
  auto cover = [](double a, double b, int col) {  // coverage of pixel col (spanning col-0.5..col+0.5) by [a, b]
    return std::max(0.0, std::min(b, col + 0.5) - std::max(a, col - 0.5));
  };
  const int top = static_cast<int>(kBoard.surface_y_px - kBoard.block_height_px), bottom = static_cast<int>(kBoard.surface_y_px);
  for (int y = top; y < bottom; ++y)
    for (int c = 0; c < 640; ++c) {
      const double k = cover(left, left + kLineWidth, c) + cover(right - kLineWidth, right, c);
      f.at<float>(y, c) = static_cast<float>(level * (1.0 - depth * k));
    }
  if (sigma > 0) cv::GaussianBlur(f, f, cv::Size(0, 0), sigma);
  if (noise > 0) {
    cv::Mat n(f.size(), CV_32F);
    cv::RNG rng(seed);
    rng.fill(n, cv::RNG::NORMAL, 0.0, noise);
    f += n;
  }
  cv::Mat out;
  f.convertTo(out, CV_8U);
  return out;
}

DetectedBlock block_at(double x) {
  DetectedBlock b;
  b.row = 0;
  b.x = x;
  b.left_line_px = kBoard.to_px_x(x) + 0.5 * kLineWidth;
  b.right_line_px = kBoard.to_px_x(x) + kBoard.block_length_px - 0.5 * kLineWidth;
  return b;
}

BlockEvidence read(const cv::Mat& f, double x = -1.0) {
  const BoardFrame board(kBoard);
  const auto e = measure_evidence(f, board, {block_at(x)});
  REQUIRE(e.size() == 1);
  return e[0];
}

}  // namespace

TEST_CASE("measure_evidence reads back a line's depth, width and noise, and its rows' scatter grows with the noise") {
  const BlockEvidence sharp = read(frame_with_block(-1.0, 170, 0.8, 0.0, 0.0));
  REQUIRE(sharp.left.measured);
  REQUIRE(sharp.right.measured);
  // A 1.5 px line absorbing 80% is as dark as 0.8 over its middle pixel's full coverage.
  CHECK(sharp.left.depth == Approx(0.8).margin(0.02));
  CHECK(sharp.left.width_px == Approx(kLineWidth).margin(0.6));
  CHECK(sharp.left.noise < 0.003);   // 8-bit rounding only
  CHECK(sharp.left.scatter_px < 0.01);
  CHECK(sharp.pair_residual_px < 0.05);  // one block apart, as the pair's kind implies

  const BlockEvidence blurred = read(frame_with_block(-1.0, 170, 0.8, 1.5, 0.0));
  REQUIRE(blurred.left.measured);
  CHECK(blurred.left.width_px > sharp.left.width_px + 1.5);  // a Gaussian of sigma 1.5 adds ~3.5 px at half depth
  CHECK(blurred.left.depth < 0.6 * sharp.left.depth);         // the same ink spread wider is shallower

  const BlockEvidence noisy = read(frame_with_block(-1.0, 170, 0.8, 0.0, 4.0));
  const BlockEvidence noisier = read(frame_with_block(-1.0, 170, 0.8, 0.0, 12.0));
  REQUIRE(noisy.left.measured);
  REQUIRE(noisier.left.measured);
  CHECK(noisy.left.noise == Approx(4.0 / 170).epsilon(0.35));  // a few dozen samples: within a third
  CHECK(noisier.left.noise == Approx(12.0 / 170).epsilon(0.35));
  CHECK(noisier.left.scatter_px > noisy.left.scatter_px);
  CHECK(noisy.left.scatter_px > sharp.left.scatter_px);
  CHECK(noisy.left.rows_effective <= 12.0);  // the band's rows (20 px less the detector's margins)
}

TEST_CASE("a line outside the image or a dark frame gives unmeasured evidence and the model's fallback") {
  const BoardFrame board(kBoard);
  DetectedBlock outside = block_at(-6.0);  // left end at -40 px
  const auto e = measure_evidence(frame_with_block(-1.0, 170, 0.8, 0, 0), board, {outside});
  REQUIRE(e.size() == 1);
  CHECK_FALSE(e[0].left.measured);
  const UncertaintyModel model;
  CHECK(frame_uncertainty(e[0], kBoard.block_length_px, model) == model.unmeasured);
  const auto dark = measure_evidence(cv::Mat(480, 640, CV_8U, cv::Scalar(2)), board, {block_at(-1.0)});
  CHECK_FALSE(dark[0].left.measured);
  CHECK(measure_evidence(cv::Mat(), board, {block_at(-1.0)})[0].left.measured == false);
}

TEST_CASE("the frame uncertainty grows with the rows' scatter, the blur, the noise and the pair residual, and shrinks with depth") {
  LineEvidence l;
  l.measured = true;
  l.scatter_px = 0.001;  // below the contrast prediction: that one counts, until the scatter is larger
  l.depth = 0.6;
  l.noise = 0.01;
  l.width_px = 2.0;
  l.rows_effective = 10;
  BlockEvidence base{l, l, 0.0, 1.5};
  const double u0 = frame_uncertainty(base, 60.0);
  CHECK(u0 > 0);
  auto with = [&](auto change) {
    BlockEvidence e = base;
    change(e);
    return frame_uncertainty(e, 60.0);
  };
  CHECK(with([](BlockEvidence& e) { e.left.scatter_px = e.right.scatter_px = 0.2; }) > u0);
  // Blur: wider lines than printed, both through the contrast prediction and the blur term.
  const double wide = with([](BlockEvidence& e) { e.left.width_px = e.right.width_px = 6.0; });
  CHECK(wide > u0 + UncertaintyModel{}.blur_factor * 4.0 / 60.0);
  CHECK(with([](BlockEvidence& e) { e.left.noise = e.right.noise = 0.03; }) > u0);
  CHECK(with([](BlockEvidence& e) { e.left.depth = e.right.depth = 0.2; }) > u0);
  CHECK(with([](BlockEvidence& e) { e.left.rows_effective = e.right.rows_effective = 3; }) > u0);
  // The pair residual adds half of itself (one line off by e moves the midpoint by e/2).
  const UncertaintyModel m;
  CHECK(with([](BlockEvidence& e) { e.pair_residual_px = 0.6; }) == Approx(u0 + m.pair_factor * 0.3 / 60.0));
  // In block lengths: the same pixels on a board seen twice as large are half the uncertainty.
  CHECK(frame_uncertainty(base, 120.0) == Approx(u0 / 2));
}

TEST_CASE("the temporal term is the spread times Student's t for 95%, none below 3 samples") {
  CHECK(temporal_uncertainty(0.001, 2) == 0.0);
  CHECK(temporal_uncertainty(0.0, 8) == 0.0);
  CHECK(temporal_uncertainty(0.001, 3) == Approx(4.303e-3));
  CHECK(temporal_uncertainty(0.001, 8) == Approx(2.365e-3));
  CHECK(temporal_uncertainty(0.001, 100) == Approx(1.984e-3).epsilon(0.01));
}

TEST_CASE("the calibration floor is the reprojection residual carried from projector pixels to board x") {
  calibration_t c = board::default_calibration();
  CHECK(calibration_floor(c, -1.0, 0.2) == 0.0);  // no residual measured
  // The default setup: 1.6 projector pixels per camera pixel, 60 camera pixels per block: 96 per block.
  c.reprojection_error_mean_px = 0.3;
  CHECK(calibration_floor(c, -1.0, 0.2) == Approx(0.3 / 96));
  CHECK(calibration_floor(c, 3.0, 1.5) == Approx(0.3 / 96));  // an affine mapping: the same everywhere
  // A projector twice as fine: each of its pixels is half as much board.
  for (int i = 0; i < 2; ++i) c.camera_to_projector[i * 4] = 3.2;
  CHECK(calibration_floor(c, -1.0, 0.2) == Approx(0.3 / 192));
  for (double& v : c.camera_to_projector) v = 0;
  CHECK_THROWS_WITH(calibration_floor(c, 0, 0), Catch::Contains("singular"));
}

TEST_CASE("the calibration floor adds the board x accuracy the scale step states, growing along and up the board") {
  calibration_t c = board::default_calibration();
  c.reprojection_error_mean_px = 0.3;
  const double residual = 0.3 / 96;
  c.board_x_accuracy[0] = 0.006;
  c.board_x_accuracy[1] = 0.004;
  c.board_x_accuracy[2] = 0.01;
  CHECK(calibration_floor(c, 0.0, 0.0) == Approx(residual + 0.006));
  CHECK(calibration_floor(c, -4.0, 0.2) == Approx(residual + 0.006 + 0.016 + 0.002));
  CHECK(calibration_floor(c, 4.5, 3.2) == Approx(residual + 0.006 + 0.018 + 0.032));
  // A calibration stating a worse accuracy gives a larger floor, hence a larger published half-width.
  calibration_t worse = c;
  worse.board_x_accuracy[1] = 0.008;
  CHECK(calibration_floor(worse, 4.5, 3.2) > calibration_floor(c, 4.5, 3.2) + 0.017);
  CHECK(published_uncertainty(0.004, 0.0, 0.0, calibration_floor(worse, 4.5, 3.2), 0.0) >
        published_uncertainty(0.004, 0.0, 0.0, calibration_floor(c, 4.5, 3.2), 0.0));
}

TEST_CASE("the published half-width is the measurement plus the lag, never below either floor") {
  CHECK(published_uncertainty(0.001, 0.0, 0.0, 0.0, 0.0) == 0.001);
  CHECK(published_uncertainty(0.001, 0.002, 0.0, 0.0, 0.0) == 0.002);   // the larger measurement
  CHECK(published_uncertainty(0.001, 0.002, 0.004, 0.0, 0.0) == Approx(0.006));
  CHECK(published_uncertainty(0.001, 0.0, 0.0, 0.003, 0.0) == 0.003);   // the calibration's residual
  CHECK(published_uncertainty(0.001, 0.0, 0.0, 0.003, 0.005) == 0.005); // the operator's setting
}

TEST_CASE("the sampling term bounds the detector's pixel-phase error of sharp and blurred lines, never below the JPEG floor") {
  // A block drawn at sixteen sub-pixel phases, sharp and blurred: the detector's x is off by where its lines
  // fell within their pixels (no noise: nothing else moves it), and the phase bound must cover that.
  const UncertaintyModel m;
  const BoardFrame board(kBoard);
  detection::Detector detector(kBoard);
  for (double sigma : {0.0, 0.5, 1.0, 1.5}) {
    double worst_error = 0, smallest_bound = 1;
    for (int k = 0; k < 16; ++k) {
      const double x = -1.0 + k / (16.0 * kBoard.block_length_px);
      const cv::Mat f = frame_with_block(x, 170, 0.8, sigma, 0.0);
      const auto d = detector.detect(f);
      REQUIRE(d.blocks.size() == 1);
      const auto e = measure_evidence(f, board, d.blocks);
      const double error_px = std::abs(d.blocks[0].x - x) * kBoard.block_length_px;
      worst_error = std::max(worst_error, error_px);
      smallest_bound = std::min(smallest_bound, e[0].phase_px);
      INFO("sigma " << sigma << " phase " << k << "/16: error " << error_px << " px, bound " << e[0].phase_px);
      CHECK(error_px <= std::max(m.sampling_px, e[0].phase_px) + 0.005);  // 8-bit rounding of the frame
      CHECK(e[0].phase_px < 0.2);  // hundredths of a pixel, not a line width
    }
    INFO("sigma " << sigma << ": worst error " << worst_error << " px, smallest bound " << smallest_bound);
    // The effect is real: sharp lines move with their phase by more than the JPEG floor alone would cover
    // (measured 0.027 px sharp, 0.031 px at sigma 0.5; 0.014 and 0.008 px blurred more; bounds 0.045-0.09 px).
    if (sigma <= 0.5) CHECK(worst_error > m.sampling_px + 0.005);
  }
  // The term enters once (both lines of a block may share their phase), in pixels of the block's length.
  LineEvidence l;
  l.measured = true;
  l.depth = 0.6;
  l.noise = 0.001;
  l.width_px = 1.5;
  l.rows_effective = 10;
  BlockEvidence e{l, l, 0.0, 1.5};
  e.frame_width_px = 1.5;
  const double floor_only = frame_uncertainty(e, 60.0);
  e.phase_px = m.sampling_px / 2;  // below the floor: no change
  CHECK(frame_uncertainty(e, 60.0) == Approx(floor_only));
  e.phase_px = 0.1;
  CHECK(frame_uncertainty(e, 60.0) == Approx(floor_only + (0.1 - m.sampling_px) / 60.0));
}
