// bricklayer-bench-calibration: accuracy and cost of calibration over random simcam setups, and the
// measurement behind the choice of method (marker corners with a modelled corner bias, marker centres
// only, or a dense Gray-code map).
//
// For seeds 1..N and a nuisance level: renders every calibration pattern through
// CameraSetup::random(seed) / ProjectorSetup::random(seed), calibrates, and compares camera ->
// projector with the truth over a grid covering the board. Prints per method the median and p99 (over
// setups) of the mean and max mapping error, and the median / p99 time of compute_calibration; for the
// board frame: where the origin lands, how level the surface is, and how far board x is off along the
// bottom row as calibrated and after the correction from blocks (detection/block_scale.h), and after
// the correction over the whole board (x -5..5 in bands, rows 0, 3, 6 and 9), along the board only and
// with the lean of the end lines (calibration/line_lean.h); --verbose also prints, per setup, the
// correction the truth asks for next to the measured one.
//
// The blocks for the scale step: --layout apart (the earlier figures' bottom row, its last block beyond the
// surface edge, where no block can stand), standing (every bottom-row block's middle over the surface) or
// stairs (standing, the right-hand tower stepping out over the edge, balanced); --nudge moves them between
// frames (0: standing still, as they do on the exhibit while the step measures); --frames as --scale-frames.
// The floor line: the correction's form fitted to the truth itself, what no measurement from blocks beats.
//
//   bricklayer-bench-calibration [--setups 20] [--nuisance mild] [--gray-code] [--shelf-clearance 8]
//                                [--towers 9] [--layout apart|standing|stairs] [--nudge 0.011] [--frames 10]
#include <opencv2/calib3d.hpp>
#include <opencv2/imgproc.hpp>

#include <algorithm>
#include <chrono>
#include <cstdio>
#include <functional>
#include <string>
#include <vector>

#include "bricklayer/calibration/calibrator.h"
#include "bricklayer/calibration/line_lean.h"
#include "bricklayer/calibration/board_frame_refit.h"
#include "bricklayer/calibration/board_x_accuracy.h"
#include "bricklayer/board/mapping.h"
#include "bricklayer/patterns/patterns.h"
#include "bricklayer/common/flags.h"
#include "bricklayer/simcam/render.h"
#include "bricklayer/detection/block_scale.h"

namespace bricklayer {
namespace {

namespace cal = calibration;
namespace sim = simcam;

// Board x is judged over the whole board: x from -5 to 5 block lengths in these bands, on these rows.
constexpr double kBands[][2] = {{-5, -4}, {-4, -2}, {-2, 2}, {2, 4}, {4, 5}};
constexpr int kBandCount = 5;
constexpr int kRows[] = {0, 3, 6, 9};
constexpr int kRowCount = 4;

struct Stats {
  std::vector<double> mean, max, ms, colour, origin, level, shelf_found, board_x, board_x_fixed, reported_max, near_shelf;
  // Worst |board x error| per setup after the correction from blocks, per x band (all rows) and per row (all x).
  std::vector<double> band_fixed[kBandCount], row_fixed[kRowCount], whole_fixed, band_raw[kBandCount];
  // The same after the lean of the end lines corrected the frame's vertical too (calibration/line_lean.h).
  std::vector<double> band_lean[kBandCount], row_lean[kRowCount], whole_lean;
  // The stated accuracy (calibration/board_x_accuracy.h) against the truth: per setup the largest error / bound
  // over the whole-board grid (<= 1: covered everywhere), and the bound at x = 5 on row 9.
  std::vector<double> bound_ratio, bound_far;
  // After the second pass (calibration/board_frame_refit.h: every row measured again in the first pass's
  // frame): per x band, per row, per band and row, the whole grid; the stated bound's coverage; the scale's
  // error against the truth (measured a / true a - 1) after the first pass and after the second.
  std::vector<double> band_refit[kBandCount], row_refit[kRowCount], cell_refit[kBandCount][kRowCount], whole_refit;
  std::vector<double> refit_bound_ratio, refit_bound_far, scale_error_first, scale_error_refit;
  int refit_failed = 0;
  // The floor (ideal_correction): per x band and whole grid, with the shelf's origin as found and with it free.
  std::vector<double> band_floor[kBandCount], whole_floor, band_floor_origin[kBandCount], whole_floor_origin;
};


double percentile(std::vector<double> v, double p) {
  if (v.empty()) return 0;
  std::sort(v.begin(), v.end());
  const size_t i = std::min(v.size() - 1, static_cast<size_t>(p * (v.size() - 1) + 0.5));
  return v[i];
}

// Largest |board x - true x| along the bottom row (y = 0.2), x = -4..4 block lengths, where the camera sees it.
double board_x_error(const calibration_t& c, const sim::CameraSetup& camera) {
  double worst = 0;
  for (double bx = -4; bx <= 4; bx += 0.25) {
    const cv::Point2d p = sim::rectified_to_camera(camera, {camera.board.to_px_x(bx), camera.board.to_px_y(0.2)});
    if (p.x < 2 || p.y < 2 || p.x > camera.size.width - 3 || p.y > camera.size.height - 3) continue;
    worst = std::max(worst, std::abs(board::camera_to_board(c, p).x - bx));
  }
  return worst;
}

// Worst |board x - true x| per x band (over kRows) and per row (over -5..5), where the camera sees the point.
struct BoardXGrid {
  double band[kBandCount] = {0, 0, 0, 0, 0};
  double row[kRowCount] = {0, 0, 0, 0};
  double cell[kBandCount][kRowCount] = {};
  double whole = 0;
};
double bound_ratio(const calibration_t& c, const sim::CameraSetup& camera, const cal::BoardXAccuracy& bound) {
  double worst = 0;
  for (int r = 0; r < kRowCount; ++r) {
    const double by = (kRows[r] + 0.5) * camera.board.block_height_px / camera.board.block_length_px;
    for (double bx = -5; bx <= 5 + 1e-9; bx += 0.25) {
      const cv::Point2d p = sim::rectified_to_camera(camera, {camera.board.to_px_x(bx), camera.board.to_px_y(by)});
      if (p.x < 2 || p.y < 2 || p.x > camera.size.width - 3 || p.y > camera.size.height - 3) continue;
      worst = std::max(worst, std::abs(board::camera_to_board(c, p).x - bx) / bound.at(bx, by));
    }
  }
  return worst;
}

BoardXGrid board_x_grid(const calibration_t& c, const sim::CameraSetup& camera) {
  BoardXGrid g;
  for (int r = 0; r < kRowCount; ++r) {
    // Half way up the row's band: block heights in block lengths.
    const double by = (kRows[r] + 0.5) * camera.board.block_height_px / camera.board.block_length_px;
    for (double bx = -5; bx <= 5 + 1e-9; bx += 0.25) {
      const cv::Point2d p = sim::rectified_to_camera(camera, {camera.board.to_px_x(bx), camera.board.to_px_y(by)});
      if (p.x < 2 || p.y < 2 || p.x > camera.size.width - 3 || p.y > camera.size.height - 3) continue;
      const double e = std::abs(board::camera_to_board(c, p).x - bx);
      g.row[r] = std::max(g.row[r], e);
      g.whole = std::max(g.whole, e);
      for (int b = 0; b < kBandCount; ++b)
        if (bx >= kBands[b][0] - 1e-9 && bx <= kBands[b][1] + 1e-9) g.band[b] = std::max(g.band[b], e), g.cell[b][r] = std::max(g.cell[b][r], e);
    }
  }
  return g;
}

// The floor no correction from blocks can go below: the correction of bricklayer-calibrate's form (a, b, g, h)
// fitted to the truth itself over the whole-board grid (board x error made linear: x_true (g x + h y + 1) =
// a x + b y), and the same with the origin free too (an added x offset: what the shelf's origin leaves). What
// remains is the calibration's own mapping error (the lens, the fit's bends) and, without the offset, the origin.
BoardXGrid ideal_correction(const calibration_t& c, const sim::CameraSetup& camera, bool free_origin) {
  std::vector<double> rows_a, rhs;
  const int n = free_origin ? 5 : 4;
  for (int r = 0; r <= 9; ++r) {
    const double by = (r + 0.5) * camera.board.block_height_px / camera.board.block_length_px;
    for (double bx = -5; bx <= 5 + 1e-9; bx += 0.25) {
      const cv::Point2d p = sim::rectified_to_camera(camera, {camera.board.to_px_x(bx), camera.board.to_px_y(by)});
      if (p.x < 2 || p.y < 2 || p.x > camera.size.width - 3 || p.y > camera.size.height - 3) continue;
      const cv::Point2d m = board::camera_to_board(c, p);
      rows_a.insert(rows_a.end(), {m.x, m.y, -m.x * bx, -m.y * bx});
      if (free_origin) rows_a.push_back(1.0);
      rhs.push_back(bx);
    }
  }
  const cv::Mat A(static_cast<int>(rhs.size()), n, CV_64F, rows_a.data()), B(static_cast<int>(rhs.size()), 1, CV_64F, rhs.data());
  cv::Mat v;
  cv::solve(A, B, v, cv::DECOMP_SVD);
  calibration_t out = cal::apply_frame_correction(c, v.at<double>(0), v.at<double>(2), v.at<double>(1), v.at<double>(3));
  if (free_origin) {
    // x' + t0: camera_to_board's first row gains t0 times its last.
    for (int j = 0; j < 3; ++j) out.camera_to_board[j] += v.at<double>(4) * out.camera_to_board[6 + j];
  }
  return board_x_grid(out, camera);
}

// How far the blocks move between frames, block lengths (--nudge).
double g_nudge = 0.011;

// The bottom row's blocks, nudged a little per frame. "apart" (the layout of the earlier figures): -3.5, -2.1,
// -0.7 and 0.6, the last wholly beyond the surface edge: a block there cannot stand (its centre is 1.1 out), so
// it is a ruler no operator can lay. "standing": -4.7, -3.5, -2.1, -0.7, every centre over the surface.
std::vector<core::Block> bottom_row(int frame, const std::string& layout) {
  const double d = g_nudge * frame;
  if (layout == "apart") return {{1, 0, -3.5 + d}, {2, 0, -2.1 - d}, {3, 0, -0.7 + d}, {4, 0, 0.6 - d}};
  return {{1, 0, -4.7 - d}, {2, 0, -3.5 + d}, {3, 0, -2.1 - d}, {4, 0, -0.7 + d}};
}

// The bottom row and one on top (no towers).
core::Stack blocks_apart(int frame, const std::string& layout) {
  core::Stack s;
  s.blocks = bottom_row(frame, layout);
  s.blocks.push_back({5, 1, -3.2 + g_nudge * frame});
  return s;
}

// The same bottom row with two towers on it (--towers): on the blocks at -3.5 and -0.7, one block on
// another up to row `top`, each a few hundredths off the one below as hands leave them. With --layout
// stairs the right-hand tower steps out to the right as it rises, balanced with a margin: each block
// reaches out over the one below by `step` times what the harmonic stack allows (1/(2k) for the k-th block
// from the top, where every upper part's centre of mass is at the edge of the block below it), and its bottom
// block is placed so the whole column's centre of mass is 0.15 inside the surface edge (step 0.7: every
// upper part's at least 0.15 inside the block below; the top block reaches 1.03).
core::Stack towers(int frame, int top, const std::string& layout, double step = 0.7) {
  const double d = g_nudge * frame;
  core::Stack s;
  s.blocks = bottom_row(frame, layout);
  const int n = top + 1;
  std::vector<double> out(n, 0.0);
  for (int row = 1; row <= top; ++row) out[row] = out[row - 1] + step / (2.0 * (n - row));
  double mean = 0;
  for (double o : out) mean += o / n;
  const double base = -0.15 - 0.5 - mean + d;
  if (layout == "stairs") s.blocks.back().x = base;
  int id = 5;
  for (int row = 1; row <= top; ++row) {
    const double jitter = 0.03 * ((row * 7) % 5 - 2) / 2.0;
    s.blocks.push_back({id++, row, -3.5 + d + jitter});
    s.blocks.push_back({id++, row, layout == "stairs" ? base + out[row] : -0.7 + d - jitter});
  }
  return s;
}

void mapping_error(const calibration_t& c, const sim::CameraSetup& camera, const sim::ProjectorSetup& projector, Stats& s) {
  double sum = 0, max = 0;
  int n = 0;
  for (double y = 10; y <= 470; y += 20) {
    for (double x = 10; x <= 630; x += 20) {
      const cv::Point2d p = sim::rectified_to_camera(camera, {x, y});
      if (p.x < 2 || p.y < 2 || p.x > camera.size.width - 3 || p.y > camera.size.height - 3) continue;
      const double d = cv::norm(board::camera_to_projector(c, p) - sim::camera_to_projector(camera, projector, p));
      sum += d;
      max = std::max(max, d);
      ++n;
    }
  }
  s.mean.push_back(sum / std::max(1, n));
  s.max.push_back(max);
}

// A fit into a calibration_t that only carries the lens and camera_to_projector (enough for mapping).
calibration_t from_fit(const cal::LensFit& fit, cv::Size camera, cv::Size projector) {
  calibration_t c{};
  c.camera_width = camera.width;
  c.camera_height = camera.height;
  c.projector_width = projector.width;
  c.projector_height = projector.height;
  c.camera_matrix[0] = fit.camera_matrix(0, 0);
  c.camera_matrix[1] = fit.camera_matrix(1, 1);
  c.camera_matrix[2] = fit.camera_matrix(0, 2);
  c.camera_matrix[3] = fit.camera_matrix(1, 2);
  for (int i = 0; i < 5; ++i) c.distortion[i] = fit.distortion[i];
  for (int i = 0; i < 9; ++i) c.camera_to_projector[i] = fit.camera_to_projector(i / 3, i % 3);
  return c;
}

// Dense Gray code: bits whose stripes are at least 4 projector pixels wide (finer ones blur away in a
// 640-wide camera), each against its inverse; every 3rd camera pixel whose every bit is decisive
// gives (camera pixel, centre of its 4-pixel projector stripe).
std::vector<cal::Correspondence> gray_code_points(const sim::Renderer& r, const sim::Nuisance& n, uint64_t seed) {
  const cv::Size psize = r.projector().size;
  const int total = patterns::gray_code_image_count(psize);
  constexpr int kSkipBits = 2;
  cv::Mat col_code, row_code, valid;
  const cv::Size csize = r.camera().size;
  col_code = cv::Mat::zeros(csize, CV_32S);
  row_code = cv::Mat::zeros(csize, CV_32S);
  valid = cv::Mat(csize, CV_8U, cv::Scalar(1));
  for (int i = 0; i < total; i += 2) {
    const patterns::GrayCodeBit b = patterns::gray_code_bit(i, psize);
    if (b.bit < kSkipBits) continue;
    command_t cmd{};
    cmd.command = command_t::SHOW_PATTERN;
    cmd.pattern = command_t::PATTERN_GRAY_CODE;
    cmd.index = i;
    const cv::Mat shown = patterns::render_pattern(cmd, psize);
    cmd.index = i + 1;
    const cv::Mat inverse = patterns::render_pattern(cmd, psize);
    cv::Mat a, bimg;
    cv::cvtColor(r.render(core::Stack{}, n, &shown, seed + i).bgr, a, cv::COLOR_BGR2GRAY);
    cv::cvtColor(r.render(core::Stack{}, n, &inverse, seed + i + 1).bgr, bimg, cv::COLOR_BGR2GRAY);
    for (int y = 0; y < csize.height; ++y) {
      for (int x = 0; x < csize.width; ++x) {
        const int d = static_cast<int>(a.at<uchar>(y, x)) - static_cast<int>(bimg.at<uchar>(y, x));
        if (std::abs(d) < 10) valid.at<uchar>(y, x) = 0;
        cv::Mat& code = b.columns ? col_code : row_code;
        if (d > 0) code.at<int>(y, x) |= 1 << (b.bit - kSkipBits);
      }
    }
  }
  auto binary = [](int g) {
    for (int shift = 1; shift < 32; shift <<= 1) g ^= g >> shift;
    return g;
  };
  std::vector<cal::Correspondence> out;
  for (int y = 1; y < csize.height; y += 3) {
    for (int x = 1; x < csize.width; x += 3) {
      if (!valid.at<uchar>(y, x)) continue;
      const double px = binary(col_code.at<int>(y, x)) * 4 + 1.5;
      const double py = binary(row_code.at<int>(y, x)) * 4 + 1.5;
      cal::Correspondence c;
      c.camera = cv::Point2d(x, y);
      c.projector = cv::Point2d(px, py);
      out.push_back(c);
    }
  }
  return out;
}

int Main(int argc, char** argv) {
  Flags flags("bricklayer-bench-calibration", "Calibration accuracy and cost over random simcam setups.");
  flags.add("setups", "20", "random setups (seeds 1..N)");
  flags.add("nuisance", "mild", "simcam nuisance level: clean, mild, strong, harsh");
  flags.add_bool("no-shelf", "do not search the shelf (board frame from the defaults as given)");
  flags.add_bool("square-projector", "the projector mounted square (simcam's default: the shelf top just below the bottom marker row) instead of ProjectorSetup::random");
  flags.add("shelf-clearance", "8", "camera px: markers with a corner this close to the shelf are left out (0 = keep all)");
  flags.add_bool("verbose", "print the board x error of every setup");
  flags.add("towers", "0", "blocks stand in two towers up to this row on the bottom row's blocks at -3.5 and -0.7 (0: the bottom row alone)");
  flags.add("layout", "apart", "the bottom row: apart (-3.5 -2.1 -0.7 0.6, the last beyond the edge, where no block stands), standing (-4.7 -3.5 -2.1 -0.7), stairs (standing, the tower on -0.7 stepping out to the right, balanced)");
  flags.add("step", "0.7", "--layout stairs: each block reaches out over the one below by this fraction of what the harmonic stack allows");
  flags.add("nudge", "0.011", "block lengths the blocks move between frames (0: standing still, as on the exhibit while the step measures)");
  flags.add("frames", "10", "camera frames of the blocks (bricklayer-calibrate --scale-frames)");
  flags.add("max-row", "12", "the second pass measures blocks on rows 0..this");
  flags.add_bool("gray-code", "also measure a dense Gray-code map (32 more frames per setup; slow)");
  if (!flags.parse(argc, argv)) return 0;
  const int setups = static_cast<int>(flags.get_int("setups"));
  sim::Nuisance nuisance = sim::Nuisance::named(flags.get("nuisance"));
  nuisance.layout_seed = 7;

  cal::CalibrationOptions options;
  options.board_from_shelf = !flags.get_bool("no-shelf");
  options.shelf_clearance_camera_px = flags.get_double("shelf-clearance");
  const bool verbose = flags.get_bool("verbose");
  const std::string layout = flags.get("layout");
  if (layout != "apart" && layout != "standing" && layout != "stairs") {
    std::fprintf(stderr, "--layout must be apart, standing or stairs, not %s\n", layout.c_str());
    return 2;
  }
  const double step = flags.get_double("step");
  g_nudge = flags.get_double("nudge");
  const int frames_count = static_cast<int>(flags.get_int("frames"));
  const auto steps = cal::calibration_steps(options);
  Stats corners, centres, gray;
  int rejected = 0;
  for (int seed = 1; seed <= setups; ++seed) {
    const sim::CameraSetup camera = sim::CameraSetup::random(seed);
    const sim::ProjectorSetup projector = flags.get_bool("square-projector") ? sim::ProjectorSetup{} : sim::ProjectorSetup::random(seed);
    const sim::Renderer renderer(camera, projector);
    std::vector<cv::Mat> frames;
    for (size_t i = 0; i < steps.size(); ++i) {
      const cv::Mat shown = patterns::render_pattern(steps[i].command, projector.size);
      frames.push_back(renderer.render(core::Stack{}, nuisance, &shown, seed * 100 + i).bgr);
    }
    const auto t0 = std::chrono::steady_clock::now();
    const cal::CalibrationResult result = cal::compute_calibration(frames, options, 0);
    corners.ms.push_back(std::chrono::duration<double, std::milli>(std::chrono::steady_clock::now() - t0).count());
    if (result.status != cal::CalibrationStatus::kOk) {
      ++rejected;
      std::printf("seed %d rejected: %s\n", seed, result.message.c_str());
      continue;
    }
    mapping_error(result.calibration, camera, projector, corners);
    corners.reported_max.push_back(result.calibration.reprojection_error_max_px);
    corners.near_shelf.push_back(result.near_shelf);
    {
      const cv::Matx33d m = board::colour_mixing(result.calibration);
      const double scale = std::max({projector.mixing(0, 0), projector.mixing(1, 1), projector.mixing(2, 2)});
      double worst = 0;
      for (int i = 0; i < 9; ++i) worst = std::max(worst, std::abs(m.val[i] - projector.mixing.val[i]) / scale);
      corners.colour.push_back(100 * worst);
      // Board frame: where the true origin (surface edge, surface top) lands, and how level the surface is.
      auto at = [&](double bx, double by) {
        const cv::Point2d r(camera.board.to_px_x(bx), camera.board.to_px_y(by));
        return board::camera_to_board(result.calibration, sim::rectified_to_camera(camera, r));
      };
      corners.shelf_found.push_back(result.shelf.found ? 1 : 0);
      corners.origin.push_back(cv::norm(at(0, 0)));
      if (verbose)
        std::printf("seed %d: shelf %s; the true origin lands at (%.4f, %.4f)\n", seed, result.shelf.message.c_str(), at(0, 0).x, at(0, 0).y);
      double level = 0;
      for (double bx = -4; bx <= 4; bx += 1) level = std::max(level, std::abs(at(bx, 0).y));
      corners.level.push_back(level);

      // Board x along the bottom row, -4..4 block lengths: as calibrated (its scale comes from the projector)
      // and after the correction from blocks (bricklayer-calibrate --scale-from-blocks: 10 frames of blocks
      // standing apart on the bottom row).
      const double worst_x = board_x_error(result.calibration, camera);
      corners.board_x.push_back(worst_x);
      detection::BlockScaleMeter meter(result.calibration);
      std::vector<cal::LineLean> leans;
      std::vector<cal::RefitFrame> stored;
      const double h = result.calibration.block_height;
      for (int f = 0; f < frames_count; ++f) {
        const int top = static_cast<int>(flags.get_int("towers"));
        const core::Stack blocks = top > 0 ? towers(f, top, layout, step) : blocks_apart(f, layout);
        if (seed == 1 && f == 0 && verbose) {
          std::printf("layout:");
          for (const core::Block& b : blocks.blocks) std::printf(" row %d %.3f..%.3f;", b.row, b.x, b.x + 1);
          std::printf("\n");
        }
        const cv::Mat frame = renderer.render(blocks, nuisance, nullptr, seed * 100 + 50 + f).bgr;
        stored.push_back({frame, cv::Mat(), cv::Size()});
        const size_t before = meter.measured().size();
        meter.add(frame);
        cv::Mat grey;
        cv::extractChannel(frame, grey, 1);  // green, as bricklayer-calibrate --scale-from-blocks
        for (size_t i = before; i < meter.measured().size(); ++i) {
          for (double x : {meter.measured()[i].left, meter.measured()[i].right})
            if (const auto lean = cal::measure_line_lean(grey, result.calibration, x, 0.2 * h, 0.75 * h)) leans.push_back({x, *lean});
        }
      }
      std::string why;
      const auto fit = meter.result(20, 0.01, &why);
      if (!fit) {
        std::printf("seed %d: board scale not measured: %s\n", seed, why.c_str());
      } else {
        const calibration_t corrected = detection::apply_board_correction(result.calibration, *fit);
        const double fixed = board_x_error(corrected, camera);
        corners.board_x_fixed.push_back(fixed);
        const BoardXGrid grid = board_x_grid(corrected, camera);
        const BoardXGrid raw = board_x_grid(result.calibration, camera);
        for (int b = 0; b < kBandCount; ++b) corners.band_fixed[b].push_back(grid.band[b]), corners.band_raw[b].push_back(raw.band[b]);
        for (int r = 0; r < kRowCount; ++r) corners.row_fixed[r].push_back(grid.row[r]);
        corners.whole_fixed.push_back(grid.whole);
        // The correction the truth asks for: the homography from the calibration's board frame to the true one.
        std::vector<cv::Point2d> from, to;
        for (double by = 0; by <= 3.2; by += 0.4)
          for (double bx = -4; bx <= 4; bx += 0.5) {
            const cv::Point2d cam = sim::rectified_to_camera(camera, {camera.board.to_px_x(bx), camera.board.to_px_y(by)});
            from.push_back(board::camera_to_board(result.calibration, cam));
            to.emplace_back(bx, by);
          }
        cv::Mat t = cv::findHomography(from, to, 0);
        t /= t.at<double>(2, 2);
        cal::FrameCorrection first;
        first.scale = fit->scale;
        first.keystone = fit->keystone;
        std::string lean_why;
        const auto lean = cal::fit_frame_lean(leans, fit->scale, fit->keystone, 8, &lean_why);
        if (lean) {
          first.shear = lean->shear;
          first.vertical_keystone = lean->vertical_keystone;
          const calibration_t leaned = first.apply(result.calibration);
          const BoardXGrid g2 = board_x_grid(leaned, camera);
          const cal::BoardXAccuracy bound = cal::board_x_accuracy(fit->residual, lean->residual);
          corners.bound_ratio.push_back(bound_ratio(leaned, camera, bound));
          corners.bound_far.push_back(bound.at(5.0, 9.5 * h));
          for (int b = 0; b < kBandCount; ++b) corners.band_lean[b].push_back(g2.band[b]);
          for (int r = 0; r < kRowCount; ++r) corners.row_lean[r].push_back(g2.row[r]);
          corners.whole_lean.push_back(g2.whole);
          if (verbose)
            std::printf("seed %d: lean of %d end lines (%d dropped, residual %.4f): shear %.4f vertical keystone %.5f; whole board %.4f, rows %.4f %.4f %.4f %.4f\n",
                        seed, lean->lines, lean->outliers, lean->residual, lean->shear, lean->vertical_keystone, g2.whole, g2.row[0], g2.row[1], g2.row[2], g2.row[3]);
        } else {
          // As bricklayer-calibrate does: the correction along the board only.
          std::printf("seed %d: frame lean not measured: %s\n", seed, lean_why.c_str());
          const cal::BoardXAccuracy bound = cal::board_x_accuracy(fit->residual, -1.0);
          corners.bound_ratio.push_back(bound_ratio(corrected, camera, bound));
          corners.bound_far.push_back(bound.at(5.0, 9.5 * h));
          for (int b = 0; b < kBandCount; ++b) corners.band_lean[b].push_back(grid.band[b]);
          for (int r = 0; r < kRowCount; ++r) corners.row_lean[r].push_back(grid.row[r]);
          corners.whole_lean.push_back(grid.whole);
        }
        corners.scale_error_first.push_back(first.scale / t.at<double>(0, 0) - 1.0);
        // The second pass: the same frames measured again on every row in the first pass's frame.
        const calibration_t first_calibration = first.apply(result.calibration);
        std::string refit_why;
        const auto refit = cal::refit_board_frame(first_calibration, stored, static_cast<int>(flags.get_int("max-row")), 20, 0.01, &refit_why);
        // What bricklayer-calibrate --scale-from-blocks does: the second pass where blocks stand on rows up the
        // board, else the first pass stands.
        if (!refit) {
          if (verbose) std::printf("seed %d: no second pass: %s\n", seed, refit_why.c_str());
          ++corners.refit_failed;
        }
        {
          const cal::FrameCorrection total = refit ? refit->correction.after(first) : first;
          const calibration_t final_calibration = total.apply(result.calibration);
          const BoardXGrid g3 = board_x_grid(final_calibration, camera);
          for (int b = 0; b < kBandCount; ++b) {
            corners.band_refit[b].push_back(g3.band[b]);
            for (int r = 0; r < kRowCount; ++r) corners.cell_refit[b][r].push_back(g3.cell[b][r]);
          }
          for (int r = 0; r < kRowCount; ++r) corners.row_refit[r].push_back(g3.row[r]);
          corners.whole_refit.push_back(g3.whole);
          const BoardXGrid floor = ideal_correction(result.calibration, camera, false);
          const BoardXGrid floor_origin = ideal_correction(result.calibration, camera, true);
          for (int b = 0; b < kBandCount; ++b)
            corners.band_floor[b].push_back(floor.band[b]), corners.band_floor_origin[b].push_back(floor_origin.band[b]);
          corners.whole_floor.push_back(floor.whole);
          corners.whole_floor_origin.push_back(floor_origin.whole);
          if (verbose)
            std::printf("seed %d: floor (the correction fitted to the truth) whole %.4f, x +4..+5 %.4f; origin free too %.4f, %.4f; origin error %.4f\n",
                        seed, floor.whole, floor.band[4], floor_origin.whole, floor_origin.band[4], corners.origin.back());
          corners.scale_error_refit.push_back(total.scale / t.at<double>(0, 0) - 1.0);
          const cal::BoardXAccuracy bound =
              refit ? cal::board_x_accuracy(refit->lengths.residual, refit->lean ? refit->lean->residual : -1.0, true)
                    : cal::board_x_accuracy(fit->residual, lean ? lean->residual : -1.0);
          corners.refit_bound_ratio.push_back(bound_ratio(final_calibration, camera, bound));
          corners.refit_bound_far.push_back(bound.at(5.0, 9.5 * h));
          if (verbose && refit)
            std::printf("seed %d: truth a %.4f b %.4f / d %.4f e %.4f / g %.5f h %.5f; first pass a %.4f b %.4f g %.5f h %.5f; second a %.4f b %.4f g %.5f h %.5f "
                        "(first residual %.4f%%; %d blocks to row %d, height span %.2f, length residual %.4f%%, %d leans residual %.4f%s); whole board %.4f, rows %.4f %.4f %.4f %.4f\n",
                        seed, t.at<double>(0, 0), t.at<double>(0, 1), t.at<double>(1, 0), t.at<double>(1, 1), t.at<double>(2, 0), t.at<double>(2, 1),
                        first.scale, first.shear, first.keystone, first.vertical_keystone, total.scale, total.shear, total.keystone,
                        total.vertical_keystone, 100 * fit->residual, refit->lengths.blocks, refit->highest_row, refit->height_span, 100 * refit->lengths.residual,
                        refit->lean ? refit->lean->lines : 0, refit->lean ? refit->lean->residual : -1.0, refit->lean ? "" : (" refused: " + refit->lean_why).c_str(),
                        g3.whole, g3.row[0], g3.row[1], g3.row[2], g3.row[3]);
        }
        if (verbose)
          std::printf("seed %d: whole board (x -5..5, rows 0/3/6/9) worst %.4f; by band %.4f %.4f %.4f %.4f %.4f (scale %.4f keystone %.5f)\n",
                      seed, grid.whole, grid.band[0], grid.band[1], grid.band[2], grid.band[3], grid.band[4], fit->scale, fit->keystone);
        if (verbose) std::printf("seed %d: board x error %.4f, after the correction from blocks %.4f\n", seed, worst_x, fixed);
      }
    }

    // Centres only: the same detections without the corners.
    auto points = cal::detect_marker_correspondences(frames[4], patterns::kMarkerSetGrid, projector.size);
    const auto more = cal::detect_marker_correspondences(frames[5], patterns::kMarkerSetShiftedGrid, projector.size);
    points.insert(points.end(), more.begin(), more.end());
    for (auto& p : points) p.has_corners = false;
    const auto t1 = std::chrono::steady_clock::now();
    const cal::LensFit centre_fit = cal::fit_lens_and_homography(points, camera.size);
    centres.ms.push_back(std::chrono::duration<double, std::milli>(std::chrono::steady_clock::now() - t1).count());
    mapping_error(from_fit(centre_fit, camera.size, projector.size), camera, projector, centres);

    if (flags.get_bool("gray-code")) {
      const auto dense = gray_code_points(renderer, nuisance, seed * 1000);
      const auto t2 = std::chrono::steady_clock::now();
      const cal::LensFit gray_fit = cal::fit_lens_and_homography(dense, camera.size);
      gray.ms.push_back(std::chrono::duration<double, std::milli>(std::chrono::steady_clock::now() - t2).count());
      mapping_error(from_fit(gray_fit, camera.size, projector.size), camera, projector, gray);
    }
  }
  auto report = [](const char* name, const Stats& s, const char* what_ms) {
    if (s.mean.empty()) return;
    std::printf("%-34s mean err median %.3f p99 %.3f | max err median %.3f p99 %.3f px | %s median %.1f p99 %.1f ms\n", name,
                percentile(s.mean, 0.5), percentile(s.mean, 0.99), percentile(s.max, 0.5), percentile(s.max, 0.99), what_ms,
                percentile(s.ms, 0.5), percentile(s.ms, 0.99));
  };
  std::printf("%d setups, nuisance %s, %d rejected; errors in projector pixels over the board grid\n", setups,
              flags.get("nuisance").c_str(), rejected);
  report("markers, corners + corner bias", corners, "compute_calibration");
  if (!corners.colour.empty()) {
    std::printf("colour mixing: worst entry error median %.2f%% p99 %.2f%% of the largest diagonal entry\n",
                percentile(corners.colour, 0.5), percentile(corners.colour, 0.99));
  }
  if (!corners.origin.empty()) {
    int found = 0;
    for (double f : corners.shelf_found) found += f > 0;
    std::printf("board frame: shelf found in %d of %zu; origin error median %.4f p99 %.4f, surface level within median %.4f p99 %.4f block lengths\n",
                found, corners.shelf_found.size(), percentile(corners.origin, 0.5), percentile(corners.origin, 0.99),
                percentile(corners.level, 0.5), percentile(corners.level, 0.99));
    std::printf("board x on the bottom row (-4..4), worst per setup: as calibrated median %.4f p99 %.4f; corrected from blocks (%zu setups) median %.4f p99 %.4f block lengths\n",
                percentile(corners.board_x, 0.5), percentile(corners.board_x, 0.99), corners.board_x_fixed.size(),
                percentile(corners.board_x_fixed, 0.5), percentile(corners.board_x_fixed, 0.99));
  }
  if (!corners.reported_max.empty()) {
    std::printf("calibrator's own largest marker error (what --max-point-error-px judges): median %.3f p99 %.3f px; markers left out at the shelf: median %.0f max %.0f\n",
                percentile(corners.reported_max, 0.5), percentile(corners.reported_max, 0.99),
                percentile(corners.near_shelf, 0.5), percentile(corners.near_shelf, 1.0));
  }
  if (!corners.whole_fixed.empty()) {
    std::printf("board x over the whole board after the correction from blocks (%zu setups), worst per setup, median / p99 block lengths:\n",
                corners.whole_fixed.size());
    for (int b = 0; b < kBandCount; ++b)
      std::printf("  x %+.0f..%+.0f (rows 0, 3, 6, 9): %.4f / %.4f   (as calibrated %.4f / %.4f)\n", kBands[b][0], kBands[b][1],
                  percentile(corners.band_fixed[b], 0.5), percentile(corners.band_fixed[b], 0.99),
                  percentile(corners.band_raw[b], 0.5), percentile(corners.band_raw[b], 0.99));
    for (int r = 0; r < kRowCount; ++r)
      std::printf("  row %d (x -5..5): %.4f / %.4f\n", kRows[r], percentile(corners.row_fixed[r], 0.5), percentile(corners.row_fixed[r], 0.99));
    std::printf("  whole board: %.4f / %.4f\n", percentile(corners.whole_fixed, 0.5), percentile(corners.whole_fixed, 0.99));
    if (!corners.whole_lean.empty()) {
      std::printf("board x over the whole board after the correction from block lengths and end-line lean (%zu setups; along the board only where the lean was refused), median / p99:\n",
                  corners.whole_lean.size());
      for (int b = 0; b < kBandCount; ++b)
        std::printf("  x %+.0f..%+.0f (rows 0, 3, 6, 9): %.4f / %.4f\n", kBands[b][0], kBands[b][1], percentile(corners.band_lean[b], 0.5),
                    percentile(corners.band_lean[b], 0.99));
      for (int r = 0; r < kRowCount; ++r)
        std::printf("  row %d (x -5..5): %.4f / %.4f\n", kRows[r], percentile(corners.row_lean[r], 0.5), percentile(corners.row_lean[r], 0.99));
      std::printf("  whole board: %.4f / %.4f\n", percentile(corners.whole_lean, 0.5), percentile(corners.whole_lean, 0.99));
    }
    if (!corners.whole_refit.empty()) {
      std::printf("board x over the whole board after the scale step (bricklayer-calibrate --scale-from-blocks: the second pass, every row "
                  "measured again, in %zu of %zu setups; the first pass where no blocks stand up the board), median / p99:\n",
                  corners.whole_refit.size() - corners.refit_failed, corners.whole_refit.size());
      for (int b = 0; b < kBandCount; ++b) {
        std::printf("  x %+.0f..%+.0f (rows 0, 3, 6, 9): %.4f / %.4f   by row", kBands[b][0], kBands[b][1], percentile(corners.band_refit[b], 0.5),
                    percentile(corners.band_refit[b], 0.99));
        for (int r = 0; r < kRowCount; ++r)
          std::printf("  %d: %.4f / %.4f", kRows[r], percentile(corners.cell_refit[b][r], 0.5), percentile(corners.cell_refit[b][r], 0.99));
        std::printf("\n");
      }
      for (int r = 0; r < kRowCount; ++r)
        std::printf("  row %d (x -5..5): %.4f / %.4f\n", kRows[r], percentile(corners.row_refit[r], 0.5), percentile(corners.row_refit[r], 0.99));
      std::printf("  whole board: %.4f / %.4f\n", percentile(corners.whole_refit, 0.5), percentile(corners.whole_refit, 0.99));
      std::printf("the floor: the correction's form fitted to the truth (origin as the shelf set it / origin free too), median / p99:");
      for (int b = 0; b < kBandCount; ++b)
        std::printf("  x %+.0f..%+.0f %.4f / %.4f (%.4f / %.4f);", kBands[b][0], kBands[b][1], percentile(corners.band_floor[b], 0.5),
                    percentile(corners.band_floor[b], 0.99), percentile(corners.band_floor_origin[b], 0.5), percentile(corners.band_floor_origin[b], 0.99));
      std::printf("  whole %.4f / %.4f (%.4f / %.4f)\n", percentile(corners.whole_floor, 0.5), percentile(corners.whole_floor, 0.99),
                  percentile(corners.whole_floor_origin, 0.5), percentile(corners.whole_floor_origin, 0.99));
      std::vector<double> abs_first, abs_refit;
      for (double e : corners.scale_error_first) abs_first.push_back(std::abs(e));
      for (double e : corners.scale_error_refit) abs_refit.push_back(std::abs(e));
      double mean_first = 0, mean_refit = 0;
      for (double e : corners.scale_error_first) mean_first += e / corners.scale_error_first.size();
      for (double e : corners.scale_error_refit) mean_refit += e / corners.scale_error_refit.size();
      std::printf("scale a against the truth (measured / true - 1): first pass mean %+.3f%%, |error| median %.3f%% max %.3f%%; after the scale step mean %+.3f%%, |error| median %.3f%% max %.3f%%\n",
                  100 * mean_first, 100 * percentile(abs_first, 0.5), 100 * percentile(abs_first, 1.0), 100 * mean_refit,
                  100 * percentile(abs_refit, 0.5), 100 * percentile(abs_refit, 1.0));
      int covered = 0;
      for (double r : corners.refit_bound_ratio) covered += r <= 1.0;
      std::printf("stated board x accuracy after the scale step: covers the whole-board grid in %d of %zu setups; largest error / bound median %.2f max %.2f; bound at x 5 row 9 median %.4f max %.4f\n",
                  covered, corners.refit_bound_ratio.size(), percentile(corners.refit_bound_ratio, 0.5), percentile(corners.refit_bound_ratio, 1.0),
                  percentile(corners.refit_bound_far, 0.5), percentile(corners.refit_bound_far, 1.0));
    }
    if (!corners.bound_ratio.empty()) {
      int covered = 0;
      for (double r : corners.bound_ratio) covered += r <= 1.0;
      std::printf("stated board x accuracy (calibration_t.board_x_accuracy): covers the whole-board grid in %d of %zu setups; largest error / bound median %.2f max %.2f; bound at x 5 row 9 median %.4f max %.4f\n",
                  covered, corners.bound_ratio.size(), percentile(corners.bound_ratio, 0.5), percentile(corners.bound_ratio, 1.0),
                  percentile(corners.bound_far, 0.5), percentile(corners.bound_far, 1.0));
    }
  }
  report("markers, centres only", centres, "fit");
  report("Gray code, dense (bits >= 2)", gray, "fit");
  return 0;
}

}  // namespace
}  // namespace bricklayer

int main(int argc, char** argv) { return bricklayer::run_main("bricklayer-bench-calibration", &bricklayer::Main, argc, argv); }
