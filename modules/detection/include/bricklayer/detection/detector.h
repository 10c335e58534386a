// Blocks from one camera frame: the seed paper's line scan made robust.
//
// Pipeline (all in the rectified board frame, see board_frame.h):
//   green channel -> rectify -> per row band: average along the line direction (upper and lower half)
//   -> subtract the projector's predicted leakage into green -> divide by a local background (1-D max
//   filter + box smoothing: shadows, gradients and vignetting cancel) -> dark dips with sub-pixel
//   centroids -> reject wide dips (out-of-focus hands and bodies), dips missing from one half of the
//   band (not a full-height line) and dips much fainter than the frame's median line (shadow-edge
//   slopes, leakage residue) -> pair lines one block length apart (a line may end one block and start
//   the next when blocks touch) -> block x from the pair's midpoint, row from the band.
// Pure function of (frame, calibration, projector image): deterministic, no state between frames.
// What a stage then makes of the blocks is its own: bricklayer-vision's publishing rules (no overlaps in
// a row, nothing cut by the image border) and temporal filter, the block-scale measurement's choice of
// blocks standing apart (block_scale.h).
#pragma once

#include <array>
#include <cstdint>
#include <vector>

#include <opencv2/core.hpp>

#include "bricklayer/calibration_t.hpp"
#include "bricklayer/board/board_geometry.h"
#include "bricklayer/detection/board_frame.h"

namespace bricklayer::detection {

struct DetectorConfig {
  double min_depth = 0.10;         // line darkness needed, as a fraction of the local background (0..1)
  double min_relative_depth = 0.5; // a line at least this fraction as dark as the frame's median line
  double max_line_width = 0.15;    // block lengths; wider dark dips are out-of-focus shapes, not lines
  double split_ratio = 1.4;        // a dip this much wider than a single line is two nearly touching lines
  double length_tolerance = 0.10;  // block lengths; how far a line pair may be from one block length apart
  double band_margin = 0.2;        // fraction of the block height ignored at the top and bottom of a row band
  double min_board_level = 12.0;   // mean green (0..255) of the board area below which it is not seen
  // Green row of the projector-to-camera colour mixing used before calibration (camera green per unit
  // projector B, G, R drive); calibration_t.colour_mixing replaces it.
  std::array<double, 3> default_green_mixing = {0.12, 0.60, 0.14};
  // End-line width in block lengths, used only when a frame has too few separate blocks to measure it.
  double line_width = 1.0 / 40.0;
  bool keep_lines = false;         // fill Detection::line_list (diagnostics)
  bool keep_profiles = false;      // fill Detection::profiles (the block-scale measurement fits end lines in them)
};

struct DetectedBlock {
  int32_t row = 0;
  double x = 0.0;                  // left end, block lengths from the surface edge
  double left_px = 0.0;            // left end in the rectified frame, pixels
  std::array<double, 4> corner_u{};  // camera pixels: left-bottom, right-bottom, right-top, left-top
  std::array<double, 4> corner_v{};
  double confidence = 0.0;         // 0..1
  // Centroids of the two end lines in the rectified frame, pixels (block_scale.h). Two touching blocks whose
  // end lines merged into one dip share it: the same value ends one and starts the other.
  double left_line_px = 0.0, right_line_px = 0.0;
};

struct Detection {
  enum Status { kOk = 0, kNoFrame = 1, kNoBoard = 2 };
  Status status = kOk;
  std::vector<DetectedBlock> blocks;  // sorted: bottom row first, left to right
  int lines = 0;                      // accepted line profiles
  int rejected_wide = 0;              // dark dips rejected as out of focus
  int rejected_faint = 0;             // dips much fainter than the frame's typical line (shadow edges, noise)
  struct Line {
    int row;
    double x_px, depth;  // centroid in the rectified frame; darkness relative to the background
  };
  std::vector<Line> line_list;        // every accepted line (only with DetectorConfig::keep_lines)
  // Per row band (only with DetectorConfig::keep_profiles): the green level across the rectified frame,
  // averaged over the band's height (less its margins), as the camera saw it, and the projector's
  // predicted leakage into it averaged alike (empty without a projector image): what the lines were found
  // in (level - leakage), before any normalisation.
  struct Profile {
    int row;
    std::vector<float> level, leakage;
  };
  std::vector<Profile> profiles;
};

// Sets left_px and the camera-pixel corners of a block from its row and x.
void place_block(DetectedBlock& block, const BoardFrame& frame);

// Whether a block lies whole inside a camera image of this size (and has a finite position): a block cut
// by the border was paired from a line the camera saw and one it only guessed, or its row band is cut off.
bool whole_in_view(const DetectedBlock& block, cv::Size image_size);

class Detector {
 public:
  explicit Detector(const BoardGeometry& geometry = {}, const DetectorConfig& config = {});

  // Switches to a calibrated board frame (remap tables built here, once). Throws std::invalid_argument
  // on an unusable calibration, keeping the previous one.
  void set_calibration(const calibration_t& calibration);
  const BoardFrame& frame() const { return frame_; }
  const DetectorConfig& config() const { return config_; }

  // What the projector shows (BGR, any size; `projector_size` is the projector's full resolution the
  // image was scaled from). Its predicted green leakage is subtracted from every following frame.
  void set_projector_image(const cv::Mat& bgr, cv::Size projector_size);
  void clear_projector_image();

  // Detects blocks in a BGR8 or GRAY8 frame. A frame whose size differs from the calibration's camera
  // size, or an empty one, gives kNoFrame.
  Detection detect(const cv::Mat& frame);

 private:
  struct Band {
    int row;
    int y0, y1, y2;  // upper half [y0, y1), lower half [y1, y2) in rectified pixels
  };
  void prepare(cv::Size rectified_size);
  struct Dip {
    double pos, depth, width;  // centroid (px), darkness (0..1), width at half depth (px)
  };
  void find_lines(const float* up, const float* lo, int width, std::vector<Dip>& dips, int& rejected);

  DetectorConfig config_;
  BoardGeometry default_geometry_;
  BoardFrame frame_;
  cv::Matx33d camera_to_projector_;
  cv::Size projector_size_;
  std::array<double, 3> green_mixing_;
  cv::Mat projector_image_;  // BGR as published
  // Cached per rectified size: bands, and the projector leakage averaged over each band half.
  cv::Size prepared_size_{-1, -1};
  std::vector<Band> bands_;
  std::vector<std::vector<float>> leak_up_, leak_lo_;
  bool leak_valid_ = false;
  // Scratch buffers reused across frames.
  std::vector<float> full_, bg_, mx_, d_, du_, dl_;
};

}  // namespace bricklayer::detection
