#include "bricklayer/patterns/patterns.h"

#include <opencv2/aruco.hpp>
#include <opencv2/imgproc.hpp>

#include <algorithm>
#include <cmath>
#include <stdexcept>
#include <string>

namespace bricklayer::patterns {
namespace {

int ceil_log2(int n) {
  int bits = 0;
  while ((1LL << bits) < n) ++bits;
  return bits;
}

void check_size(cv::Size size) {
  if (size.width < 16 || size.height < 16 || size.width > 16384 || size.height > 16384) {
    throw std::invalid_argument("projector size " + std::to_string(size.width) + "x" +
                                std::to_string(size.height) + " out of range (16..16384 per side)");
  }
}

uchar clamp_channel(int16_t value) { return static_cast<uchar>(std::clamp<int>(value, 0, 255)); }

cv::Ptr<cv::aruco::Dictionary> dictionary() {
  static const cv::Ptr<cv::aruco::Dictionary> dict = cv::aruco::getPredefinedDictionary(cv::aruco::DICT_4X4_250);
  return dict;
}

// Grid pitch and marker side (a multiple of the 6 cells of a 4x4 marker with its border, so
// drawMarker scales without resampling artefacts) for the registration grids.
struct GridSpec {
  int pitch;
  int side;
  int columns;
  int rows;
  double x0;  // top-left corner of the first marker
  double y0;
};

GridSpec grid_spec(cv::Size size) {
  GridSpec g{};
  g.pitch = std::max(12, static_cast<int>(std::ceil(std::max(size.width, size.height) / 10.5)));
  g.side = std::max(6, 6 * static_cast<int>(0.6 * g.pitch / 6.0));
  const double margin = 0.2 * g.pitch;
  g.columns = std::max(1, static_cast<int>((size.width - 2 * margin - g.side) / g.pitch) + 1);
  g.rows = std::max(1, static_cast<int>((size.height - 2 * margin - g.side) / g.pitch) + 1);
  g.x0 = std::floor((size.width - ((g.columns - 1) * g.pitch + g.side)) / 2.0);
  g.y0 = std::floor((size.height - ((g.rows - 1) * g.pitch + g.side)) / 2.0);
  return g;
}

MarkerPlacement place(int id, double x, double y, int side) {
  MarkerPlacement m;
  m.id = id;
  m.pixels = cv::Rect(static_cast<int>(x), static_cast<int>(y), side, side);
  const auto fx = static_cast<float>(m.pixels.x) - 0.5f;
  const auto fy = static_cast<float>(m.pixels.y) - 0.5f;
  const auto s = static_cast<float>(side);
  m.corners = {cv::Point2f(fx, fy), cv::Point2f(fx + s, fy), cv::Point2f(fx + s, fy + s), cv::Point2f(fx, fy + s)};
  return m;
}

struct ChessSpec {
  int square;
  cv::Size inner;
  int x0;
  int y0;
};

ChessSpec chess_spec(cv::Size size) {
  ChessSpec c{};
  c.inner = cv::Size(9, 6);  // 10 x 7 squares: asymmetric, so the corner order is unambiguous
  c.square = std::max(1, std::min(size.width / (c.inner.width + 3), size.height / (c.inner.height + 3)));
  c.x0 = (size.width - (c.inner.width + 1) * c.square) / 2;
  c.y0 = (size.height - (c.inner.height + 1) * c.square) / 2;
  return c;
}

}  // namespace

int gray_code_column_bits(cv::Size size) { return ceil_log2(size.width); }
int gray_code_row_bits(cv::Size size) { return ceil_log2(size.height); }
int gray_code_image_count(cv::Size size) { return 2 * (gray_code_column_bits(size) + gray_code_row_bits(size)); }

GrayCodeBit gray_code_bit(int index, cv::Size size) {
  const int count = gray_code_image_count(size);
  if (index < 0 || index >= count) {
    throw std::invalid_argument("Gray-code image index " + std::to_string(index) + " out of range 0.." +
                                std::to_string(count - 1) + " for this projector size");
  }
  const int column_bits = gray_code_column_bits(size);
  GrayCodeBit b;
  b.inverse = (index % 2) == 1;
  const int pair = index / 2;
  if (pair < column_bits) {
    b.columns = true;
    b.bit = column_bits - 1 - pair;  // most significant first, as OpenCV orders them
  } else {
    b.columns = false;
    b.bit = gray_code_row_bits(size) - 1 - (pair - column_bits);
  }
  return b;
}

std::vector<MarkerPlacement> marker_layout(int set, cv::Size size) {
  check_size(size);
  std::vector<MarkerPlacement> out;
  if (set == kMarkerSetGrid || set == kMarkerSetShiftedGrid) {
    const GridSpec g = grid_spec(size);
    const bool shifted = set == kMarkerSetShiftedGrid;
    const int columns = shifted ? g.columns - 1 : g.columns;
    const int rows = shifted ? g.rows - 1 : g.rows;
    const double offset = shifted ? g.pitch / 2.0 : 0.0;
    const int first_id = shifted ? 100 : 0;
    for (int r = 0; r < rows; ++r) {
      for (int c = 0; c < columns; ++c) {
        const int id = first_id + r * columns + c;
        if (id >= first_id + 100) break;  // grid_spec keeps sets below 100 markers; never overlap sets
        out.push_back(place(id, std::floor(g.x0 + offset) + c * g.pitch, std::floor(g.y0 + offset) + r * g.pitch, g.side));
      }
    }
  } else if (set == kMarkerSetSelfCheck) {
    const int side = std::max(6, 6 * (std::min(size.width, size.height) / 6 / 6));
    const double cx[5] = {0.25, 0.75, 0.5, 0.25, 0.75};
    const double cy[5] = {0.25, 0.25, 0.5, 0.75, 0.75};
    for (int i = 0; i < 5; ++i) {
      out.push_back(place(200 + i, std::floor(cx[i] * size.width - side / 2.0),
                          std::floor(cy[i] * size.height - side / 2.0), side));
    }
  } else {
    throw std::invalid_argument("marker set " + std::to_string(set) + " unknown (0.." +
                                std::to_string(kMarkerSetCount - 1) + ")");
  }
  return out;
}

cv::Size chessboard_inner_corners(cv::Size size) { return chess_spec(size).inner; }

std::vector<cv::Point2f> chessboard_corner_positions(cv::Size size) {
  const ChessSpec c = chess_spec(size);
  std::vector<cv::Point2f> out;
  for (int r = 1; r <= c.inner.height; ++r) {
    for (int col = 1; col <= c.inner.width; ++col) {
      // Pixel edges: the corner between squares sits at the boundary, i.e. half a pixel before
      // the first pixel of the next square in OpenCV's pixel-centre convention.
      out.emplace_back(static_cast<float>(c.x0 + col * c.square) - 0.5f, static_cast<float>(c.y0 + r * c.square) - 0.5f);
    }
  }
  return out;
}

cv::Mat render_pattern(const bricklayer::command_t& cmd, cv::Size size) {
  check_size(size);
  switch (cmd.pattern) {
    case bricklayer::command_t::PATTERN_SOLID:
      return cv::Mat(size, CV_8UC3, cv::Scalar(clamp_channel(cmd.blue), clamp_channel(cmd.green), clamp_channel(cmd.red)));

    case bricklayer::command_t::PATTERN_GRAY_CODE: {
      const GrayCodeBit b = gray_code_bit(cmd.index, size);
      cv::Mat gray(size, CV_8UC1);
      const int n = b.columns ? size.width : size.height;
      std::vector<uchar> value(n);
      for (int i = 0; i < n; ++i) {
        const int code = i ^ (i >> 1);
        const bool on = ((code >> b.bit) & 1) != 0;
        value[i] = (on != b.inverse) ? 255 : 0;
      }
      for (int y = 0; y < size.height; ++y) {
        auto* row = gray.ptr<uchar>(y);
        if (b.columns) {
          std::copy(value.begin(), value.end(), row);
        } else {
          std::fill(row, row + size.width, value[y]);
        }
      }
      cv::Mat bgr;
      cv::cvtColor(gray, bgr, cv::COLOR_GRAY2BGR);
      return bgr;
    }

    case bricklayer::command_t::PATTERN_MARKERS: {
      cv::Mat gray(size, CV_8UC1, cv::Scalar(255));
      for (const MarkerPlacement& m : marker_layout(cmd.index, size)) {
        const cv::Rect where = m.pixels;
        cv::Mat marker;
        cv::aruco::drawMarker(dictionary(), m.id, where.width, marker, 1);
        const cv::Rect clipped = where & cv::Rect(0, 0, size.width, size.height);
        if (clipped.area() == 0) continue;
        marker(cv::Rect(clipped.x - where.x, clipped.y - where.y, clipped.width, clipped.height)).copyTo(gray(clipped));
      }
      cv::Mat bgr;
      cv::cvtColor(gray, bgr, cv::COLOR_GRAY2BGR);
      return bgr;
    }

    case bricklayer::command_t::PATTERN_CHESSBOARD: {
      const ChessSpec c = chess_spec(size);
      cv::Mat gray(size, CV_8UC1, cv::Scalar(255));
      for (int r = 0; r <= c.inner.height; ++r) {
        for (int col = 0; col <= c.inner.width; ++col) {
          if ((r + col) % 2 == 0) {
            cv::rectangle(gray, cv::Rect(c.x0 + col * c.square, c.y0 + r * c.square, c.square, c.square),
                          cv::Scalar(0), cv::FILLED);
          }
        }
      }
      cv::Mat bgr;
      cv::cvtColor(gray, bgr, cv::COLOR_GRAY2BGR);
      return bgr;
    }

    default:
      throw std::invalid_argument("pattern " + std::to_string(cmd.pattern) +
                                  " unknown (PATTERN_SOLID=1, GRAY_CODE=2, MARKERS=3, CHESSBOARD=4)");
  }
}

}  // namespace bricklayer::patterns
