// Board geometry in rectified board pixels, for a camera looking straight at the board (or after
// calibration's rectification): where the surface edge and top are, and how big a block is.
// This is the --board FILE of bricklayer-vision and the layout simcam renders.
// Part of bricklayer::board (bricklayer::board_geometry alone needs no OpenCV). BoardGeometry and the
// default setup stay in namespace bricklayer, beside the message types: every stage speaks them.
#pragma once

#include <array>
#include <string>

namespace bricklayer {

// The uncalibrated default setup, shared by simcam (what it renders), vision (what it assumes) and
// projection (where it draws) so the demo lines up before any calibration: a 640x480 camera looking
// straight at the board with the BoardGeometry defaults below, and a 1024x768 projector whose image
// covers exactly the camera's view (projector pixel = 1.6 x camera pixel).
inline constexpr int kDefaultCameraWidth = 640;
inline constexpr int kDefaultCameraHeight = 480;
inline constexpr int kDefaultProjectorWidth = 1024;
inline constexpr int kDefaultProjectorHeight = 768;
inline constexpr std::array<double, 9> kDefaultCameraToProjector = {1.6, 0, 0, 0, 1.6, 0, 0, 0, 1};

struct BoardGeometry {
  double edge_x_px = 320.0;       // pixel column of the surface edge
  double surface_y_px = 440.0;    // pixel row of the surface top (rows grow downwards)
  double block_length_px = 60.0;  // a block's length in pixels
  double block_height_px = 20.0;  // a block's height in pixels

  // Board coordinates (block lengths, x right from the edge, y up from the surface) <-> pixels.
  double to_px_x(double x_blocks) const { return edge_x_px + x_blocks * block_length_px; }
  double to_px_y(double y_blocks) const { return surface_y_px - y_blocks * block_length_px; }
  double from_px_x(double u) const { return (u - edge_x_px) / block_length_px; }
  double row_top_px(int row) const { return surface_y_px - (row + 1) * block_height_px; }

  // Row-major homography from (rectified) camera pixels to board coordinates, matching to_px_*.
  std::array<double, 9> camera_to_board() const {
    return {1.0 / block_length_px, 0, -edge_x_px / block_length_px,
            0, -1.0 / block_length_px, surface_y_px / block_length_px,
            0, 0, 1};
  }
};

// Reads {"edge_x_px":..,"surface_y_px":..,"block_length_px":..,"block_height_px":..}.
// Throws std::runtime_error naming the missing/unknown key or bad value (every key is required).
BoardGeometry load_board_geometry(const std::string& path);
BoardGeometry parse_board_geometry(const std::string& json_text);

}  // namespace bricklayer
