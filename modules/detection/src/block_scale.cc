#include "bricklayer/detection/block_scale.h"

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <stdexcept>

#include <opencv2/core/optim.hpp>

#include "bricklayer/detection/end_line_fit.h"

namespace bricklayer::detection {

namespace {

DetectorConfig widened(DetectorConfig config) {
  // Pairs of a mis-scaled board are up to kMaxScaleError of a length off; accept them (with margin).
  config.length_tolerance = std::max(config.length_tolerance, kMaxScaleError + 0.05);
  config.keep_profiles = true;  // the end lines are placed again by fitting their profiles (end_line_fit.h),
  config.keep_lines = true;     // in windows no other line of the row reaches into
  return config;
}

double corrected(double x, double y, double a, double c, double h) { return a * x / (c * x + h * y + 1.0); }
double corrected(double x, double a, double c) { return corrected(x, 0.0, a, c, 0.0); }

struct Fit {
  double a = 1.0, c = 0.0, h = 0.0, rss = 0.0;
};

double length(const EndLines& e, double a, double c, double h) {
  return corrected(e.right, e.y, a, c, h) - corrected(e.left, e.y, a, c, h);
}

// For a fixed keystone c (and h) every block gives a * d_i = target with d_i = u(right) - u(left),
// u = x / (c x + h y + 1): a is linear least squares; the residual is then minimised over c by
// golden-section search (it is smooth and, over the small range searched, unimodal), or over c and h by
// Nelder-Mead.
Fit fit_scale(const std::vector<EndLines>& m, double target, double c, double h = 0.0) {
  double sdd = 0, sd = 0;
  for (const EndLines& e : m) {
    const double d = length(e, 1.0, c, h);
    sdd += d * d, sd += d;
  }
  Fit f;
  f.c = c;
  f.h = h;
  f.a = sdd > 0 ? target * sd / sdd : 1.0;
  for (const EndLines& e : m) {
    const double r = length(e, f.a, c, h) / target - 1.0;
    f.rss += r * r;
  }
  return f;
}

class ScaleResidual : public cv::MinProblemSolver::Function {
 public:
  ScaleResidual(const std::vector<EndLines>& m, double target) : m_(m), target_(target) {}
  int getDims() const override { return 2; }
  double calc(const double* v) const override {
    // Outside the searched ranges the residual is made large so the simplex walks back. Scaled so the
    // solver's tolerance (on the value) is far below the relative lengths' squares.
    const double over = std::max(0.0, std::abs(v[0]) - kMaxKeystone) + std::max(0.0, std::abs(v[1]) - kMaxKeystone);
    return 1e8 * (fit_scale(m_, target_, std::clamp(v[0], -kMaxKeystone, kMaxKeystone), std::clamp(v[1], -kMaxKeystone, kMaxKeystone)).rss +
                  over);
  }

 private:
  const std::vector<EndLines>& m_;
  double target_;
};

double height_span(const std::vector<EndLines>& m) {
  double lo = 1e300, hi = -1e300;
  for (const EndLines& e : m) lo = std::min(lo, e.y), hi = std::max(hi, e.y);
  return m.empty() ? 0.0 : hi - lo;
}

Fit fit_along(const std::vector<EndLines>& m, double target);

Fit fit(const std::vector<EndLines>& m, double target, bool keystone) {
  if (!keystone) return fit_scale(m, target, 0.0);
  if (height_span(m) >= kMinHeightForVerticalKeystone) {
    // From c alone (below), then c and h together.
    const Fit along = fit_along(m, target);
    const cv::Ptr<ScaleResidual> residual = cv::makePtr<ScaleResidual>(m, target);
    const cv::Ptr<cv::DownhillSolver> solver = cv::DownhillSolver::create(
        residual, cv::Mat(cv::Matx12d(0.002, 0.002)), cv::TermCriteria(cv::TermCriteria::MAX_ITER + cv::TermCriteria::EPS, 500, 1e-9));
    cv::Mat v = (cv::Mat_<double>(1, 2) << along.c, 0.0);
    solver->minimize(v);
    solver->setInitStep(cv::Mat(cv::Matx12d(0.0005, 0.0005)));
    solver->minimize(v);
    const Fit both = fit_scale(m, target, std::clamp(v.at<double>(0), -kMaxKeystone, kMaxKeystone),
                               std::clamp(v.at<double>(1), -kMaxKeystone, kMaxKeystone));
    return both.rss <= along.rss ? both : along;
  }
  return fit_along(m, target);
}

// The keystone along the board alone (h = 0): golden-section search over c.
Fit fit_along(const std::vector<EndLines>& m, double target) {
  const double g = (std::sqrt(5.0) - 1) / 2;
  double lo = -kMaxKeystone, hi = kMaxKeystone;
  Fit p = fit_scale(m, target, hi - g * (hi - lo)), q = fit_scale(m, target, lo + g * (hi - lo));
  for (int i = 0; i < 60; ++i) {
    if (p.rss <= q.rss) {
      hi = q.c, q = p;
      p = fit_scale(m, target, hi - g * (hi - lo));
    } else {
      lo = p.c, p = q;
      q = fit_scale(m, target, lo + g * (hi - lo));
    }
  }
  return p.rss <= q.rss ? p : q;
}

double span(const std::vector<EndLines>& m) {
  double lo = 1e300, hi = -1e300;
  for (const EndLines& e : m) lo = std::min(lo, 0.5 * (e.left + e.right)), hi = std::max(hi, 0.5 * (e.left + e.right));
  return m.empty() ? 0.0 : hi - lo;
}

}  // namespace

double BoardCorrection::length_at(double x) const {
  // Inverse of x' = a x / (c x + 1) is x = x' / (a - c x'); a block from x' to x' + 1 read this long.
  const double xp = corrected(x, scale, keystone);
  return (xp + 1) / (scale - keystone * (xp + 1)) - xp / (scale - keystone * xp);
}

double BoardCorrection::max_change(double half_width) const {
  double worst = 0;
  for (double x = -half_width; x <= half_width; x += half_width / 50)
    worst = std::max(worst, std::abs(corrected(x, scale, keystone) - x));
  return worst;
}

std::optional<BoardCorrection> fit_board_correction(const std::vector<EndLines>& measured, double line_width,
                                                    int min_blocks, double max_residual, std::string* why) {
  auto fail = [&](const std::string& text) -> std::optional<BoardCorrection> {
    if (why) *why = text;
    return std::nullopt;
  };
  const std::string place = "stand 3 or more blocks on the bottom row, apart from each other, spread along it, whole in the camera's view";
  if (static_cast<int>(measured.size()) < std::max(1, min_blocks))
    return fail("measured " + std::to_string(measured.size()) + " blocks, need " + std::to_string(min_blocks) + ": " + place);
  const double target = 1.0 - line_width;
  // Fit; while the worst measurement is more than 3% off the fit (a mispaired line next to a touching pair),
  // drop it and fit again. One at a time: a gross outlier drags the first fit, so its neighbours may look
  // off until it is gone.
  std::vector<EndLines> m = measured;
  const auto error = [&](const Fit& f, const EndLines& e) { return std::abs(length(e, f.a, f.c, f.h) / target - 1.0); };
  Fit f = fit(m, target, span(m) >= kMinSpanForKeystone);
  while (!m.empty()) {
    const auto worst = std::max_element(m.begin(), m.end(), [&](const EndLines& x, const EndLines& y) { return error(f, x) < error(f, y); });
    if (error(f, *worst) <= 0.03 || 4 * (measured.size() - m.size() + 1) > measured.size()) break;
    m.erase(worst);
    f = fit(m, target, span(m) >= kMinSpanForKeystone);
  }
  const int outliers = static_cast<int>(measured.size() - m.size());
  if (static_cast<int>(m.size()) < std::max(1, min_blocks))
    return fail("measured " + std::to_string(m.size()) + " blocks that agree, need " + std::to_string(min_blocks) + ": " + place);

  BoardCorrection c;
  c.scale = f.a;
  c.keystone = f.c;
  c.vertical_keystone = f.h;
  c.blocks = static_cast<int>(m.size());
  c.outliers = outliers;
  c.residual = std::sqrt(f.rss / static_cast<double>(m.size()));
  char text[200];
  if (c.residual > max_residual) {
    std::snprintf(text, sizeof text, "block lengths disagree by %.1f%% RMS after the fit (at most %.1f%% allowed): ",
                  100 * c.residual, 100 * max_residual);
    return fail(text + place + "; is the camera steady?");
  }
  if (std::abs(1.0 / c.scale - 1.0) > kMaxScaleError) {
    std::snprintf(text, sizeof text, "blocks read %.3f block lengths long, beyond what can be measured (1 +- %.2f): ",
                  1.0 / c.scale, kMaxScaleError);
    return fail(std::string(text) + "check the calibration's --board geometry");
  }
  return c;
}

BlockScaleMeter::BlockScaleMeter(const calibration_t& calibration, DetectorConfig config, int max_row)
    : line_width_(config.line_width), max_row_(max_row), detector_(BoardGeometry{}, widened(config)) {
  if (!(line_width_ >= 0.0 && line_width_ < 0.5)) throw std::invalid_argument("line width must be in [0, 0.5) block lengths");
  if (max_row < 0) throw std::invalid_argument("max_row must be 0 or more");
  detector_.set_calibration(calibration);
}

int BlockScaleMeter::add(const cv::Mat& frame) {
  const Detection d = detector_.detect(frame);
  if (d.status != Detection::kOk) return 0;
  const BoardGeometry& g = detector_.frame().geometry();
  const double apart_px = kMinGap * g.block_length_px;
  const double line_px = line_width_ * g.block_length_px;
  int added = 0;
  for (int row = 0; row <= max_row_; ++row) {
    // Only blocks standing apart are measured: where two blocks touch (or nearly), their end lines merge
    // into one dip or two split ones whose centroids are not half a width inside each block. Judged from
    // the lines themselves, not from the pairing's guess of which lines are shared, since that guess
    // compares spacings with the scale being measured.
    std::vector<double> ends;
    for (const DetectedBlock& b : d.blocks)
      if (b.row == row && whole_in_view(b, frame.size())) ends.insert(ends.end(), {b.left_line_px, b.right_line_px});
    if (ends.empty()) continue;
    auto crowded = [&](double line) {
      // Its own line is at distance 0; a block's two lines are never this close to each other.
      return std::count_if(ends.begin(), ends.end(), [&](double e) { return std::abs(e - line) < apart_px; }) > 1;
    };
    // The row's profile, to place each end line by fitting it (end_line_fit.h) instead of by its dip's
    // centroid, which blur pulls inwards. The window reaches 0.1 block lengths either side, less where
    // another line of the row is closer (it must not enter the window).
    const Detection::Profile* profile = nullptr;
    for (const Detection::Profile& p : d.profiles)
      if (p.row == row) profile = &p;
    auto refit = [&](double line) -> std::optional<double> {
      if (!profile) return std::nullopt;
      double nearest = 0.1 * g.block_length_px + 3.0;
      for (const Detection::Line& other : d.line_list)
        if (other.row == row && other.x_px != line) nearest = std::min(nearest, std::abs(other.x_px - line));
      const auto fit = fit_end_line(profile->level, profile->leakage, line, line_px, std::max(4.0, nearest - 3.0));
      return fit ? std::optional<double>(fit->centre) : std::nullopt;
    };
    // The band's middle: its margins are alike at the top and the bottom.
    const double y = (row + 0.5) * g.block_height_px / g.block_length_px;
    for (const DetectedBlock& b : d.blocks) {
      // A block not whole in view was paired from a line the camera saw and one it only guessed.
      if (b.row != row || !whole_in_view(b, frame.size()) || !(b.right_line_px > b.left_line_px) || crowded(b.left_line_px) ||
          crowded(b.right_line_px))
        continue;
      const auto left = refit(b.left_line_px), right = refit(b.right_line_px);
      if (!left || !right) {
        ++unfitted_;
        continue;
      }
      measured_.push_back({(*left - g.edge_x_px) / g.block_length_px, (*right - g.edge_x_px) / g.block_length_px, y, row});
      ++added;
    }
  }
  return added;
}

calibration_t apply_board_correction(const calibration_t& calibration, const BoardCorrection& correction) {
  const double a = correction.scale, c = correction.keystone, v = correction.vertical_keystone;
  if (!(a > 0.0) || !std::isfinite(a) || !std::isfinite(c) || !std::isfinite(v))
    throw std::invalid_argument("apply_board_correction: scale must be positive and finite, keystones finite");
  const double* h = calibration.camera_to_board;
  calibration_t out = calibration;
  // Board (X, Y, W) = H * camera; C = [a 0 0; 0 a 0; c v 1] gives x' = a X / (c X + v Y + W) = a x / (c x + v y + 1).
  for (int j = 0; j < 3; ++j) {
    out.camera_to_board[j] = a * h[j];
    out.camera_to_board[3 + j] = a * h[3 + j];
    out.camera_to_board[6 + j] = c * h[j] + v * h[3 + j] + h[6 + j];
  }
  return out;
}

}  // namespace bricklayer::detection
