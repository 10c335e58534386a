#include "bricklayer/detection/detector.h"

#include <algorithm>
#include <cmath>
#include <stdexcept>

#include <opencv2/imgproc.hpp>


namespace bricklayer::detection {
namespace {

constexpr float kDarkFloor = 4.0f;  // background levels below this (0..255) carry no usable contrast

// Running maximum over a centred window of `radius` (simple and fast enough for one profile row).
void max_filter(const float* in, float* out, int n, int radius) {
  for (int x = 0; x < n; ++x) {
    const int a = std::max(0, x - radius), b = std::min(n - 1, x + radius);
    float m = in[a];
    for (int k = a + 1; k <= b; ++k) m = std::max(m, in[k]);
    out[x] = m;
  }
}

// Centred box mean over `radius`, shrinking at the ends.
void box_filter(const float* in, float* out, int n, int radius) {
  double sum = 0;
  int a = 0, b = -1;  // current window [a, b]
  for (int x = 0; x < n; ++x) {
    const int na = std::max(0, x - radius), nb = std::min(n - 1, x + radius);
    while (b < nb) sum += in[++b];
    while (a < na) sum -= in[a++];
    out[x] = static_cast<float>(sum / (b - a + 1));
  }
}

}  // namespace

void place_block(DetectedBlock& block, const BoardFrame& frame) {
  const BoardGeometry& g = frame.geometry();
  block.left_px = g.edge_x_px + block.x * g.block_length_px;
  const double bottom = g.surface_y_px - block.row * g.block_height_px, top = bottom - g.block_height_px;
  const double right = block.left_px + g.block_length_px;
  const cv::Point2d corners[4] = {{block.left_px, bottom}, {right, bottom}, {right, top}, {block.left_px, top}};
  for (int c = 0; c < 4; ++c) {
    const cv::Point2d q = frame.to_camera(corners[c]);
    block.corner_u[c] = q.x;
    block.corner_v[c] = q.y;
  }
}

bool whole_in_view(const DetectedBlock& b, cv::Size image) {
  if (!std::isfinite(b.x)) return false;
  // Pixel centres are integers, so the image covers [-0.5, size - 0.5].
  for (int c = 0; c < 4; ++c) {
    if (!(b.corner_u[c] >= -0.5 && b.corner_u[c] <= image.width - 0.5 && b.corner_v[c] >= -0.5 &&
          b.corner_v[c] <= image.height - 0.5))
      return false;
  }
  return true;
}

Detector::Detector(const BoardGeometry& geometry, const DetectorConfig& config)
    : config_(config),
      default_geometry_(geometry),
      frame_(geometry),
      camera_to_projector_(kDefaultCameraToProjector.data()),
      projector_size_(kDefaultProjectorWidth, kDefaultProjectorHeight),
      green_mixing_(config.default_green_mixing) {
  if (!(geometry.block_length_px > 2) || !(geometry.block_height_px > 2))
    throw std::invalid_argument("board geometry: blocks must be more than 2 pixels long and tall");
}

void Detector::set_calibration(const calibration_t& c) {
  BoardFrame f = BoardFrame::from_calibration(c);  // validates the camera part
  for (double v : c.camera_to_projector)
    if (!std::isfinite(v)) throw std::invalid_argument("calibration: camera_to_projector is not finite");
  for (double v : c.colour_mixing)
    if (!std::isfinite(v) || std::abs(v) > 10) throw std::invalid_argument("calibration: colour_mixing out of range");
  if (c.projector_width <= 0 || c.projector_height <= 0)
    throw std::invalid_argument("calibration: projector_width/projector_height must be positive");
  frame_ = std::move(f);
  camera_to_projector_ = cv::Matx33d(c.camera_to_projector);
  projector_size_ = {c.projector_width, c.projector_height};
  green_mixing_ = {c.colour_mixing[3], c.colour_mixing[4], c.colour_mixing[5]};
  prepared_size_ = {-1, -1};
}

void Detector::set_projector_image(const cv::Mat& bgr, cv::Size projector_size) {
  if (bgr.empty() || bgr.type() != CV_8UC3) throw std::invalid_argument("projector image must be non-empty BGR8");
  projector_image_ = bgr.clone();
  if (projector_size.width > 0 && projector_size.height > 0) projector_size_ = projector_size;
  prepared_size_ = {-1, -1};
}

void Detector::clear_projector_image() {
  projector_image_.release();
  prepared_size_ = {-1, -1};
}

void Detector::prepare(cv::Size size) {
  if (size == prepared_size_) return;
  prepared_size_ = size;
  const BoardGeometry& g = frame_.geometry();
  const double h = g.block_height_px;
  bands_.clear();
  for (int row = 0;; ++row) {
    const double top = g.surface_y_px - (row + 1) * h, bottom = g.surface_y_px - row * h;
    const int y0 = static_cast<int>(std::ceil(top + config_.band_margin * h));
    const int y2 = static_cast<int>(std::floor(bottom - config_.band_margin * h));
    if (y0 < 0 || row > 1000) break;
    if (y2 > size.height) continue;  // band below the image: skip, rows above may still be seen
    const int y1 = (y0 + y2) / 2;
    if (y1 <= y0 || y2 <= y1) break;
    bands_.push_back({row, y0, y1, y2});
  }
  leak_up_.assign(bands_.size(), {});
  leak_lo_.assign(bands_.size(), {});
  leak_valid_ = false;
  if (projector_image_.empty()) return;

  // Predicted green leakage, drawn in projector-image pixels, then warped into the rectified frame.
  cv::Mat bgr_f;
  projector_image_.convertTo(bgr_f, CV_32FC3);
  cv::Mat leak_proj;
  cv::transform(bgr_f, leak_proj,
                cv::Matx13f(static_cast<float>(green_mixing_[0]), static_cast<float>(green_mixing_[1]),
                            static_cast<float>(green_mixing_[2])));
  const double sx = static_cast<double>(projector_image_.cols) / projector_size_.width;
  const double sy = static_cast<double>(projector_image_.rows) / projector_size_.height;
  const cv::Matx33d scale(sx, 0, 0.5 * sx - 0.5, 0, sy, 0.5 * sy - 0.5, 0, 0, 1);
  const cv::Matx33d rect_to_image = scale * camera_to_projector_ * frame_.rectified_to_undistorted();
  cv::Mat leak;
  cv::warpPerspective(leak_proj, leak, cv::Mat(rect_to_image), size, cv::INTER_LINEAR | cv::WARP_INVERSE_MAP,
                      cv::BORDER_CONSTANT, cv::Scalar(0));
  for (size_t i = 0; i < bands_.size(); ++i) {
    const Band& b = bands_[i];
    cv::Mat up, lo;
    cv::reduce(leak.rowRange(b.y0, b.y1), up, 0, cv::REDUCE_AVG, CV_32F);
    cv::reduce(leak.rowRange(b.y1, b.y2), lo, 0, cv::REDUCE_AVG, CV_32F);
    leak_up_[i].assign(up.ptr<float>(), up.ptr<float>() + size.width);
    leak_lo_[i].assign(lo.ptr<float>(), lo.ptr<float>() + size.width);
  }
  leak_valid_ = true;
}

void Detector::find_lines(const float* up, const float* lo, int n, std::vector<Dip>& dips, int& rejected) {
  const double length = frame_.geometry().block_length_px;
  const int max_radius = std::max(2, static_cast<int>(std::lround(0.09 * length)));
  const int box_radius = std::max(2, static_cast<int>(std::lround(0.10 * length)));
  const double max_width = config_.max_line_width * length;
  const float min_depth = static_cast<float>(config_.min_depth);

  for (auto* v : {&full_, &bg_, &mx_, &d_, &du_, &dl_}) v->resize(n);
  std::vector<float>&full = full_, &bg = bg_, &mx = mx_, &d = d_, &du = du_, &dl = dl_;
  for (int x = 0; x < n; ++x) full[x] = 0.5f * (up[x] + lo[x]);
  max_filter(full.data(), mx.data(), n, max_radius);
  box_filter(mx.data(), bg.data(), n, box_radius);
  for (int x = 0; x < n; ++x) {
    if (bg[x] < kDarkFloor) {
      d[x] = du[x] = dl[x] = 0;
      continue;
    }
    d[x] = 1.0f - full[x] / bg[x];
    du[x] = 1.0f - up[x] / bg[x];
    dl[x] = 1.0f - lo[x] / bg[x];
  }

  // Peaks: local maxima deep enough; neighbouring peaks not separated by a real valley are one dip.
  std::vector<int> peaks;
  for (int x = 1; x + 1 < n; ++x) {
    if (d[x] >= min_depth && d[x] >= d[x - 1] && d[x] > d[x + 1]) {
      if (!peaks.empty()) {
        const int p = peaks.back();
        float valley = d[p];
        for (int k = p; k <= x; ++k) valley = std::min(valley, d[k]);
        if (valley > 0.6f * std::min(d[p], d[x])) {
          if (d[x] > d[p]) peaks.back() = x;
          continue;
        }
      }
      peaks.push_back(x);
    }
  }
  // The valley (lowest point) between consecutive peaks bounds each dip.
  std::vector<int> valley(peaks.size() + 1);
  valley.front() = 0;
  valley.back() = n - 1;
  for (size_t i = 0; i + 1 < peaks.size(); ++i) {
    int v = peaks[i];
    for (int k = peaks[i]; k <= peaks[i + 1]; ++k)
      if (d[k] < d[v]) v = k;
    valley[i + 1] = v;
  }
  for (size_t i = 0; i < peaks.size(); ++i) {
    const int p = peaks[i];
    const float peak = d[p];
    // Dip extent: down to 30% of the peak, never past the valley towards a neighbouring peak. Not
    // stopped by a shallow notch: two nearly touching lines (blocks 1-3 px apart) are one dip with two
    // sub-minima, and must measure as wide as both so the split below separates them.
    const int lo_limit = valley[i], hi_limit = valley[i + 1];
    int a = p, b = p;
    while (a > lo_limit && d[a - 1] >= 0.3f * peak) --a;
    while (b < hi_limit && d[b + 1] >= 0.3f * peak) ++b;
    // Width at half depth, with linear interpolation of the crossings.
    const float half = 0.5f * peak;
    int l = p, r = p;
    while (l > a && d[l - 1] >= half) --l;
    while (r < b && d[r + 1] >= half) ++r;
    double left_edge = l, right_edge = r;
    if (l > 0 && d[l - 1] < half) left_edge = l - (d[l] - half) / std::max(1e-6f, d[l] - d[l - 1]);
    if (r + 1 < n && d[r + 1] < half) right_edge = r + (d[r] - half) / std::max(1e-6f, d[r] - d[r + 1]);
    const double width = right_edge - left_edge;
    if (width > max_width) {
      ++rejected;
      continue;
    }
    // A line runs the full block height: it must be dark in both halves of the band.
    const float up_depth = std::max({du[p], du[std::max(0, p - 1)], du[std::min(n - 1, p + 1)]});
    const float lo_depth = std::max({dl[p], dl[std::max(0, p - 1)], dl[std::min(n - 1, p + 1)]});
    if (std::min(up_depth, lo_depth) < 0.5f * min_depth || std::min(up_depth, lo_depth) < 0.35f * std::max(up_depth, lo_depth))
      continue;
    // Sub-pixel position: centroid of the dip above 30% of its depth.
    double sw = 0, sx = 0;
    const float floor_level = 0.3f * peak;
    for (int k = a; k <= b; ++k) {
      const double w = d[k] - floor_level;
      if (w > 0) sw += w, sx += w * k;
    }
    dips.push_back({sw > 0 ? sx / sw : p, peak, width});
  }
}

Detection Detector::detect(const cv::Mat& frame) {
  Detection out;
  if (frame.empty() || frame.depth() != CV_8U || (frame.channels() != 1 && frame.channels() != 3)) {
    out.status = Detection::kNoFrame;
    return out;
  }
  if (!frame_.identity() && frame.size() != frame_.camera_size()) {
    out.status = Detection::kNoFrame;
    return out;
  }
  cv::Mat green;
  if (frame.channels() == 3)
    cv::extractChannel(frame, green, 1);
  else
    green = frame;
  const cv::Mat rect = frame_.rectify(green);
  prepare(rect.size());
  if (bands_.empty()) {
    out.status = Detection::kNoBoard;
    return out;
  }
  const int y_top = bands_.back().y0, y_bottom = bands_.front().y2;
  if (cv::mean(rect.rowRange(y_top, y_bottom))[0] < config_.min_board_level) {
    out.status = Detection::kNoBoard;
    return out;
  }

  const BoardGeometry& g = frame_.geometry();
  const double length = g.block_length_px, tol = config_.length_tolerance * length;
  const int n = rect.cols;
  cv::Mat up_m, lo_m;
  std::vector<double> lines, depths;
  struct Pair {
    int row;
    double left, right;  // line centroids, rectified pixels
    bool shared_left = false, shared_right = false;
    double err, depth;
  };
  std::vector<Pair> pairs;
  std::vector<std::vector<Dip>> band_dips(bands_.size());
  for (size_t bi = 0; bi < bands_.size(); ++bi) {
    const Band& band = bands_[bi];
    cv::reduce(rect.rowRange(band.y0, band.y1), up_m, 0, cv::REDUCE_AVG, CV_32F);
    cv::reduce(rect.rowRange(band.y1, band.y2), lo_m, 0, cv::REDUCE_AVG, CV_32F);
    float* up = up_m.ptr<float>();
    float* lo = lo_m.ptr<float>();
    if (config_.keep_profiles) {
      Detection::Profile& profile = out.profiles.emplace_back();
      profile.row = band.row;
      profile.level.resize(static_cast<size_t>(n));
      for (int x = 0; x < n; ++x) profile.level[static_cast<size_t>(x)] = 0.5f * (up[x] + lo[x]);
      if (leak_valid_) {
        profile.leakage.resize(static_cast<size_t>(n));
        for (int x = 0; x < n; ++x) profile.leakage[static_cast<size_t>(x)] = 0.5f * (leak_up_[bi][x] + leak_lo_[bi][x]);
      }
    }
    if (leak_valid_) {
      for (int x = 0; x < n; ++x) {
        up[x] = std::max(0.0f, up[x] - leak_up_[bi][x]);
        lo[x] = std::max(0.0f, lo[x] - leak_lo_[bi][x]);
      }
    }
    find_lines(up, lo, n, band_dips[bi], out.rejected_wide);
  }
  // Width of a single line in this frame (blur and focus vary): the median dip width, since most dips
  // are single lines. A dip clearly wider is two nearly touching lines: split it around its centroid.
  // Every block's end lines are printed alike, so in one frame real lines are about equally dark
  // relative to their local background (measured: 0.74x the frame's median or darker even at the harsh
  // level); the much fainter dips are shadow-edge slopes, leakage residue and noise.
  std::vector<double> depths_all;
  for (const auto& dips : band_dips)
    for (const Dip& dip : dips) depths_all.push_back(dip.depth);
  if (depths_all.size() >= 4) {
    std::nth_element(depths_all.begin(), depths_all.begin() + depths_all.size() / 2, depths_all.end());
    const double floor_depth = config_.min_relative_depth * depths_all[depths_all.size() / 2];
    for (auto& dips : band_dips) {
      const auto faint = std::remove_if(dips.begin(), dips.end(), [&](const Dip& d) { return d.depth < floor_depth; });
      out.rejected_faint += static_cast<int>(dips.end() - faint);
      dips.erase(faint, dips.end());
    }
  }
  std::vector<double> widths;
  for (const auto& dips : band_dips)
    for (const Dip& dip : dips) widths.push_back(dip.width);
  double single_width = 0;
  if (widths.size() >= 4) {
    std::nth_element(widths.begin(), widths.begin() + widths.size() / 2, widths.end());
    single_width = widths[widths.size() / 2];
  }

  std::vector<std::vector<double>> band_lines(bands_.size()), band_depths(bands_.size());
  for (size_t bi = 0; bi < bands_.size(); ++bi) {
    const Band& band = bands_[bi];
    lines.clear();
    depths.clear();
    for (const Dip& dip : band_dips[bi]) {
      if (single_width > 0 && dip.width > config_.split_ratio * single_width) {
        const double half_spacing = 0.5 * (dip.width - single_width);
        lines.push_back(dip.pos - half_spacing);
        lines.push_back(dip.pos + half_spacing);
        depths.push_back(dip.depth);
        depths.push_back(dip.depth);
      } else {
        lines.push_back(dip.pos);
        depths.push_back(dip.depth);
      }
    }
    out.lines += static_cast<int>(lines.size());
    if (config_.keep_lines)
      for (size_t k = 0; k < lines.size(); ++k) out.line_list.push_back({band.row, lines[k], depths[k]});

    band_lines[bi] = lines;
    band_depths[bi] = depths;
  }

  // Pairing: a block is two lines one length apart; when blocks touch, one line (or two nearly
  // coincident ones) ends a block and starts the next. Choose the non-overlapping set of blocks that
  // explains the most lines, then the best lengths (dynamic programming over the sorted lines).
  // Lines lie inside the blocks: a lone line's centroid is half a line width w inside the block's end, a
  // line shared by two touching blocks sits on the boundary, so the expected spacing of a pair is
  // L - w (both lone), L - w/2 (one shared) or L (both shared). Judging lengths against these, not L,
  // tells a chain of touching blocks from blocks with one-length gaps between them.
  auto pair_lines = [&](double w) {
    pairs.clear();
    for (size_t bi = 0; bi < bands_.size(); ++bi) {
      const std::vector<double>& lines_b = band_lines[bi];
      const std::vector<double>& depths_b = band_depths[bi];
      const int m = static_cast<int>(lines_b.size());
      auto expected = [&](int shared_left, int shared_right) { return length - w + 0.5 * w * (shared_left + shared_right); };
      // score[i][used]: best over lines i.. when line i is (used = 1) or is not yet the right end of a block.
      std::vector<std::array<double, 2>> score(m + 1, {0.0, 0.0});
      std::vector<std::array<int, 2>> choice(m + 1, {-1, -1});   // partner j, or -1 for "skip line i"
      std::vector<std::array<int, 2>> next_used(m + 1, {0, 0});  // after the block (i, j): continue at j (1) or j+1 (0)
      for (int i = m - 1; i >= 0; --i) {
        for (int used = 0; used <= 1; ++used) {
          double best = score[i + 1][0];
          int best_j = -1, best_next = 0;
          for (int j = i + 1; j < m && lines_b[j] - lines_b[i] < length + tol; ++j) {
            const double spacing = lines_b[j] - lines_b[i];
            if (std::abs(spacing - length) >= tol) continue;
            const double lines_gained = used ? 1.0 : 2.0;
            // Line j shared with the next block, or lone.
            const double via_shared = lines_gained - 0.5 * std::abs(spacing - expected(used, 1)) / tol + score[j][1];
            const double via_next = lines_gained - 0.5 * std::abs(spacing - expected(used, 0)) / tol + score[j + 1][0];
            const double total = std::max(via_shared, via_next);
            if (total > best + 1e-9) best = total, best_j = j, best_next = via_shared > via_next ? 1 : 0;
          }
          score[i][used] = best;
          choice[i][used] = best_j;
          next_used[i][used] = best_next;
        }
      }
      for (int i = 0, used = 0; i < m;) {
        const int j = choice[i][used];
        if (j < 0) {
          ++i;
          used = 0;
          continue;
        }
        Pair pair;
        pair.row = bands_[bi].row;
        pair.left = lines_b[i];
        pair.right = lines_b[j];
        pair.shared_left = used == 1;
        pair.shared_right = next_used[i][used] == 1;
        pair.err = std::abs(lines_b[j] - lines_b[i] - expected(pair.shared_left, pair.shared_right));
        pair.depth = std::min(depths_b[i], depths_b[j]);
        pairs.push_back(pair);
        if (pair.shared_right) {
          i = j;
          used = 1;
        } else {
          i = j + 1;
          used = 0;
        }
      }
    }
  };
  // The line width: first the configured one, then the median over this frame's pairs of lone lines
  // (blur and focus make it vary), and pair again with it.
  double line_width = config_.line_width * length;
  pair_lines(line_width);
  std::vector<double> pair_widths;
  for (const Pair& p : pairs)
    if (!p.shared_left && !p.shared_right) pair_widths.push_back(length - (p.right - p.left));
  if (pair_widths.size() >= 3) {
    std::nth_element(pair_widths.begin(), pair_widths.begin() + pair_widths.size() / 2, pair_widths.end());
    const double measured = std::clamp(pair_widths[pair_widths.size() / 2], 0.0, config_.max_line_width * length);
    if (std::abs(measured - line_width) > 0.05 * line_width) {
      line_width = measured;
      pair_lines(line_width);
    }
  }
  for (const Pair& p : pairs) {
    const double left = p.shared_left ? p.left + 0.5 * line_width : p.left;
    const double right = p.shared_right ? p.right - 0.5 * line_width : p.right;
    DetectedBlock blk;
    blk.row = p.row;
    blk.x = (0.5 * (left + right) - 0.5 * length - g.edge_x_px) / length;
    const double contrast = p.depth / (2.0 * config_.min_depth);
    blk.confidence = std::clamp(std::min(1.0, contrast) * (1.0 - p.err / tol), 0.0, 1.0);
    blk.left_line_px = p.left;
    blk.right_line_px = p.right;
    place_block(blk, frame_);
    out.blocks.push_back(blk);
  }
  return out;
}

}  // namespace bricklayer::detection
