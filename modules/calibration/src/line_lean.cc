#include "bricklayer/calibration/line_lean.h"

#include <opencv2/imgproc.hpp>

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <stdexcept>

#include "bricklayer/board/mapping.h"

namespace bricklayer::calibration {
namespace {

// Bilinear grey level at a camera point; negative outside the frame.
double sample(const cv::Mat& grey, cv::Point2d p) {
  const int x0 = static_cast<int>(std::floor(p.x)), y0 = static_cast<int>(std::floor(p.y));
  if (x0 < 0 || y0 < 0 || x0 + 1 >= grey.cols || y0 + 1 >= grey.rows) return -1.0;
  const double fx = p.x - x0, fy = p.y - y0;
  const double a = grey.at<uchar>(y0, x0), b = grey.at<uchar>(y0, x0 + 1);
  const double c = grey.at<uchar>(y0 + 1, x0), d = grey.at<uchar>(y0 + 1, x0 + 1);
  return (a * (1 - fx) + b * fx) * (1 - fy) + (c * (1 - fx) + d * fx) * fy;
}

double median(std::vector<double> v) {
  if (v.empty()) return 0.0;
  const size_t mid = v.size() / 2;
  std::nth_element(v.begin(), v.begin() + mid, v.end());
  return v[mid];
}

}  // namespace

std::optional<double> measure_line_lean(const cv::Mat& grey, const calibration_t& calibration, double x, double y0,
                                        double y1) {
  if (grey.empty() || grey.type() != CV_8UC1 || !(y1 > y0)) return std::nullopt;
  const cv::Matx33d board_to_camera = board::camera_to_board_h(calibration).inv();
  auto camera_at = [&](double bx, double by) {
    return board::distort_point(calibration, board::apply_homography(board_to_camera, cv::Point2d(bx, by)));
  };
  // Profile half-width: the line (1/40) and its blur, clear of the neighbouring block's line (>= 0.1 away).
  constexpr double kHalf = 0.07, kStep = 0.0035;
  constexpr int kHeights = 11;
  const int n = static_cast<int>(std::lround(2 * kHalf / kStep)) + 1;
  std::vector<double> ys, xs;
  std::vector<double> profile(n);
  for (int j = 0; j < kHeights; ++j) {
    const double y = y0 + (y1 - y0) * (j + 0.5) / kHeights;
    bool inside = true;
    for (int i = 0; i < n && inside; ++i) {
      profile[i] = sample(grey, camera_at(x - kHalf + i * kStep, y));
      inside = profile[i] >= 0;
    }
    if (!inside) continue;
    // Background: the brighter ends of the profile; darkness below it weighs the centroid.
    const int edge = n / 6;
    std::vector<double> ends(profile.begin(), profile.begin() + edge);
    ends.insert(ends.end(), profile.end() - edge, profile.end());
    const double background = median(ends);
    const double darkest = *std::min_element(profile.begin(), profile.end());
    if (background - darkest < 8.0) continue;  // no line here (or too faint to place)
    double sw = 0, swx = 0;
    for (int i = 0; i < n; ++i) {
      const double w = std::max(0.0, background - profile[i] - 0.2 * (background - darkest));
      sw += w;
      swx += w * (x - kHalf + i * kStep);
    }
    if (sw <= 0) continue;
    ys.push_back(y);
    xs.push_back(swx / sw);
  }
  if (ys.size() < static_cast<size_t>(kHeights * 2 / 3)) return std::nullopt;
  // Least squares x = x0 + lean * y.
  double sy = 0, sx = 0, syy = 0, syx = 0;
  for (size_t k = 0; k < ys.size(); ++k) sy += ys[k], sx += xs[k], syy += ys[k] * ys[k], syx += ys[k] * xs[k];
  const double m = static_cast<double>(ys.size());
  const double den = m * syy - sy * sy;
  if (den <= 0) return std::nullopt;
  const double lean = (m * syx - sy * sx) / den;
  // A centroid far from the fitted line: two dips (a neighbour's line) or a shadow edge; not a clean line.
  const double x0 = (sx - lean * sy) / m;
  for (size_t k = 0; k < ys.size(); ++k)
    if (std::abs(xs[k] - (x0 + lean * ys[k])) > 0.01) return std::nullopt;
  return lean;
}

std::optional<FrameLean> fit_frame_lean(const std::vector<LineLean>& leans, double scale, double keystone, int min_lines,
                                        std::string* why, double min_span_for_keystone, double max_residual) {
  auto fail = [&](const std::string& text) -> std::optional<FrameLean> {
    if (why) *why = text;
    return std::nullopt;
  };
  if (static_cast<int>(leans.size()) < std::max(1, min_lines))
    return fail("measured the lean of " + std::to_string(leans.size()) + " end lines, need " + std::to_string(min_lines));
  double lo = 1e300, hi = -1e300;
  for (const LineLean& l : leans) lo = std::min(lo, l.x), hi = std::max(hi, l.x);
  const bool with_keystone = hi - lo >= min_span_for_keystone;
  // lean = p + q x; robust: fit, drop leans more than 4 median absolute deviations off, fit again.
  auto fit = [&](const std::vector<LineLean>& v, double& p, double& q) {
    double sx = 0, sl = 0, sxx = 0, sxl = 0;
    for (const LineLean& l : v) sx += l.x, sl += l.lean, sxx += l.x * l.x, sxl += l.x * l.lean;
    const double m = static_cast<double>(v.size());
    const double den = m * sxx - sx * sx;
    q = with_keystone && den > 1e-12 ? (m * sxl - sx * sl) / den : 0.0;
    p = (sl - q * sx) / m;
  };
  double p = 0, q = 0;
  fit(leans, p, q);
  std::vector<double> dev;
  for (const LineLean& l : leans) dev.push_back(std::abs(l.lean - (p + q * l.x)));
  const double mad = std::max(1e-4, median(dev));
  std::vector<LineLean> kept;
  for (const LineLean& l : leans)
    if (std::abs(l.lean - (p + q * l.x)) <= 4 * 1.4826 * mad) kept.push_back(l);
  if (static_cast<int>(kept.size()) < std::max(1, min_lines))
    return fail("the leans of the end lines disagree (" + std::to_string(kept.size()) + " of " + std::to_string(leans.size()) +
                " agree, need " + std::to_string(min_lines) + ")");
  fit(kept, p, q);
  FrameLean out;
  out.shear = -scale * p;
  out.vertical_keystone = q - p * keystone;
  out.lines = static_cast<int>(kept.size());
  out.outliers = static_cast<int>(leans.size() - kept.size());
  double ss = 0;
  for (const LineLean& l : kept) ss += std::pow(l.lean - (p + q * l.x), 2);
  out.residual = std::sqrt(ss / kept.size());
  if (out.residual > max_residual) {
    char text[160];
    std::snprintf(text, sizeof text, "the end lines' leans scatter by %.3f RMS about the fit (at most %.3f): shadows or blur on the lines?",
                  out.residual, max_residual);
    return fail(text);
  }
  return out;
}

std::optional<FrameLean> fit_shear(const std::vector<LineLean>& leans, double a, double g, double h, int min_lines,
                                   std::string* why, double max_residual) {
  auto fail = [&](const std::string& text) -> std::optional<FrameLean> {
    if (why) *why = text;
    return std::nullopt;
  };
  if (static_cast<int>(leans.size()) < std::max(1, min_lines))
    return fail("measured the lean of " + std::to_string(leans.size()) + " end lines, need " + std::to_string(min_lines));
  const auto shear_of = [&](const LineLean& l) { return a * (l.x * h - l.lean * (h * l.y + 1)) / (g * l.x + 1 - l.lean * g * l.y); };
  const auto lean_of = [&](const LineLean& l, double b) {
    const double n = a * l.x + b * l.y, d = g * l.x + h * l.y + 1;
    return (n * h - b * d) / (a * d - n * g);
  };
  std::vector<double> shears;
  for (const LineLean& l : leans) shears.push_back(shear_of(l));
  const double mid = median(shears);
  std::vector<double> dev;
  for (const LineLean& l : leans) dev.push_back(std::abs(l.lean - lean_of(l, mid)));
  const double mad = std::max(1e-4, median(dev));
  double sum = 0;
  std::vector<LineLean> kept;
  for (const LineLean& l : leans)
    if (std::abs(l.lean - lean_of(l, mid)) <= 4 * 1.4826 * mad) kept.push_back(l), sum += shear_of(l);
  if (static_cast<int>(kept.size()) < std::max(1, min_lines))
    return fail("the leans of the end lines disagree (" + std::to_string(kept.size()) + " of " + std::to_string(leans.size()) +
                " agree, need " + std::to_string(min_lines) + ")");
  FrameLean out;
  out.shear = sum / static_cast<double>(kept.size());
  out.vertical_keystone = h;
  out.lines = static_cast<int>(kept.size());
  out.outliers = static_cast<int>(leans.size() - kept.size());
  double ss = 0;
  for (const LineLean& l : kept) ss += std::pow(l.lean - lean_of(l, out.shear), 2);
  out.residual = std::sqrt(ss / static_cast<double>(kept.size()));
  if (out.residual > max_residual) {
    char text[160];
    std::snprintf(text, sizeof text, "the end lines' leans scatter by %.3f RMS about the fit (at most %.3f): shadows or blur on the lines?",
                  out.residual, max_residual);
    return fail(text);
  }
  return out;
}

calibration_t apply_frame_correction(const calibration_t& calibration, double a, double g, double b, double h) {
  if (!(a > 0.0) || !std::isfinite(a) || !std::isfinite(g) || !std::isfinite(b) || !std::isfinite(h))
    throw std::invalid_argument("apply_frame_correction: scale must be positive and finite, the other terms finite");
  const cv::Matx33d c(a, b, 0, 0, a, 0, g, h, 1);
  const cv::Matx33d m = c * board::camera_to_board_h(calibration);
  calibration_t out = calibration;
  for (int i = 0; i < 9; ++i) out.camera_to_board[i] = m(i / 3, i % 3);
  return out;
}

double frame_correction_change(double a, double g, double b, double h, double half_width, double height) {
  double worst = 0;
  for (double y = 0; y <= height + 1e-9; y += height / 10) {
    for (double x = -half_width; x <= half_width + 1e-9; x += half_width / 50) {
      const double xp = (a * x + b * y) / (g * x + h * y + 1.0);
      worst = std::max(worst, std::abs(xp - x));
    }
  }
  return worst;
}

}  // namespace bricklayer::calibration
