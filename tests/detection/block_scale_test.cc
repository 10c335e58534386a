// Board scale from blocks (block_scale.h): a calibration whose board frame reads blocks k long, with or
// without keystone along the board (what a projector mounted bigger, smaller or askew gives
// bricklayer-calibrate), is measured from bottom-row blocks standing apart in simcam frames, and the
// corrected calibration places every block where simcam drew it.
#include <catch2/catch.hpp>

#include <cmath>
#include <string>

#include "bricklayer/simcam/render.h"
#include "bricklayer/detection/block_scale.h"
#include "bricklayer/detection/detector.h"
#include "evaluate.h"

using namespace bricklayer;

namespace {

// The calibration bricklayer-calibrate gives when its board frame is off: board x' = k x / (q x + 1) (and
// y alike), i.e. a block at the edge reads k long and the reading changes along the board with q.
calibration_t misscaled(const calibration_t& truth, double k, double q = 0.0) {
  detection::BoardCorrection wrong;
  wrong.scale = k;
  wrong.keystone = q;
  return detection::apply_board_correction(truth, wrong);
}

// Blocks standing apart along the bottom row (from 3.6 left of the edge to 1.1 right of it), one touching
// pair, and a block on top (neither of the last two kinds may be measured: shared lines and upper rows),
// shifted per frame as a player nudges them.
core::Stack scene(int frame) {
  const double d = 0.013 * frame;
  core::Stack s;
  s.blocks = {{1, 0, -3.6 + d}, {2, 0, -2.2 + d}, {3, 0, -0.9 - d}, {4, 0, 0.15 + d},
              {5, 0, 1.6 + d},  {6, 0, 2.6 + d},  {7, 1, -3.3 - d}};
  return s;
}

double max_x_error(const std::vector<simcam::TrueBlock>& truth, const std::vector<detection::DetectedBlock>& found) {
  double worst = 0;
  for (const auto& t : truth) {
    if (!t.visible) continue;
    double best = 1e9;
    for (const auto& f : found)
      if (f.row == t.row) best = std::min(best, std::abs(f.x - t.x));
    worst = std::max(worst, best);
  }
  return worst;
}

}  // namespace

TEST_CASE("a mis-scaled board is measured from bottom-row blocks standing apart, and the corrected calibration places blocks right") {
  const auto [k, q] = GENERATE(table<double, double>({{0.80, 0.0}, {0.9, 0.0}, {0.97, 0.0}, {1.0, 0.0}, {1.06, 0.0},
                                                      {1.12, 0.0}, {1.2, 0.0}, {0.9, 0.02}, {1.1, -0.03}, {1.0, 0.015}}));
  const uint64_t setup = GENERATE(3, 8);
  const int level = GENERATE(1, 3);
  const simcam::CameraSetup camera = simcam::CameraSetup::random(setup);
  const simcam::ProjectorSetup projector = simcam::ProjectorSetup::random(setup);
  simcam::Renderer renderer(camera, projector);
  const calibration_t truth = detection::eval::true_calibration(camera, projector);
  const calibration_t wrong = misscaled(truth, k, q);
  INFO("k " << k << ", q " << q << ", setup " << setup << ", nuisance level " << level);

  detection::BlockScaleMeter meter(wrong);
  std::vector<simcam::Rendered> frames;
  int measured = 0;
  for (int f = 0; f < 10; ++f) {
    frames.push_back(renderer.render(scene(f), simcam::Nuisance::level(level), nullptr, 40 + static_cast<uint64_t>(f)));
    measured += meter.add(frames.back().bgr);
  }
  std::string why;
  const auto fit = meter.result(20, 0.01, &why);
  INFO(why);
  REQUIRE(fit.has_value());
  CHECK(measured >= 30);  // 4 blocks standing apart per frame, nearly all of them
  CHECK(fit->blocks + fit->outliers == measured);
  // A block from the edge to 1 reads k / (q + 1) long: the fitted correction says so. Blur pulls the end lines' centroids
  // inward (lengths up to 0.25% short at the mild level, 0.5% at the harsh one), and the keystone fitted
  // to that bias's own variation along the board adds a little.
  CHECK(fit->length_at(0.0) == Approx(k / (q + 1)).epsilon(level >= 3 ? 0.008 : 0.005));

  // Before: x reads wrong (or blocks go unseen); after: every block, including the touching pair and the
  // top block that were not measured, up to 3.7 lengths from the edge, within 0.02 (mild) or 0.025 (harsh).
  // Measured: worst 0.016 / 0.021, typically 0.009 / 0.016; the detector alone reaches 0.01 / 0.02.
  detection::Detector before, after;
  before.set_calibration(wrong);
  after.set_calibration(detection::apply_board_correction(wrong, *fit));
  for (const auto& frame : frames) {
    const auto found = after.detect(frame.bgr).blocks;
    for (const auto& t : frame.truth) {
      if (!t.visible) continue;
      double best = 1e9;
      for (const auto& b : found)
        if (b.row == t.row) best = std::min(best, std::abs(b.x - t.x));
      INFO("block at " << t.x << " row " << t.row);
      CHECK(best <= (level >= 3 ? 0.025 : 0.02));
    }
    if (std::abs(k - 1) > 0.05) CHECK(max_x_error(frame.truth, before.detect(frame.bgr).blocks) > 0.05);
  }
}

TEST_CASE("with the game's red and blue light on the blocks, the projector image given, the board is measured alike") {
  const simcam::CameraSetup camera = simcam::CameraSetup::random(5);
  const simcam::ProjectorSetup projector = simcam::ProjectorSetup::random(5);
  simcam::Renderer renderer(camera, projector);
  const calibration_t wrong = misscaled(detection::eval::true_calibration(camera, projector), 0.9, 0.01);
  detection::BlockScaleMeter meter(wrong);
  int measured = 0;
  for (int f = 0; f < 10; ++f) {
    const core::Stack s = scene(f);
    const cv::Mat light = detection::eval::red_blue_projection(s, camera, projector);
    meter.set_projector_image(light, projector.size);
    measured += meter.add(renderer.render(s, simcam::Nuisance::level(2), &light, 70 + static_cast<uint64_t>(f)).bgr);
  }
  std::string why;
  const auto fit = meter.result(20, 0.01, &why);
  INFO(why);
  REQUIRE(fit.has_value());
  CHECK(measured >= 30);
  CHECK(fit->length_at(0.0) == Approx(0.9 / 1.01).epsilon(0.005));
  CHECK(fit->keystone == Approx(-0.01 / 0.9).margin(0.003));
}

TEST_CASE("on blurred frames, with and without the game's light, block lengths are measured without the blur's bias") {
  // Harsh nuisance (blur 1.2 camera px, JPEG 80), the true calibration, three mountings. The end lines' dip
  // centroids read blocks 0.05-0.2% short in room light and 0.3-0.6% short under the game's red and blue
  // light (the step beside each line and the light's edge at each end pull them inwards); the fitted lines
  // read them within +-0.13% and +0.27% (end_line_fit.h).
  double sum = 0;
  int runs = 0;
  for (const uint64_t setup : {1, 3, 4}) {
    for (const bool light : {false, true}) {
      const simcam::CameraSetup camera = simcam::CameraSetup::random(setup);
      const simcam::ProjectorSetup projector = simcam::ProjectorSetup::random(setup);
      simcam::Renderer renderer(camera, projector);
      detection::BlockScaleMeter meter(detection::eval::true_calibration(camera, projector));
      for (int f = 0; f < 8; ++f) {
        const core::Stack s = scene(f);
        cv::Mat shown;
        if (light) {
          shown = detection::eval::red_blue_projection(s, camera, projector);
          meter.set_projector_image(shown, projector.size);
        }
        meter.add(renderer.render(s, simcam::Nuisance::level(3), light ? &shown : nullptr, 90 + static_cast<uint64_t>(f)).bgr);
      }
      REQUIRE(meter.measured().size() >= 24);
      double total = 0;
      for (const detection::EndLines& e : meter.measured()) total += e.right - e.left;
      const double bias = total / static_cast<double>(meter.measured().size()) / (1.0 - 1.0 / 40) - 1.0;
      INFO("setup " << setup << (light ? ", the game's light" : ", room light") << ": lengths read " << 100 * bias << "% off");
      CHECK(std::abs(bias) < 0.003);
      sum += bias;
      ++runs;
    }
  }
  INFO("mean " << 100 * sum / runs << "%");
  CHECK(std::abs(sum / runs) < 0.0015);
}

TEST_CASE("the fit recovers scale and keystone from exact end lines, drops mispaired ones, and refuses too few or disagreeing blocks") {
  const double w = 1.0 / 40;
  detection::BoardCorrection truth;  // the correction that makes these board readings right
  truth.scale = 1.08;
  truth.keystone = -0.02;
  // Board readings x of true positions X: X = a x / (c x + 1)  =>  x = X / (a - c X).
  auto reading = [&](double X) { return X / (truth.scale - truth.keystone * X); };
  std::vector<detection::EndLines> m;
  for (double X : {-3.7, -2.4, -1.1, 0.3, 1.5}) m.push_back({reading(X + w / 2), reading(X + 1 - w / 2)});
  std::string why;
  auto fit = detection::fit_board_correction(m, w, 5, 0.01, &why);
  REQUIRE(fit.has_value());
  CHECK(fit->scale == Approx(truth.scale).epsilon(1e-6));
  CHECK(fit->keystone == Approx(truth.keystone).margin(1e-6));
  CHECK(fit->residual < 1e-6);
  CHECK(fit->length_at(reading(0.3)) == Approx(reading(1.3) - reading(0.3)).epsilon(1e-6));

  m.push_back({reading(-1.8), reading(-1.8) + 0.8});  // a mispaired measurement 20% short
  fit = detection::fit_board_correction(m, w, 5, 0.01, &why);
  REQUIRE(fit.has_value());
  CHECK(fit->outliers == 1);
  CHECK(fit->scale == Approx(truth.scale).epsilon(1e-6));

  // Blocks close together: no keystone is fitted from less than kMinSpanForKeystone.
  truth.keystone = 0;
  const std::vector<detection::EndLines> close = {{reading(0.0125), reading(0.9875)}, {reading(1.2125), reading(2.1875)}};
  fit = detection::fit_board_correction(close, w, 2, 0.01, &why);
  REQUIRE(fit.has_value());
  CHECK(fit->keystone == 0.0);
  CHECK(fit->scale == Approx(truth.scale).epsilon(1e-6));

  CHECK_FALSE(detection::fit_board_correction({m[0], m[1]}, w, 5, 0.01, &why).has_value());
  CHECK(why.find("need 5") != std::string::npos);
  std::vector<detection::EndLines> noisy;
  for (int i = 0; i < 10; ++i) noisy.push_back({-3.0 + 0.6 * i, -3.0 + 0.6 * i + (i % 2 ? 0.96 : 1.0)});
  CHECK_FALSE(detection::fit_board_correction(noisy, w, 5, 0.01, &why).has_value());
  CHECK(why.find("disagree") != std::string::npos);
}

TEST_CASE("no blocks, only touching blocks, or blocks only in upper rows measure nothing, with a message saying what to do") {
  simcam::Renderer renderer;
  const calibration_t truth = detection::eval::true_calibration(renderer.camera(), renderer.projector());
  core::Stack touching, upper;
  touching.blocks = {{1, 0, -3.0}, {2, 0, -2.0}, {3, 0, -1.0}, {4, 0, 0.0}, {5, 1, -2.5}};
  upper.blocks = {{1, 1, -3.0}, {2, 1, -1.5}, {3, 2, -2.5}, {4, 2, 0.2}};
  for (const core::Stack& s : {core::Stack{}, touching, upper}) {
    detection::BlockScaleMeter meter(truth);
    for (uint64_t f = 0; f < 5; ++f) meter.add(renderer.render(s, simcam::Nuisance::level(1), nullptr, f).bgr);
    std::string why;
    CHECK_FALSE(meter.result(10, 0.01, &why).has_value());
    CHECK(why.find("stand 3 or more blocks on the bottom row, apart from each other") != std::string::npos);
  }
  detection::BlockScaleMeter meter(truth);
  CHECK(meter.add(cv::Mat()) == 0);
  CHECK(meter.add(cv::Mat(480, 640, CV_8UC3, cv::Scalar::all(0))) == 0);
}

TEST_CASE("apply_board_correction maps board coordinates by x' = a x / (c x + 1), y' = a y / (c x + 1), and refuses nonsense") {
  simcam::Renderer renderer;
  const calibration_t c = detection::eval::true_calibration(renderer.camera(), renderer.projector());
  detection::BoardCorrection k;
  k.scale = 1.25;
  k.keystone = 0.03;
  const calibration_t r = detection::apply_board_correction(c, k);
  auto board = [](const calibration_t& cal, double u, double v) {
    const double* h = cal.camera_to_board;
    const double w = h[6] * u + h[7] * v + h[8];
    return std::pair<double, double>((h[0] * u + h[1] * v + h[2]) / w, (h[3] * u + h[4] * v + h[5]) / w);
  };
  for (double u : {10.0, 320.0, 600.0}) {
    for (double v : {20.0, 240.0, 470.0}) {
      const auto [x0, y0] = board(c, u, v);
      const auto [x1, y1] = board(r, u, v);
      CHECK(x1 == Approx(1.25 * x0 / (0.03 * x0 + 1)).margin(1e-12));
      CHECK(y1 == Approx(1.25 * y0 / (0.03 * x0 + 1)).margin(1e-12));
    }
  }
  for (int i = 0; i < 9; ++i) CHECK(r.camera_to_projector[i] == c.camera_to_projector[i]);
  k.scale = 0.0;
  CHECK_THROWS_AS(detection::apply_board_correction(c, k), std::invalid_argument);
  k.scale = 1.0;
  k.keystone = std::nan("");
  CHECK_THROWS_AS(detection::apply_board_correction(c, k), std::invalid_argument);
}
