#include "bricklayer/vision/position_uncertainty.h"

#include <algorithm>
#include <cmath>
#include <limits>
#include <stdexcept>

#include <opencv2/imgproc.hpp>

namespace bricklayer::vision {

using detection::BoardFrame;
using detection::DetectedBlock;

namespace {

// The detector's band: the block's row minus this fraction of the block height at top and bottom (the
// detector's DetectorConfig::band_margin default), where the end lines run clear of the block outlines.
constexpr double kBandMargin = 0.2;
// Half-width of the window read around a line, as a fraction of a block length: the detector's background
// max-filter radius (0.09) plus a pixel, so the window's ends are the background the detector compared with.
constexpr double kWindowFraction = 0.1;
// Per-row centroids weigh the dip above this fraction of its depth (the detector's centroid floor).
constexpr double kCentroidFloor = 0.3;
// The detector's end-line width (DetectorConfig::line_width), used when a frame has too few lone pairs.
constexpr double kDefaultLineWidth = 1.0 / 40.0;

// Bilinear sample of an 8-bit image; NaN outside [0, size - 1].
double sample(const cv::Mat& img, cv::Point2d p) {
  if (!(p.x >= 0 && p.y >= 0 && p.x <= img.cols - 1 && p.y <= img.rows - 1)) return std::nan("");
  const int x0 = static_cast<int>(p.x), y0 = static_cast<int>(p.y);
  const int x1 = std::min(x0 + 1, img.cols - 1), y1 = std::min(y0 + 1, img.rows - 1);
  const double fx = p.x - x0, fy = p.y - y0;
  const uint8_t* r0 = img.ptr<uint8_t>(y0);
  const uint8_t* r1 = img.ptr<uint8_t>(y1);
  return (1 - fy) * ((1 - fx) * r0[x0] + fx * r0[x1]) + fy * ((1 - fx) * r1[x0] + fx * r1[x1]);
}

// Lag-1 correlation of a sequence (rows), clamped to [0, 0.95].
double lag1_correlation(const std::vector<double>& v) {
  if (v.size() < 3) return 0.0;
  double mean = 0;
  for (double x : v) mean += x;
  mean /= static_cast<double>(v.size());
  double num = 0, den = 0;
  for (size_t i = 0; i < v.size(); ++i) {
    den += (v[i] - mean) * (v[i] - mean);
    if (i + 1 < v.size()) num += (v[i] - mean) * (v[i + 1] - mean);
  }
  if (!(den > 0)) return 0.0;
  return std::clamp(num / den, 0.0, 0.95);
}

// Effective number of independent samples among n correlated as AR(1) with lag-1 correlation rho.
double effective(double n, double rho) { return std::max(1.0, n * (1 - rho) / (1 + rho)); }

LineEvidence read_line(const cv::Mat& green, const BoardFrame& board, int row, double centre_px) {
  LineEvidence e;
  const BoardGeometry& g = board.geometry();
  const double h = g.block_height_px;
  const double top = g.surface_y_px - (row + 1) * h, bottom = g.surface_y_px - row * h;
  const int y0 = static_cast<int>(std::ceil(top + kBandMargin * h));
  const int y2 = static_cast<int>(std::floor(bottom - kBandMargin * h));
  const int radius = std::max(4, static_cast<int>(std::lround(kWindowFraction * g.block_length_px)));
  const int c = static_cast<int>(std::lround(centre_px));
  const int n = 2 * radius + 1, rows = y2 - y0;
  if (rows < 3 || !std::isfinite(centre_px)) return e;
  // Profiles: rows x columns of the rectified frame around the line.
  std::vector<double> p(static_cast<size_t>(rows * n));
  if (board.identity()) {
    // Rectified pixels are camera pixels: read them directly (most of the cost otherwise).
    if (c - radius < 0 || c + radius >= green.cols || y0 < 0 || y0 + rows > green.rows) return e;
    for (int r = 0; r < rows; ++r) {
      const uint8_t* row_px = green.ptr<uint8_t>(y0 + r) + (c - radius);
      for (int k = 0; k < n; ++k) p[static_cast<size_t>(r * n + k)] = row_px[k];
    }
  } else {
    for (int r = 0; r < rows; ++r) {
      for (int k = 0; k < n; ++k) {
        const double v = sample(green, board.to_camera({static_cast<double>(c - radius + k), static_cast<double>(y0 + r)}));
        if (!std::isfinite(v)) return e;
        p[static_cast<size_t>(r * n + k)] = v;
      }
    }
  }
  // Band-averaged profile and its background: a straight line through the two outermost samples on each side
  // (light gradients and shadow edges across the window are mostly linear over a tenth of a block).
  std::vector<double> mean(n, 0.0);
  for (int r = 0; r < rows; ++r)
    for (int k = 0; k < n; ++k) mean[k] += p[static_cast<size_t>(r * n + k)] / rows;
  const double b_left = 0.5 * (mean[0] + mean[1]), b_right = 0.5 * (mean[n - 1] + mean[n - 2]);
  auto background = [&](int k) { return b_left + (b_right - b_left) * (k - 0.5) / (n - 2.0); };
  if (!(std::min(b_left, b_right) > 4.0)) return e;  // no light: no contrast to read (the detector's dark floor)
  std::vector<double> depth(n);
  int peak = 0;
  for (int k = 0; k < n; ++k) {
    depth[k] = 1.0 - mean[k] / background(k);
    if (depth[k] > depth[peak]) peak = k;
  }
  const double d = depth[peak];
  if (!(d > 0.02)) return e;
  // Width at half depth, crossings interpolated.
  const double half = 0.5 * d;
  int l = peak, rr = peak;
  while (l > 0 && depth[l - 1] >= half) --l;
  while (rr < n - 1 && depth[rr + 1] >= half) ++rr;
  double left_edge = l, right_edge = rr;
  if (l > 0) left_edge = l - (depth[l] - half) / std::max(1e-9, depth[l] - depth[l - 1]);
  if (rr < n - 1) right_edge = rr + (depth[rr] - half) / std::max(1e-9, depth[rr] - depth[rr + 1]);

  // Noise: the background samples (two outermost columns each side) relative to their column's mean, row by row.
  std::vector<double> resid_rows;  // per row, mean of the four relative residuals (for the rows' correlation)
  double ss = 0;
  int count = 0;
  const int edge_cols[4] = {0, 1, n - 2, n - 1};
  for (int r = 0; r < rows; ++r) {
    double row_sum = 0;
    for (int k : edge_cols) {
      const double rel = p[static_cast<size_t>(r * n + k)] / mean[k] - 1.0;
      ss += rel * rel;
      row_sum += rel;
      ++count;
    }
    resid_rows.push_back(row_sum / 4);
  }
  const double noise = std::sqrt(ss / std::max(1, count - 4));
  const double rho = lag1_correlation(resid_rows);

  // Per-row centroids of the dip (each row against the band's background), then their straight fit: a line
  // leaning in the rectified frame (calibration slightly off) does not count as scatter.
  std::vector<double> ys, cs;
  for (int r = 0; r < rows; ++r) {
    double sw = 0, sx = 0;
    for (int k = 0; k < n; ++k) {
      const double w = (1.0 - p[static_cast<size_t>(r * n + k)] / background(k)) - kCentroidFloor * d;
      if (w > 0) sw += w, sx += w * k;
    }
    if (sw > 0) ys.push_back(r), cs.push_back(sx / sw);
  }
  if (ys.size() < 3) return e;
  double my = 0, mc = 0;
  for (size_t i = 0; i < ys.size(); ++i) my += ys[i], mc += cs[i];
  my /= static_cast<double>(ys.size());
  mc /= static_cast<double>(ys.size());
  double syy = 0, syc = 0;
  for (size_t i = 0; i < ys.size(); ++i) syy += (ys[i] - my) * (ys[i] - my), syc += (ys[i] - my) * (cs[i] - mc);
  const double slope = syy > 0 ? syc / syy : 0.0;
  std::vector<double> fit_resid;
  double rss = 0;
  for (size_t i = 0; i < ys.size(); ++i) {
    const double res = cs[i] - (mc + slope * (ys[i] - my));
    fit_resid.push_back(res);
    rss += res * res;
  }
  const double m = static_cast<double>(ys.size());
  // Neighbouring rows share noise through the blur and JPEG's 8x8 blocks: the larger of the two correlations
  // (the fit's own residuals, the background's) discounts the rows to independent ones.
  const double rho_fit = std::max(rho, lag1_correlation(fit_resid));
  e.rows_effective = effective(m, rho_fit);
  e.scatter_px = std::sqrt(rss / (m - 2)) / std::sqrt(e.rows_effective);
  e.depth = d;
  e.noise = noise;
  e.width_px = right_edge - left_edge;
  e.measured = true;
  return e;
}

// The detector's centroid rule (above 30% of the peak, weighed by depth minus that floor) is not exact on a
// sampled line: how far it lands from the line's true centre depends on where the line falls within its
// pixels. For a line of printed width `print_px` blurred to `width_px` at half depth (Gaussian blur, each
// pixel integrating its area as a sensor does), the largest such error over the sub-pixel phases, and over
// blurs a little either side of the one the width implies (the error swings with the blur, and the width is
// measured on sampled dips). `resampled`: the detector reads a rectified frame interpolated (bilinear) from
// the camera's pixels at another phase, which moves the thresholded centroid again. Sharp lines are the worst
// (3 px lines at 1280x720: an eighth of a pixel); a blur of a pixel or more smooths it away. The same in every
// row and every frame of a still block, so neither the scatter nor the temporal spread sees it.
double phase_bias(double print_px, double width_px, bool resampled) {
  const double p = std::clamp(print_px, 0.5, 40.0);
  const double sigma0 = std::sqrt(std::max(0.0, width_px * width_px - p * p)) / 2.355;
  constexpr int kPhases = 16, kSub = 16;
  const int resample_phases = resampled ? 8 : 1;
  double worst = 0;
  auto centroid_error = [&](const std::vector<double>& d, int half, double centre) {
    const double peak = *std::max_element(d.begin(), d.end());
    double sw = 0, sx = 0;
    for (int k = -half; k <= half; ++k) {
      const double w = d[static_cast<size_t>(k + half)] - kCentroidFloor * peak;
      if (w > 0) sw += w, sx += w * k;
    }
    if (sw > 0) worst = std::max(worst, std::abs(sx / sw - centre));
  };
  for (double f : {0.6, 0.8, 1.0, 1.2}) {
    const double sigma = f * sigma0;
    const int half = static_cast<int>(std::ceil(0.5 * p + 3 * sigma)) + 2;
    std::vector<double> d(static_cast<size_t>(2 * half + 1)), r(d.size());
    for (int ph = 0; ph < kPhases; ++ph) {
      const double c = static_cast<double>(ph) / kPhases;
      for (int k = -half; k <= half; ++k) {
        double sum = 0;
        for (int j = 0; j < kSub; ++j) {
          const double x = k - 0.5 + (j + 0.5) / kSub - c;
          sum += sigma > 1e-3 ? 0.5 * (std::erf((x + 0.5 * p) / (sigma * M_SQRT2)) - std::erf((x - 0.5 * p) / (sigma * M_SQRT2)))
                              : (std::abs(x) < 0.5 * p ? 1.0 : 0.0);
        }
        d[static_cast<size_t>(k + half)] = sum / kSub;
      }
      for (int q = 0; q < resample_phases; ++q) {
        if (q == 0) {
          centroid_error(d, half, c);
          continue;
        }
        // Rectified pixel k read at camera position k + g.
        const double g = static_cast<double>(q) / resample_phases;
        for (size_t k = 0; k < d.size(); ++k) r[k] = (1 - g) * d[k] + g * (k + 1 < d.size() ? d[k + 1] : 0.0);
        centroid_error(r, half, c - g);
      }
    }
  }
  return worst;
}

double student_t95(int dof) {
  // Two-sided 95% quantiles of Student's t.
  static const double t[] = {0, 12.71, 4.303, 3.182, 2.776, 2.571, 2.447, 2.365, 2.306, 2.262, 2.228,
                             2.201, 2.179, 2.160, 2.145, 2.131, 2.120};
  if (dof < 1) return 0;
  if (dof < static_cast<int>(std::size(t))) return t[dof];
  return 1.96 + 2.4 / dof;  // within 0.01 of the table beyond 16
}

}  // namespace

std::vector<BlockEvidence> measure_evidence(const cv::Mat& frame, const BoardFrame& board,
                                            const std::vector<DetectedBlock>& blocks) {
  std::vector<BlockEvidence> out(blocks.size());
  if (frame.empty() || frame.depth() != CV_8U || (frame.channels() != 1 && frame.channels() != 3)) return out;
  cv::Mat green;
  if (frame.channels() == 3)
    cv::extractChannel(frame, green, 1);
  else
    green = frame;
  const double length = board.geometry().block_length_px;
  // A line ending one block and starting the next (touching blocks whose lines merged) is the same centroid in
  // both: the detector then expects the pair one full line width longer on that side.
  auto shared_left = [&](size_t i) {
    for (size_t j = 0; j < blocks.size(); ++j)
      if (j != i && blocks[j].row == blocks[i].row && blocks[j].right_line_px == blocks[i].left_line_px) return true;
    return false;
  };
  auto shared_right = [&](size_t i) {
    for (size_t j = 0; j < blocks.size(); ++j)
      if (j != i && blocks[j].row == blocks[i].row && blocks[j].left_line_px == blocks[i].right_line_px) return true;
    return false;
  };
  // The line width as this frame shows it, as the detector measures it: the median shortfall of lone pairs.
  std::vector<double> shortfall;
  std::vector<int> kinds(blocks.size());
  for (size_t i = 0; i < blocks.size(); ++i) {
    kinds[i] = shared_left(i) + shared_right(i);
    if (kinds[i] == 0) shortfall.push_back(length - (blocks[i].right_line_px - blocks[i].left_line_px));
  }
  double line_width = kDefaultLineWidth * length;
  if (shortfall.size() >= 3) {
    std::nth_element(shortfall.begin(), shortfall.begin() + static_cast<std::ptrdiff_t>(shortfall.size() / 2), shortfall.end());
    line_width = std::clamp(shortfall[shortfall.size() / 2], 0.0, 0.15 * length);
  }
  // The nearest other line of the row: touching blocks' lines merge into one dip or overlap when blurred.
  auto neighbour = [&](size_t i, double line) {
    double d = std::numeric_limits<double>::infinity();
    for (size_t j = 0; j < blocks.size(); ++j) {
      if (j == i || blocks[j].row != blocks[i].row) continue;
      for (double other : {blocks[j].left_line_px, blocks[j].right_line_px})
        if (other != line) d = std::min(d, std::abs(other - line));
    }
    return d;
  };
  std::vector<double> widths;
  for (size_t i = 0; i < blocks.size(); ++i) {
    const DetectedBlock& b = blocks[i];
    out[i].left = read_line(green, board, b.row, b.left_line_px);
    out[i].right = read_line(green, board, b.row, b.right_line_px);
    out[i].left.neighbour_px = neighbour(i, b.left_line_px);
    out[i].right.neighbour_px = neighbour(i, b.right_line_px);
    for (const LineEvidence* l : {&out[i].left, &out[i].right})
      if (l->measured) widths.push_back(l->width_px);
    const double expected = length - line_width + 0.5 * line_width * kinds[i];
    out[i].pair_residual_px = std::abs((b.right_line_px - b.left_line_px) - expected);
    out[i].line_width_px = line_width;
  }
  // Most lines stand alone: the median is the width of one line as this frame's focus shows it.
  double frame_width = line_width;
  if (!widths.empty()) {
    std::nth_element(widths.begin(), widths.begin() + static_cast<std::ptrdiff_t>(widths.size() / 2), widths.end());
    frame_width = widths[widths.size() / 2];
  }
  const double phase = phase_bias(line_width, frame_width, !board.identity());
  for (BlockEvidence& e : out) e.frame_width_px = frame_width, e.phase_px = phase;
  return out;
}

double frame_uncertainty(const BlockEvidence& e, double block_length_px, const UncertaintyModel& m) {
  if (!e.left.measured || !e.right.measured || !(block_length_px > 0)) return m.unmeasured;
  // A line centre's standard error, two ways: the rows' scatter sees noise directly; the profile predicts it
  // from contrast. A centroid over a dip of width w moves by about noise x sqrt(w) / depth per row (the noise
  // of ~w samples, each weighed against the depth), averaged over the effective rows: darker lines, less noise
  // and more rows measure better. The larger of the two, so neither a few lucky rows nor a profile that hides
  // texture make the estimate small.
  auto line_se = [&](const LineEvidence& l) {
    const double snr = m.snr_factor * std::sqrt(std::max(1.0, l.width_px)) * l.noise /
                       (std::max(1e-3, l.depth) * std::sqrt(std::max(1.0, l.rows_effective)));
    return std::max(l.scatter_px, snr);
  };
  const double sl = line_se(e.left), sr = line_se(e.right);
  // x is the pair's midpoint: half of each line's error, independent between the lines.
  const double random_px = 0.5 * std::sqrt(sl * sl + sr * sr);
  // What is the same in every row and every frame, so neither the scatter nor the temporal spread sees it:
  //  - sampling: a centroid of a line a pixel or two wide depends on where the line falls within its pixels
  //    and on JPEG's quantisation, a few hundredths of a pixel;
  //  - blur: a blurred line spreads over the neighbouring line of a touching block, the block's outline and
  //    shadow edges, whose overlap pulls its centroid; the pull grows with how far beyond its printed width
  //    the line spreads (measured: errors of blurred frames grow with it, sharp frames of any noise do not);
  //  - the pair residual: a line moved by e moves the midpoint by e/2, and the pair's spacing shows it; part of
  //    the residual is the frame's line-width estimate, not this block, hence the factor.
  const double blur_px = std::max(0.0, 0.5 * (e.left.width_px + e.right.width_px) - e.line_width_px);
  // Crowding: a neighbouring line within two line widths (at half depth) overlaps this line's dip and pulls its
  // centroid, the more the closer it comes; half of it per line, as for the pair.
  auto crowding = [&](const LineEvidence& l) { return std::max(0.0, 2.0 * e.frame_width_px - l.neighbour_px); };
  const double crowd_px = 0.5 * (crowding(e.left) + crowding(e.right));
  // Sampling: the centroid's pixel-phase error of lines this sharp and this wide (phase_bias), at least the
  // JPEG floor; both lines of a block can share their phase (a block a whole number of pixels long), so the
  // midpoint's error is as large as one line's.
  const double sampling = std::max(m.sampling_px, m.phase_factor * e.phase_px);
  const double px = m.coverage_factor * random_px + sampling + m.blur_factor * blur_px +
                    m.pair_factor * 0.5 * e.pair_residual_px + m.crowding_factor * crowd_px;
  return px / block_length_px;
}

double temporal_uncertainty(double spread, int samples) {
  if (samples < 3 || !(spread > 0)) return 0.0;
  return student_t95(samples - 1) * spread;
}

namespace {

// The bound the scale step states on board x (calibration_t.board_x_accuracy; 0 when not stated).
double stated_accuracy(const calibration_t& c, double x, double y) {
  const double* a = c.board_x_accuracy;
  return a[0] + a[1] * std::abs(x) + a[2] * std::max(0.0, y);
}

// The mapping's mean reprojection residual (projector px) carried to board x through the homography's slope.
double residual_floor(const calibration_t& c, double x, double y) {
  const double residual = c.reprojection_error_mean_px;
  if (!(residual > 0)) return 0.0;
  const cv::Matx33d cam_to_proj(c.camera_to_projector), cam_to_board(c.camera_to_board);
  if (std::abs(cv::determinant(cam_to_proj)) < 1e-12)
    throw std::invalid_argument("calibration: camera_to_projector is singular");
  const cv::Matx33d proj_to_board = cam_to_board * cam_to_proj.inv();
  const cv::Matx33d board_to_proj = proj_to_board.inv();
  const cv::Vec3d q = board_to_proj * cv::Vec3d(x, y, 1.0);
  if (!(std::abs(q[2]) > 1e-12)) throw std::invalid_argument("calibration: board point maps to infinity");
  const double u = q[0] / q[2], v = q[1] / q[2];
  // d(board x)/d(projector u, v) of the homography at (u, v).
  const cv::Matx33d& H = proj_to_board;
  const double w = H(2, 0) * u + H(2, 1) * v + H(2, 2);
  const double bx = (H(0, 0) * u + H(0, 1) * v + H(0, 2)) / w;
  const double dxu = (H(0, 0) - bx * H(2, 0)) / w, dxv = (H(0, 1) - bx * H(2, 1)) / w;
  return residual * std::hypot(dxu, dxv);
}

}  // namespace

double calibration_floor(const calibration_t& c, double x, double y) {
  // Both are the calibration's: the mapping's residual and the board frame's scale, independent errors
  // that add.
  return residual_floor(c, x, y) + stated_accuracy(c, x, y);
}

double published_uncertainty(double frame, double temporal, double lag, double calibration_floor, double operator_floor) {
  return std::max({std::max(frame, temporal) + lag, calibration_floor, operator_floor});
}

}  // namespace bricklayer::vision
