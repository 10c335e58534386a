// An end line placed by fitting its profile (end_line_fit.h): exact profiles of a line at a block's end
// (bare glass outside, the block's face inside, blurred, each sample the mean over its pixel), with and
// without the game's light on the block, put the line's middle within 0.01 px (0.02 px under the light), where the dip's centroid (what
// the detector gives) is pulled inwards by the step; and what the fit refuses.
#include <catch2/catch.hpp>

#include <cmath>
#include <vector>

#include "bricklayer/detection/end_line_fit.h"

using namespace bricklayer;

namespace {

constexpr double kWidth = 1.5;  // the line, pixels (1/40 of a 60-pixel block)

double blurred_step(double x, double sigma) { return 0.5 * std::erfc(-x / (std::sqrt(2.0) * sigma)); }

// The camera's level along a row through a left end line whose middle is at `centre`: `outside` left of the
// block, `line` on it, `inside` on the block's face, and `light` more from the block's end on (the game's
// colour on the block), all blurred by sigma; each sample is the mean over its pixel (16 sub-samples).
std::vector<float> profile(double centre, double sigma, double outside, double line, double inside, double light = 0) {
  std::vector<float> out(40);
  const double end = centre - kWidth / 2;
  for (size_t i = 0; i < out.size(); ++i) {
    double sum = 0;
    for (int k = 0; k < 16; ++k) {
      const double x = static_cast<double>(i) - 0.5 + (k + 0.5) / 16;
      sum += outside + (line - outside) * blurred_step(x - end, sigma) + (inside - line) * blurred_step(x - end - kWidth, sigma) +
             light * blurred_step(x - end, sigma);
    }
    out[i] = static_cast<float>(sum / 16);
  }
  return out;
}

// The detector's way: the centroid of the darkness above 30% of the dip's depth, the background the brighter side.
double dip_centroid(const std::vector<float>& p, double guess) {
  double background = 0, darkest = 1e9;
  for (int i = static_cast<int>(guess) - 6; i <= static_cast<int>(guess) + 6; ++i)
    background = std::max(background, static_cast<double>(p[i])), darkest = std::min(darkest, static_cast<double>(p[i]));
  double sw = 0, sx = 0;
  for (int i = static_cast<int>(guess) - 6; i <= static_cast<int>(guess) + 6; ++i) {
    const double w = (background - p[i]) - 0.3 * (background - darkest);
    if (w > 0) sw += w, sx += w * i;
  }
  return sx / sw;
}

}  // namespace

TEST_CASE("an end line's middle is found within 0.01-0.02 px whatever the blur, the step beside it and the light on the block") {
  const double sigma = GENERATE(0.3, 0.6, 0.9, 1.3);
  const double centre = GENERATE(19.0, 19.37, 19.81);
  // Room light only: the face 0.94 of the glass. Under the game's light, the detector's own prediction of it
  // given (sharp, as the projector draws it): the face then reads brighter than the glass.
  const double light = GENERATE(0.0, 40.0);
  INFO("sigma " << sigma << ", centre " << centre << ", light " << light);
  const std::vector<float> seen = profile(centre, sigma, 170, 12, 160, light);
  std::vector<float> predicted;
  if (light > 0) {
    predicted.resize(seen.size());
    for (size_t i = 0; i < seen.size(); ++i) {
      // The prediction's own pixels: the light covers [end, ...), its share of each pixel.
      const double end = centre - kWidth / 2;
      predicted[i] = static_cast<float>(light * std::clamp(static_cast<double>(i) + 0.5 - end, 0.0, 1.0));
    }
  }
  const auto fit = detection::fit_end_line(seen, predicted, std::round(centre), kWidth, 6.0);
  REQUIRE(fit.has_value());
  // Under the light 0.02: the prediction is the light's share of each pixel, which the fit takes as a level
  // per pixel (measured up to 0.015 px off).
  CHECK(fit->centre == Approx(centre).margin(light > 0 ? 0.02 : 0.01));
  CHECK(fit->depth > 100);
  CHECK(fit->rms < 0.5);
  // The dip's centroid leans into the block, by more the blurrier (measured 0.03-0.2 px here): that is the
  // bias the fit removes (0.1 px on a 60-pixel block is 0.17% of its length, per end).
  if (sigma >= 0.9 && light == 0) CHECK(dip_centroid(seen, centre) - centre > 0.03);
}

TEST_CASE("the light is not read as part of the step only when its prediction is given") {
  const double centre = 19.37, sigma = 1.0, light = 40.0;
  const std::vector<float> seen = profile(centre, sigma, 170, 12, 160, light);
  std::vector<float> predicted(seen.size());
  for (size_t i = 0; i < seen.size(); ++i)
    predicted[i] = static_cast<float>(light * std::clamp(static_cast<double>(i) + 0.5 - (centre - kWidth / 2), 0.0, 1.0));
  // The detector subtracts the prediction sharp: a bright-dark pair at the block's end is left over.
  std::vector<float> subtracted(seen.size());
  for (size_t i = 0; i < seen.size(); ++i) subtracted[i] = seen[i] - predicted[i];
  const auto with = detection::fit_end_line(seen, predicted, 19.0, kWidth, 6.0);
  const auto sharp = detection::fit_end_line(subtracted, {}, 19.0, kWidth, 6.0);
  REQUIRE(with.has_value());
  REQUIRE(sharp.has_value());
  CHECK(std::abs(with->centre - centre) < 0.01);
  CHECK(std::abs(sharp->centre - centre) > 0.03);
}

TEST_CASE("the fit refuses a window off the profile, a flat profile, a bright line and a mismatched prediction") {
  const std::vector<float> seen = profile(19.4, 0.8, 170, 12, 160);
  CHECK_FALSE(detection::fit_end_line(seen, {}, 3.0, kWidth, 6.0).has_value());   // window starts before 0
  CHECK_FALSE(detection::fit_end_line(seen, {}, 37.0, kWidth, 6.0).has_value());  // and ends past the last sample
  CHECK_FALSE(detection::fit_end_line(seen, {}, 19.0, kWidth, 3.0).has_value());  // too few samples
  CHECK_FALSE(detection::fit_end_line(std::vector<float>(40, 150.0f), {}, 19.0, kWidth, 6.0).has_value());
  CHECK_FALSE(detection::fit_end_line(profile(19.4, 0.8, 100, 200, 100), {}, 19.0, kWidth, 6.0).has_value());
  CHECK_FALSE(detection::fit_end_line(seen, std::vector<float>(10, 0.0f), 19.0, kWidth, 6.0).has_value());
  CHECK_FALSE(detection::fit_end_line(seen, {}, std::nan(""), kWidth, 6.0).has_value());
}
