// The images bricklayer-projection shows on command_t SHOW_PATTERN, and what calibration knows about
// them (where every marker corner is, which Gray-code bit an image carries). One renderer, used by
// the projector and by calibration's tests, so the two can never disagree.
#pragma once

#include <opencv2/core.hpp>

#include <array>
#include <vector>

#include "bricklayer/command_t.hpp"

namespace bricklayer::patterns {

// Renders the pattern a SHOW_PATTERN command asks for, as a BGR (CV_8UC3) image of projector_size:
// - PATTERN_SOLID: the whole image in (cmd.red, cmd.green, cmd.blue), each clamped to 0..255.
// - PATTERN_GRAY_CODE: image number cmd.index of the Gray-code sequence, identical (as grey) to
//   cv::structured_light::GrayCodePattern::generate() for this size: for each column bit from the
//   most significant, the bit image then its inverse; then the same for the row bits.
//   cmd.index in [0, gray_code_image_count(size)); see gray_code_bit().
// - PATTERN_MARKERS: ArUco marker set number cmd.index (see marker_layout()), black markers on white.
// - PATTERN_CHESSBOARD: a chessboard of chessboard_inner_corners(size) inner corners on white.
// Throws std::invalid_argument on an unknown pattern, an index out of range or a size below 16x16.
cv::Mat render_pattern(const bricklayer::command_t& cmd, cv::Size projector_size);

// Number of Gray-code images for a projector size: 2 * (ceil(log2 width) + ceil(log2 height)),
// the same as cv::structured_light::GrayCodePattern::getNumberOfPatternImages().
int gray_code_image_count(cv::Size projector_size);
int gray_code_column_bits(cv::Size projector_size);  // ceil(log2 width)
int gray_code_row_bits(cv::Size projector_size);     // ceil(log2 height)

// What Gray-code image number index shows: a column (vertical stripes) or row bit, which bit
// (0 = least significant), and whether it is the inverse image.
struct GrayCodeBit {
  bool columns = true;
  int bit = 0;
  bool inverse = false;
};
GrayCodeBit gray_code_bit(int index, cv::Size projector_size);

// ArUco marker sets (dictionary DICT_4X4_250):
//   0: a dense grid covering the projector image (registration),
//   1: the same grid shifted by half a pitch (more correspondences),
//   2: five large markers (four near the corners, one in the centre) for the drift self-check.
inline constexpr int kMarkerSetGrid = 0;
inline constexpr int kMarkerSetShiftedGrid = 1;
inline constexpr int kMarkerSetSelfCheck = 2;
inline constexpr int kMarkerSetCount = 3;

struct MarkerPlacement {
  int id = 0;
  cv::Rect pixels;  // the projector pixels the marker (with its black border) covers
  // Outer corners of the marker's black square in projector pixel coordinates (pixel centres at
  // integers, so the edge of pixel column x is at x - 0.5), in ArUco's order (top-left, top-right,
  // bottom-right, bottom-left), the same order and convention cv::aruco::detectMarkers reports.
  std::array<cv::Point2f, 4> corners;
};
std::vector<MarkerPlacement> marker_layout(int set, cv::Size projector_size);

// Inner corners (columns, rows) of the chessboard pattern for a projector size.
cv::Size chessboard_inner_corners(cv::Size projector_size);
// Inner corner positions in projector pixels, row by row from the top-left.
std::vector<cv::Point2f> chessboard_corner_positions(cv::Size projector_size);

}  // namespace bricklayer::patterns
