// The simulated camera's renderer: a stack of blocks against the frosted-glass board, seen by a
// webcam behind the board, optionally lit by the projector. Used by bricklayer-simcam (frames on the
// bus), by vision's accuracy benchmark and tests, and by calibration's random-setup tests.
//
// Coordinates (OpenCV convention: pixel centres at integer coordinates, pixel (i, j) covers
// [i-0.5, i+0.5] x [j-0.5, j+0.5]):
//   board coordinates   block lengths, x right from the surface edge, y up from the surface
//   rectified pixels    the board layout of BoardGeometry (camera looking straight at the board)
//   ideal camera pixels rectified pixels through CameraSetup::rectified_to_camera (a homography)
//   camera pixels       ideal camera pixels through the lens distortion (camera_matrix, distortion)
//   projector pixels    through ProjectorSetup::projector_to_rectified to rectified pixels
//
// The scene (what the camera sees):
//   - the frosted glass, bright and slightly uneven (low-frequency brightness bumps);
//   - the stacking surface (a shelf) as a darker band below surface_y_px, for x <= edge;
//   - every block a faintly tinted transparent rectangle with a faint outline: row r spans heights
//     [r*h, (r+1)*h] above the surface (h = board.block_height_px), x from its left end over one
//     block length;
//   - at both ends of every block a thin black vertical line of the full block height and
//     line_width block lengths wide, lying INSIDE the block: the left line covers [x, x + w], the
//     right line [x + 1 - w, x + 1] (block lengths). Line centres are w/2 inside the block's ends;
//     the truth corners below are the block's true ends.
// Sharp geometry is rendered with exact area coverage of every pixel (the limit of supersampling
// and INTER_AREA downsampling, so sub-pixel positions are exact), then taken through the homography
// and lens distortion (bilinear remap; skipped when both are identity), lit (gradient, vignetting,
// soft multiplicative shadows of a player, out-of-focus dark blobs), lit by the projector through
// the colour mixing matrix, blurred, given brightness-dependent noise and optionally JPEG-compressed.
// Deterministic: the same inputs and seed give bit-identical frames.
#pragma once

#include <array>
#include <cstdint>
#include <memory>
#include <string>
#include <vector>

#include <opencv2/core.hpp>

#include "bricklayer/board/board_geometry.h"
#include "bricklayer/core/stack.h"

namespace bricklayer::simcam {

// Everything in the image that is not the blocks. All fields zero = a clean, ideal frame.
struct Nuisance {
  std::string name = "clean";
  double gradient = 0.0;         // room-light gradient: ambient light varies by +-gradient/2 across the frame (1 at the centre)
  double vignetting = 0.0;       // lens falloff: brightness at the frame corners is 1 - vignetting (1 at the centre)
  double unevenness = 0.03;      // frosted-glass brightness bumps, relative amplitude
  double shadow_strength = 0.0;  // 0..1: fraction of ambient light removed at the core of a player's shadow
  int shadow_count = 0;          // soft shadows of hand / arm / body (elongated, very soft edges)
  double blob_strength = 0.0;    // 0..1: darkening at the core of an out-of-focus dark blob
  int blob_count = 0;            // hands / bodies away from the board: round dark blurred blobs
  double blur_sigma = 0.0;       // optical blur, Gaussian sigma in camera pixels (0 = none)
  double noise = 0.0;            // noise std-dev in 8-bit levels at full brightness; scales with sqrt(brightness)
  double read_noise = 0.0;       // brightness-independent noise std-dev, 8-bit levels
  int jpeg_quality = 0;          // 0 = no compression round trip, else 1..100 (artefacts as the bus would carry)
  // Which shadows, blobs and bumps: 0 = derived from render()'s seed. Keep it fixed and advance
  // time_s to move the shadows smoothly along their seeded paths (simcam does).
  uint64_t layout_seed = 0;
  double time_s = 0.0;

  // Named levels: 0 "clean", 1 "mild", 2 "strong", 3 "harsh". Throws std::invalid_argument otherwise.
  static Nuisance level(int level);
  // By name ("clean", "mild", "strong", "harsh") or digit; throws std::invalid_argument naming the choices.
  static Nuisance named(const std::string& name);
};

struct CameraSetup {
  cv::Size size{kDefaultCameraWidth, kDefaultCameraHeight};
  BoardGeometry board;  // layout in rectified pixels (defaults = the uncalibrated default setup)
  double line_width = 1.0 / 40.0;  // end-line width, block lengths
  double board_brightness = 170.0; // green level of the bare board at the frame centre (exposure locked), 8-bit
  cv::Matx33d rectified_to_camera = cv::Matx33d::eye();  // rectified -> ideal camera pixels
  // Lens: ideal camera pixels -> normalised by camera_matrix -> distorted (OpenCV model k1,k2,p1,p2,k3)
  // -> camera pixels. Zero distortion (the default) makes the lens an identity.
  cv::Matx33d camera_matrix{560, 0, (kDefaultCameraWidth - 1) / 2.0, 0, 560, (kDefaultCameraHeight - 1) / 2.0, 0, 0, 1};
  cv::Vec<double, 5> distortion{0, 0, 0, 0, 0};

  // The default setup scaled to another frame size (board layout and camera matrix scale with the width;
  // the surface stays 40/480 of the height above the bottom). default_for({640,480}) == CameraSetup{}.
  static CameraSetup default_for(cv::Size size);
  // A plausible webcam pose around the default: tilt (perspective), rotation up to ~3 degrees, scale
  // 0.9..1.1, shift up to ~20 px, radial distortion k1 in [-0.12, -0.03]. Deterministic per seed.
  static CameraSetup random(uint64_t seed, cv::Size size = {kDefaultCameraWidth, kDefaultCameraHeight});

  bool has_lens_distortion() const;
  bool is_identity() const;  // no homography, no distortion: rendering skips the remap
};

struct ProjectorSetup {
  cv::Size size{kDefaultProjectorWidth, kDefaultProjectorHeight};
  // Projector pixels -> rectified pixels. Default: the inverse of the default camera->projector
  // scale (board.h kDefaultCameraToProjector), i.e. rectified = projector / 1.6.
  cv::Matx33d projector_to_rectified{1 / 1.6, 0, 0, 0, 1 / 1.6, 0, 0, 0, 1};
  // Colour mixing: camera BGR levels added per projector BGR level on the bare board at the frame
  // centre (before vignetting, noise, blur). Column j = camera response to projector channel j (B, G, R).
  // Red and blue leak into green, as real spectra overlap.
  cv::Matx33d mixing{0.55, 0.10, 0.02,
                     0.12, 0.60, 0.14,
                     0.02, 0.08, 0.58};
  cv::Vec3d ambient{4.0, 4.0, 4.0};  // camera BGR levels the projector adds while showing black (inside its image)
  // How much a black end line absorbs projector light relative to ambient light (the projector's
  // light is scattered by the glass before it meets the line): 1 = as dark as in room light.
  double line_absorption = 0.6;

  // A plausible projector placement around the default (small rotation/scale/shift/keystone, still
  // covering the camera's view) and a random mixing matrix (diagonal 0.45..0.7, red->green and
  // blue->green 0.05..0.2, other leaks 0..0.05). Deterministic per seed.
  static ProjectorSetup random(uint64_t seed);
};

// A block as rendered: the truth to compare vision against.
struct TrueBlock {
  int64_t id = 0;
  int32_t row = 0;
  double x = 0.0;  // left end, block lengths from the surface edge ((stack x - table_edge) / block_length)
  // Camera pixels (distorted), order as block_t: left-bottom, right-bottom, right-top, left-top.
  std::array<cv::Point2d, 4> corners;
  bool visible = false;  // all four corners inside the frame
};

struct Rendered {
  cv::Mat bgr;                  // CV_8UC3 camera frame (after the JPEG round trip when jpeg_quality > 0)
  std::vector<TrueBlock> truth; // same order as the stack's blocks
};

// Point mappings (exact, the same model render() uses). Camera pixels are distorted pixels.
cv::Point2d rectified_to_camera(const CameraSetup& camera, cv::Point2d rectified);
// Inverse (iterative undistortion, converges to ~1e-9 px for webcam-like distortion).
cv::Point2d camera_to_rectified(const CameraSetup& camera, cv::Point2d camera_px);
cv::Point2d board_to_rectified(const BoardGeometry& board, cv::Point2d board_xy);  // block lengths -> px
cv::Point2d projector_to_camera(const CameraSetup& camera, const ProjectorSetup& projector, cv::Point2d projector_px);
cv::Point2d camera_to_projector(const CameraSetup& camera, const ProjectorSetup& projector, cv::Point2d camera_px);

// The truth for a stack without rendering pixels.
std::vector<TrueBlock> true_blocks(const core::Stack& stack, const CameraSetup& camera);

// A renderer for one camera/projector setup: precomputes the remap tables once (use it for many
// frames). Thread-compatible (one render() at a time per instance).
class Renderer {
 public:
  explicit Renderer(const CameraSetup& camera = {}, const ProjectorSetup& projector = {});
  ~Renderer();
  Renderer(Renderer&&) noexcept;
  Renderer& operator=(Renderer&&) noexcept;

  // projector_image: BGR (CV_8UC3) what the projector shows, any size (stretched over the projector's
  // full size), or null for projector off (then the projector adds nothing, not even ambient).
  // Throws std::invalid_argument for a non-CV_8UC3 projector image or a stack with non-finite numbers.
  Rendered render(const core::Stack& stack, const Nuisance& nuisance, const cv::Mat* projector_image,
                  uint64_t seed) const;

  const CameraSetup& camera() const;
  const ProjectorSetup& projector() const;

 private:
  struct Impl;
  std::unique_ptr<Impl> impl_;
};

// One-shot convenience (builds a Renderer each call; use Renderer for many frames).
Rendered render(const core::Stack& stack, const CameraSetup& camera, const Nuisance& nuisance,
                const cv::Mat* projector_image, const ProjectorSetup& projector, uint64_t seed);

}  // namespace bricklayer::simcam
