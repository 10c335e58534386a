#include "bricklayer/simcam/render.h"

#include <algorithm>
#include <cmath>
#include <stdexcept>
#include <string>

#include <opencv2/imgcodecs.hpp>
#include <opencv2/imgproc.hpp>

#include "bricklayer/core/splitmix64.h"

namespace bricklayer::simcam {
namespace {

// ---------- deterministic random numbers (no std:: distributions: identical on every platform) ----------

using core::splitmix64;

class Random {
 public:
  explicit Random(uint64_t seed) : state_(seed * 0xD1B54A32D192ED03ULL + 0x1234567ULL) {}
  uint64_t next() { return splitmix64(state_); }
  double uniform() { return core::unit_double(next()); }  // [0, 1)
  double uniform(double lo, double hi) { return lo + (hi - lo) * uniform(); }
  int integer(int lo, int hi) { return lo + static_cast<int>(next() % static_cast<uint64_t>(hi - lo + 1)); }

 private:
  uint64_t state_;
};

// 65536 standard normal samples (Box-Muller over splitmix64), built once: per-pixel noise is a table lookup.
const std::vector<float>& normal_table() {
  static const std::vector<float> table = [] {
    std::vector<float> t(1 << 16);
    Random r(20241122);
    for (size_t i = 0; i < t.size(); i += 2) {
      double u1 = std::max(r.uniform(), 1e-300), u2 = r.uniform();
      double rad = std::sqrt(-2.0 * std::log(u1));
      t[i] = static_cast<float>(rad * std::cos(2 * M_PI * u2));
      t[i + 1] = static_cast<float>(rad * std::sin(2 * M_PI * u2));
    }
    return t;
  }();
  return table;
}

// ---------- geometry ----------

cv::Point2d apply_h(const cv::Matx33d& h, cv::Point2d p) {
  cv::Vec3d q = h * cv::Vec3d(p.x, p.y, 1.0);
  return {q[0] / q[2], q[1] / q[2]};
}

// Ideal (undistorted) camera pixel -> camera pixel, OpenCV's distortion model.
cv::Point2d distort(const CameraSetup& c, cv::Point2d p) {
  const auto& k = c.camera_matrix;
  const auto& d = c.distortion;
  double x = (p.x - k(0, 2)) / k(0, 0), y = (p.y - k(1, 2)) / k(1, 1);
  double r2 = x * x + y * y;
  double radial = 1 + d[0] * r2 + d[1] * r2 * r2 + d[4] * r2 * r2 * r2;
  double xd = x * radial + 2 * d[2] * x * y + d[3] * (r2 + 2 * x * x);
  double yd = y * radial + d[2] * (r2 + 2 * y * y) + 2 * d[3] * x * y;
  return {xd * k(0, 0) + k(0, 2), yd * k(1, 1) + k(1, 2)};
}

// Camera pixel -> ideal pixel: Newton's method on distort() with a numeric Jacobian.
cv::Point2d undistort(const CameraSetup& c, cv::Point2d q) {
  if (!c.has_lens_distortion()) return q;
  cv::Point2d p = q;
  for (int it = 0; it < 20; ++it) {
    cv::Point2d f = distort(c, p) - q;
    if (std::abs(f.x) < 1e-10 && std::abs(f.y) < 1e-10) break;
    const double e = 1e-4;
    cv::Point2d fx = (distort(c, p + cv::Point2d(e, 0)) - distort(c, p - cv::Point2d(e, 0))) / (2 * e);
    cv::Point2d fy = (distort(c, p + cv::Point2d(0, e)) - distort(c, p - cv::Point2d(0, e))) / (2 * e);
    double det = fx.x * fy.y - fy.x * fx.y;
    if (std::abs(det) < 1e-12) break;
    p.x -= (fy.y * f.x - fy.x * f.y) / det;
    p.y -= (-fx.y * f.x + fx.x * f.y) / det;
  }
  return p;
}

double overlap(double a0, double a1, double b0, double b1) {
  return std::max(0.0, std::min(a1, b1) - std::max(a0, b0));
}

// Multiplies the pixels of img (CV_32FC3, canvas pixel i covers [i-0.5, i+0.5] around canvas coordinate i)
// by 1 - coverage * (1 - t) for the rectangle [x0,x1] x [y0,y1] in canvas coordinates: exact area
// coverage, so edges land at their sub-pixel positions.
void paint_rect(cv::Mat& img, double x0, double x1, double y0, double y1, cv::Vec3f t) {
  if (!(x1 > x0 && y1 > y0)) return;
  int i0 = std::max(0, static_cast<int>(std::floor(x0 + 0.5)));
  int i1 = std::min(img.cols - 1, static_cast<int>(std::floor(x1 + 0.5)));
  int j0 = std::max(0, static_cast<int>(std::floor(y0 + 0.5)));
  int j1 = std::min(img.rows - 1, static_cast<int>(std::floor(y1 + 0.5)));
  if (i0 > i1 || j0 > j1) return;
  thread_local std::vector<float> cx;
  cx.resize(static_cast<size_t>(i1 - i0 + 1));
  for (int i = i0; i <= i1; ++i) cx[static_cast<size_t>(i - i0)] = static_cast<float>(overlap(i - 0.5, i + 0.5, x0, x1));
  const cv::Vec3f one_minus_t(1 - t[0], 1 - t[1], 1 - t[2]);
  for (int j = j0; j <= j1; ++j) {
    float cy = static_cast<float>(overlap(j - 0.5, j + 0.5, y0, y1));
    if (cy <= 0) continue;
    cv::Vec3f* row = img.ptr<cv::Vec3f>(j);
    for (int i = i0; i <= i1; ++i) {
      float c = cy * cx[static_cast<size_t>(i - i0)];
      cv::Vec3f& p = row[i];
      p[0] *= 1 - c * one_minus_t[0];
      p[1] *= 1 - c * one_minus_t[1];
      p[2] *= 1 - c * one_minus_t[2];
    }
  }
}

// Reflectances (B, G, R) of the scene's materials, relative to the bare frosted glass.
const cv::Vec3f kShelf(0.40f, 0.45f, 0.50f);
const cv::Vec3f kBlockTint(0.95f, 0.94f, 0.92f);
const cv::Vec3f kOutline(0.82f, 0.82f, 0.82f);
const cv::Vec3f kLine(0.07f, 0.07f, 0.07f);
const double kOutlineWidthPx = 0.6;
// Colour of the room light through the glass, relative to green (white balance locked slightly cool).
const cv::Vec3f kAmbientColour(1.03f, 1.0f, 0.93f);

double block_x(const core::Stack& s, const core::Block& b) { return (b.x - s.table_edge) / s.block_length; }

void check_stack(const core::Stack& s) {
  if (!std::isfinite(s.block_length) || s.block_length <= 0 || !std::isfinite(s.table_edge))
    throw std::invalid_argument("simcam render: stack block_length must be positive and table_edge finite");
  for (const auto& b : s.blocks) {
    if (!std::isfinite(b.x))
      throw std::invalid_argument("simcam render: block " + std::to_string(b.id) + " has a non-finite x");
    if (b.row < 0) throw std::invalid_argument("simcam render: block " + std::to_string(b.id) + " has a negative row");
  }
}

}  // namespace

// ---------- Nuisance ----------

Nuisance Nuisance::level(int level) {
  Nuisance n;
  switch (level) {
    case 0:
      n.name = "clean";
      return n;
    case 1:
      n.name = "mild";
      n.gradient = 0.15; n.vignetting = 0.10; n.unevenness = 0.05;
      n.shadow_strength = 0.30; n.shadow_count = 1;
      n.blur_sigma = 0.6; n.noise = 1.5; n.read_noise = 0.5; n.jpeg_quality = 95;
      return n;
    case 2:
      n.name = "strong";
      n.gradient = 0.30; n.vignetting = 0.20; n.unevenness = 0.07;
      n.shadow_strength = 0.50; n.shadow_count = 2; n.blob_strength = 0.5; n.blob_count = 1;
      n.blur_sigma = 0.9; n.noise = 2.5; n.read_noise = 0.8; n.jpeg_quality = 90;
      return n;
    case 3:
      n.name = "harsh";
      n.gradient = 0.45; n.vignetting = 0.30; n.unevenness = 0.10;
      n.shadow_strength = 0.65; n.shadow_count = 3; n.blob_strength = 0.65; n.blob_count = 2;
      n.blur_sigma = 1.2; n.noise = 3.5; n.read_noise = 1.0; n.jpeg_quality = 80;
      return n;
    default:
      throw std::invalid_argument("nuisance level must be 0..3 (clean, mild, strong, harsh), got " + std::to_string(level));
  }
}

Nuisance Nuisance::named(const std::string& name) {
  static const char* names[] = {"clean", "mild", "strong", "harsh"};
  for (int i = 0; i < 4; ++i)
    if (name == names[i] || name == std::to_string(i)) return level(i);
  throw std::invalid_argument("unknown nuisance level '" + name + "' (expected clean, mild, strong, harsh or 0..3)");
}

// ---------- setups ----------

CameraSetup CameraSetup::default_for(cv::Size size) {
  CameraSetup c;
  double s = size.width / static_cast<double>(kDefaultCameraWidth);
  c.size = size;
  c.board.edge_x_px = c.board.edge_x_px * s;
  c.board.block_length_px *= s;
  c.board.block_height_px *= s;
  c.board.surface_y_px = size.height - (kDefaultCameraHeight - BoardGeometry{}.surface_y_px) * s;
  c.camera_matrix = cv::Matx33d(560 * s, 0, (size.width - 1) / 2.0, 0, 560 * s, (size.height - 1) / 2.0, 0, 0, 1);
  return c;
}

CameraSetup CameraSetup::random(uint64_t seed, cv::Size size) {
  CameraSetup c = default_for(size);
  Random r(seed ^ 0xCA3E5E7ULL);
  const double cx = (size.width - 1) / 2.0, cy = (size.height - 1) / 2.0;
  const double sw = size.width / static_cast<double>(kDefaultCameraWidth);
  double angle = r.uniform(-3.0, 3.0) * M_PI / 180.0;
  double scale = r.uniform(0.9, 1.1);
  double tx = r.uniform(-20, 20) * sw, ty = r.uniform(-20, 20) * sw;
  double px = r.uniform(-1.5e-4, 1.5e-4) / sw, py = r.uniform(-1.5e-4, 1.5e-4) / sw;  // keystone
  cv::Matx33d to_centre(1, 0, -cx, 0, 1, -cy, 0, 0, 1);
  cv::Matx33d rot(scale * std::cos(angle), -scale * std::sin(angle), 0, scale * std::sin(angle), scale * std::cos(angle), 0, 0, 0, 1);
  cv::Matx33d persp(1, 0, 0, 0, 1, 0, px, py, 1);
  cv::Matx33d back(1, 0, cx + tx, 0, 1, cy + ty, 0, 0, 1);
  c.rectified_to_camera = back * persp * rot * to_centre;
  double f = 560 * sw * r.uniform(0.92, 1.08);
  c.camera_matrix = cv::Matx33d(f, 0, cx + r.uniform(-8, 8) * sw, 0, f, cy + r.uniform(-8, 8) * sw, 0, 0, 1);
  c.distortion = cv::Vec<double, 5>(r.uniform(-0.12, -0.03), r.uniform(-0.02, 0.05), r.uniform(-1e-3, 1e-3),
                                    r.uniform(-1e-3, 1e-3), 0.0);
  return c;
}

bool CameraSetup::has_lens_distortion() const {
  for (int i = 0; i < 5; ++i)
    if (distortion[i] != 0.0) return true;
  return false;
}

bool CameraSetup::is_identity() const {
  return !has_lens_distortion() && rectified_to_camera == cv::Matx33d::eye();
}

ProjectorSetup ProjectorSetup::random(uint64_t seed) {
  ProjectorSetup p;
  Random r(seed ^ 0x9F0EC70ULL);
  const double pcx = (p.size.width - 1) / 2.0, pcy = (p.size.height - 1) / 2.0;
  const double rcx = (kDefaultCameraWidth - 1) / 2.0, rcy = (kDefaultCameraHeight - 1) / 2.0;
  double angle = r.uniform(-2.0, 2.0) * M_PI / 180.0;
  double scale = r.uniform(1.08, 1.18) / 1.6;  // a little larger than the camera's view, so it stays covered
  double tx = r.uniform(-12, 12), ty = r.uniform(-12, 12);
  double kx = r.uniform(-8e-5, 8e-5), ky = r.uniform(-8e-5, 8e-5);
  cv::Matx33d to_centre(1, 0, -pcx, 0, 1, -pcy, 0, 0, 1);
  cv::Matx33d keystone(1, 0, 0, 0, 1, 0, kx, ky, 1);
  cv::Matx33d rot(scale * std::cos(angle), -scale * std::sin(angle), 0, scale * std::sin(angle), scale * std::cos(angle), 0, 0, 0, 1);
  cv::Matx33d back(1, 0, rcx + tx, 0, 1, rcy + ty, 0, 0, 1);
  p.projector_to_rectified = back * rot * keystone * to_centre;
  p.mixing = cv::Matx33d(r.uniform(0.45, 0.7), r.uniform(0.0, 0.05), r.uniform(0.0, 0.05),
                         r.uniform(0.05, 0.2), r.uniform(0.45, 0.7), r.uniform(0.05, 0.2),
                         r.uniform(0.0, 0.05), r.uniform(0.0, 0.05), r.uniform(0.45, 0.7));
  double black = r.uniform(2.0, 8.0);
  p.ambient = cv::Vec3d(black, black, black);
  return p;
}

// ---------- point mappings ----------

cv::Point2d rectified_to_camera(const CameraSetup& camera, cv::Point2d rectified) {
  return distort(camera, apply_h(camera.rectified_to_camera, rectified));
}

cv::Point2d camera_to_rectified(const CameraSetup& camera, cv::Point2d camera_px) {
  return apply_h(camera.rectified_to_camera.inv(), undistort(camera, camera_px));
}

cv::Point2d board_to_rectified(const BoardGeometry& board, cv::Point2d board_xy) {
  return {board.to_px_x(board_xy.x), board.to_px_y(board_xy.y)};
}

cv::Point2d projector_to_camera(const CameraSetup& camera, const ProjectorSetup& projector, cv::Point2d projector_px) {
  return rectified_to_camera(camera, apply_h(projector.projector_to_rectified, projector_px));
}

cv::Point2d camera_to_projector(const CameraSetup& camera, const ProjectorSetup& projector, cv::Point2d camera_px) {
  return apply_h(projector.projector_to_rectified.inv(), camera_to_rectified(camera, camera_px));
}

std::vector<TrueBlock> true_blocks(const core::Stack& stack, const CameraSetup& camera) {
  check_stack(stack);
  const BoardGeometry& g = camera.board;
  std::vector<TrueBlock> out;
  out.reserve(stack.blocks.size());
  for (const auto& b : stack.blocks) {
    TrueBlock t;
    t.id = b.id;
    t.row = b.row;
    t.x = block_x(stack, b);
    double u0 = g.to_px_x(t.x), u1 = g.to_px_x(t.x + 1.0);
    double v_bottom = g.surface_y_px - b.row * g.block_height_px, v_top = v_bottom - g.block_height_px;
    const cv::Point2d rect[4] = {{u0, v_bottom}, {u1, v_bottom}, {u1, v_top}, {u0, v_top}};
    t.visible = true;
    for (int k = 0; k < 4; ++k) {
      t.corners[static_cast<size_t>(k)] = rectified_to_camera(camera, rect[k]);
      const cv::Point2d& c = t.corners[static_cast<size_t>(k)];
      if (!(c.x >= -0.5 && c.y >= -0.5 && c.x <= camera.size.width - 0.5 && c.y <= camera.size.height - 0.5)) t.visible = false;
    }
    out.push_back(t);
  }
  return out;
}

// ---------- Renderer ----------

struct Renderer::Impl {
  CameraSetup camera;
  ProjectorSetup projector;
  bool identity = true;
  // Rectified canvas: canvas pixel (i, j) is rectified pixel (i + origin.x, j + origin.y).
  cv::Point origin{0, 0};
  cv::Size canvas_size;
  cv::Mat scene_map_x, scene_map_y;  // CV_32F: camera pixel -> canvas coordinates
  cv::Mat proj_x, proj_y;            // CV_32F: camera pixel -> projector pixel
  cv::Mat proj_cover;                // CV_32F: 1 where the projector's image reaches the camera pixel
  // Projector maps scaled for the last projector image size (fixed point for a fast remap).
  mutable cv::Size scaled_for;
  mutable cv::Mat scaled_map1, scaled_map2;
  mutable cv::Mat canvas, camera_refl, ambient, light, proj_light, frame;  // scratch

  void build();
  void paint_scene(const core::Stack& stack) const;
  void lighting(const Nuisance& n, uint64_t seed) const;
};

void Renderer::Impl::build() {
  const cv::Size size = camera.size;
  if (size.width < 8 || size.height < 8) throw std::invalid_argument("simcam render: camera size must be at least 8x8");
  if (projector.size.width < 1 || projector.size.height < 1)
    throw std::invalid_argument("simcam render: projector size must be positive");
  identity = camera.is_identity();
  const cv::Matx33d rect_from_ideal = camera.rectified_to_camera.inv();
  const cv::Matx33d proj_from_rect = projector.projector_to_rectified.inv();
  cv::Mat rect_x(size, CV_64F), rect_y(size, CV_64F);
  for (int v = 0; v < size.height; ++v) {
    for (int u = 0; u < size.width; ++u) {
      cv::Point2d r = identity ? cv::Point2d(u, v) : apply_h(rect_from_ideal, undistort(camera, cv::Point2d(u, v)));
      rect_x.at<double>(v, u) = r.x;
      rect_y.at<double>(v, u) = r.y;
    }
  }
  if (identity) {
    origin = {0, 0};
    canvas_size = size;
  } else {
    double min_x, max_x, min_y, max_y;
    cv::minMaxLoc(rect_x, &min_x, &max_x);
    cv::minMaxLoc(rect_y, &min_y, &max_y);
    const double limit = 4.0 * std::max(size.width, size.height);
    min_x = std::max(min_x, -limit); min_y = std::max(min_y, -limit);
    max_x = std::min(max_x, limit); max_y = std::min(max_y, limit);
    origin = {static_cast<int>(std::floor(min_x)) - 2, static_cast<int>(std::floor(min_y)) - 2};
    canvas_size = {static_cast<int>(std::ceil(max_x)) + 3 - origin.x, static_cast<int>(std::ceil(max_y)) + 3 - origin.y};
    scene_map_x.create(size, CV_32F);
    scene_map_y.create(size, CV_32F);
    for (int v = 0; v < size.height; ++v)
      for (int u = 0; u < size.width; ++u) {
        scene_map_x.at<float>(v, u) = static_cast<float>(rect_x.at<double>(v, u) - origin.x);
        scene_map_y.at<float>(v, u) = static_cast<float>(rect_y.at<double>(v, u) - origin.y);
      }
  }
  proj_x.create(size, CV_32F);
  proj_y.create(size, CV_32F);
  proj_cover.create(size, CV_32F);
  for (int v = 0; v < size.height; ++v)
    for (int u = 0; u < size.width; ++u) {
      cv::Point2d p = apply_h(proj_from_rect, {rect_x.at<double>(v, u), rect_y.at<double>(v, u)});
      proj_x.at<float>(v, u) = static_cast<float>(p.x);
      proj_y.at<float>(v, u) = static_cast<float>(p.y);
      bool inside = p.x >= -0.5 && p.y >= -0.5 && p.x <= projector.size.width - 0.5 && p.y <= projector.size.height - 0.5;
      proj_cover.at<float>(v, u) = inside ? 1.0f : 0.0f;
    }
}

// Reflectance of the scene on the rectified canvas (CV_32FC3, 1 = bare glass).
void Renderer::Impl::paint_scene(const core::Stack& stack) const {
  canvas.create(canvas_size, CV_32FC3);
  canvas.setTo(cv::Scalar(1, 1, 1));
  const BoardGeometry& g = camera.board;
  const double ox = origin.x, oy = origin.y;
  const double far = 1e6;
  // The shelf: x <= edge, below the surface top.
  paint_rect(canvas, -far, g.edge_x_px - ox, g.surface_y_px - oy, far, kShelf);
  const double w = camera.line_width * g.block_length_px;
  for (const auto& b : stack.blocks) {
    double x0 = g.to_px_x(block_x(stack, b)) - ox, x1 = x0 + g.block_length_px;
    double y1 = g.surface_y_px - b.row * g.block_height_px - oy, y0 = y1 - g.block_height_px;
    paint_rect(canvas, x0, x1, y0, y1, kBlockTint);
    paint_rect(canvas, x0, x1, y0, y0 + kOutlineWidthPx, kOutline);
    paint_rect(canvas, x0, x1, y1 - kOutlineWidthPx, y1, kOutline);
    paint_rect(canvas, x0, x0 + w, y0, y1, kLine);
    paint_rect(canvas, x1 - w, x1, y0, y1, kLine);
  }
}

// Ambient light field (CV_32F, levels of green on bare glass) and vignetting (into light), full size.
void Renderer::Impl::lighting(const Nuisance& n, uint64_t seed) const {
  const cv::Size size = camera.size;
  const int step = 8;
  const cv::Size low((size.width + step - 1) / step + 1, (size.height + step - 1) / step + 1);
  Random r(n.layout_seed != 0 ? n.layout_seed : seed ^ 0x5EED1A70ULL);
  const double cx = (size.width - 1) / 2.0, cy = (size.height - 1) / 2.0;
  const double half_diag = std::hypot(cx, cy);

  // Gradient and glass unevenness.
  cv::Mat field(low, CV_32F);
  double gdir = r.uniform(0, 2 * M_PI);
  struct Bump { double x, y, s, a; };
  std::vector<Bump> bumps;
  for (int i = 0; i < 6; ++i)
    bumps.push_back({r.uniform(0, size.width), r.uniform(0, size.height), r.uniform(0.1, 0.3) * size.width,
                     r.uniform(-1, 1) * n.unevenness});
  for (int j = 0; j < low.height; ++j)
    for (int i = 0; i < low.width; ++i) {
      double u = i * step, v = j * step;
      double t = ((u - cx) * std::cos(gdir) + (v - cy) * std::sin(gdir)) / half_diag;  // -1..1
      double val = 1.0 + 0.5 * n.gradient * t;
      for (const auto& b : bumps) val *= 1.0 + b.a * std::exp(-((u - b.x) * (u - b.x) + (v - b.y) * (v - b.y)) / (2 * b.s * b.s));
      field.at<float>(j, i) = static_cast<float>(val);
    }

  // Shadows of a player (arms with a hand, a body) and out-of-focus blobs, drawn small and blurred.
  auto darken = [&](const cv::Mat& mask, double strength, double sigma_px) {
    cv::Mat soft;
    double s = std::max(0.5, sigma_px / step);
    cv::GaussianBlur(mask, soft, cv::Size(0, 0), s, s, cv::BORDER_REPLICATE);
    field = field.mul(1.0 - strength * soft);
  };
  const double scale = size.width / 640.0;
  for (int k = 0; k < n.shadow_count; ++k) {
    cv::Mat mask = cv::Mat::zeros(low, CV_32F);
    double phase = r.uniform(0, 2 * M_PI), speed = r.uniform(0.3, 0.9);
    double sway = std::sin(n.time_s * speed + phase);
    if (k == 2) {  // a body: broad, from the bottom
      cv::Point2d c(r.uniform(0.2, 0.8) * size.width + 40 * scale * sway, size.height * r.uniform(1.0, 1.15));
      cv::ellipse(mask, cv::Point(static_cast<int>(c.x / step), static_cast<int>(c.y / step)),
                  cv::Size(static_cast<int>(170 * scale / step), static_cast<int>(260 * scale / step)), 0, 0, 360,
                  cv::Scalar(1), cv::FILLED, cv::LINE_AA);
      darken(mask, n.shadow_strength, 45 * scale);
      continue;
    }
    // An arm from the bottom or a side towards the board, the hand at its end.
    int side = r.integer(0, 2);
    cv::Point2d base, dir;
    if (side == 0) { base = {r.uniform(0.2, 0.8) * size.width, size.height + 20.0 * scale}; dir = {r.uniform(-0.5, 0.5), -1}; }
    else if (side == 1) { base = {-20.0 * scale, r.uniform(0.3, 0.9) * size.height}; dir = {1, r.uniform(-0.6, 0.2)}; }
    else { base = {size.width + 20.0 * scale, r.uniform(0.3, 0.9) * size.height}; dir = {-1, r.uniform(-0.6, 0.2)}; }
    dir /= std::hypot(dir.x, dir.y);
    double reach = (r.uniform(0.3, 0.6) + 0.12 * sway) * size.height;
    cv::Point2d hand = base + dir * reach;
    int thick = std::max(1, static_cast<int>(r.uniform(55, 85) * scale / step));
    cv::line(mask, cv::Point(static_cast<int>(base.x / step), static_cast<int>(base.y / step)),
             cv::Point(static_cast<int>(hand.x / step), static_cast<int>(hand.y / step)), cv::Scalar(1), thick, cv::LINE_AA);
    cv::circle(mask, cv::Point(static_cast<int>(hand.x / step), static_cast<int>(hand.y / step)),
               std::max(1, static_cast<int>(50 * scale / step)), cv::Scalar(1), cv::FILLED, cv::LINE_AA);
    darken(mask, n.shadow_strength, 22 * scale);
  }
  for (int k = 0; k < n.blob_count; ++k) {
    cv::Mat mask = cv::Mat::zeros(low, CV_32F);
    double phase = r.uniform(0, 2 * M_PI);
    cv::Point2d c(r.uniform(0.1, 0.9) * size.width + 30 * scale * std::sin(n.time_s * 0.5 + phase),
                  r.uniform(0.1, 0.9) * size.height + 20 * scale * std::cos(n.time_s * 0.4 + phase));
    double radius = r.uniform(40, 80) * scale;
    cv::circle(mask, cv::Point(static_cast<int>(c.x / step), static_cast<int>(c.y / step)),
               std::max(1, static_cast<int>(radius / step)), cv::Scalar(1), cv::FILLED, cv::LINE_AA);
    darken(mask, n.blob_strength, 0.6 * radius);
  }

  // Vignetting (lens: applies to projector light too), cos^4-like falloff approximated quadratically.
  cv::Mat vig(low, CV_32F);
  for (int j = 0; j < low.height; ++j)
    for (int i = 0; i < low.width; ++i) {
      double rr = std::hypot(i * step - cx, j * step - cy) / half_diag;
      vig.at<float>(j, i) = static_cast<float>(1.0 - n.vignetting * rr * rr);
    }
  // Upsample: low-res sample (i, j) sits at full-res pixel (i*step, j*step).
  cv::Mat warp = (cv::Mat_<double>(2, 3) << step, 0, 0, 0, step, 0);
  cv::warpAffine(field, ambient, warp, size, cv::INTER_LINEAR, cv::BORDER_REPLICATE);
  cv::warpAffine(vig, light, warp, size, cv::INTER_LINEAR, cv::BORDER_REPLICATE);
}

Renderer::Renderer(const CameraSetup& camera, const ProjectorSetup& projector) : impl_(std::make_unique<Impl>()) {
  impl_->camera = camera;
  impl_->projector = projector;
  impl_->build();
}
Renderer::~Renderer() = default;
Renderer::Renderer(Renderer&&) noexcept = default;
Renderer& Renderer::operator=(Renderer&&) noexcept = default;
const CameraSetup& Renderer::camera() const { return impl_->camera; }
const ProjectorSetup& Renderer::projector() const { return impl_->projector; }

Rendered Renderer::render(const core::Stack& stack, const Nuisance& n, const cv::Mat* projector_image, uint64_t seed) const {
  Impl& m = *impl_;
  check_stack(stack);
  if (projector_image && !projector_image->empty() && projector_image->type() != CV_8UC3)
    throw std::invalid_argument("simcam render: projector image must be CV_8UC3 (BGR), got type " +
                                std::to_string(projector_image->type()));
  const bool projecting = projector_image && !projector_image->empty();
  const cv::Size size = m.camera.size;

  m.paint_scene(stack);
  if (m.identity) {
    m.camera_refl = m.canvas;
  } else {
    cv::remap(m.canvas, m.camera_refl, m.scene_map_x, m.scene_map_y, cv::INTER_LINEAR, cv::BORDER_REPLICATE);
  }
  m.lighting(n, seed);

  if (projecting) {
    const cv::Size psize = projector_image->size();
    if (psize != m.scaled_for) {
      cv::Mat sx = m.proj_x * (psize.width / static_cast<double>(m.projector.size.width));
      cv::Mat sy = m.proj_y * (psize.height / static_cast<double>(m.projector.size.height));
      // Projector pixel p of the full-size image covers image pixels around p * scale + (scale - 1) / 2.
      sx += 0.5 * (psize.width / static_cast<double>(m.projector.size.width)) - 0.5;
      sy += 0.5 * (psize.height / static_cast<double>(m.projector.size.height)) - 0.5;
      cv::convertMaps(sx, sy, m.scaled_map1, m.scaled_map2, CV_16SC2);
      m.scaled_for = psize;
    }
    cv::remap(*projector_image, m.proj_light, m.scaled_map1, m.scaled_map2, cv::INTER_LINEAR, cv::BORDER_CONSTANT,
              cv::Scalar(0, 0, 0));
  }

  // Compose: vignette * (reflectance * ambient light + projector light attenuated by dark lines).
  m.frame.create(size, CV_32FC3);
  float mix[9];
  for (int i = 0; i < 9; ++i) mix[i] = static_cast<float>(m.projector.mixing.val[i]);
  const float black[3] = {static_cast<float>(m.projector.ambient[0]), static_cast<float>(m.projector.ambient[1]),
                          static_cast<float>(m.projector.ambient[2])};
  const float absorb = static_cast<float>(m.projector.line_absorption);
  const float amb[3] = {kAmbientColour[0] * static_cast<float>(m.camera.board_brightness),
                        kAmbientColour[1] * static_cast<float>(m.camera.board_brightness),
                        kAmbientColour[2] * static_cast<float>(m.camera.board_brightness)};
  for (int v = 0; v < size.height; ++v) {
    const float* refl = m.camera_refl.ptr<float>(v);
    const float* a = m.ambient.ptr<float>(v);
    const float* vig = m.light.ptr<float>(v);
    float* out = m.frame.ptr<float>(v);
    if (!projecting) {
      for (int u = 0; u < size.width; ++u) {
        const float s = a[u] * vig[u];
        out[3 * u] = refl[3 * u] * amb[0] * s;
        out[3 * u + 1] = refl[3 * u + 1] * amb[1] * s;
        out[3 * u + 2] = refl[3 * u + 2] * amb[2] * s;
      }
      continue;
    }
    const uchar* pl = m.proj_light.ptr<uchar>(v);
    const float* cover = m.proj_cover.ptr<float>(v);
    for (int u = 0; u < size.width; ++u) {
      const float pb = pl[3 * u], pg = pl[3 * u + 1], pr = pl[3 * u + 2];
      for (int ch = 0; ch < 3; ++ch) {
        const float r = refl[3 * u + ch];
        const float added = mix[3 * ch] * pb + mix[3 * ch + 1] * pg + mix[3 * ch + 2] * pr + black[ch] * cover[u];
        out[3 * u + ch] = (r * amb[ch] * a[u] + added * (1.0f - absorb * (1.0f - r))) * vig[u];
      }
    }
  }

  if (n.blur_sigma > 0) cv::GaussianBlur(m.frame, m.frame, cv::Size(0, 0), n.blur_sigma, n.blur_sigma, cv::BORDER_REPLICATE);

  Rendered result;
  const bool noisy = n.noise > 0 || n.read_noise > 0;
  if (!noisy) {
    m.frame.convertTo(result.bgr, CV_8UC3);
  } else {
    result.bgr.create(size, CV_8UC3);
    // Noise std-dev per brightness level (brightness-dependent shot noise plus read noise), a table lookup.
    float sigma_of[257];
    for (int i = 0; i <= 256; ++i) sigma_of[i] = static_cast<float>(std::sqrt(n.read_noise * n.read_noise + n.noise * n.noise * i / 255.0));
    const std::vector<float>& table = normal_table();
    uint64_t state = seed * 0x2545F4914F6CDD1DULL + 0x6A09E667F3BCC909ULL;
    for (int v = 0; v < size.height; ++v) {
      const float* in = m.frame.ptr<float>(v);
      uchar* out = result.bgr.ptr<uchar>(v);
      for (int u = 0; u < size.width; ++u) {
        const uint64_t bits = splitmix64(state);
        for (int ch = 0; ch < 3; ++ch) {
          const float c = in[3 * u + ch];
          const int level = static_cast<int>(std::clamp(c, 0.0f, 256.0f));
          out[3 * u + ch] = cv::saturate_cast<uchar>(c + sigma_of[level] * table[(bits >> (16 * ch)) & 0xFFFF]);
        }
      }
    }
  }
  if (n.jpeg_quality > 0) {
    std::vector<uchar> buf;
    cv::imencode(".jpg", result.bgr, buf, {cv::IMWRITE_JPEG_QUALITY, std::clamp(n.jpeg_quality, 1, 100)});
    result.bgr = cv::imdecode(buf, cv::IMREAD_COLOR);
  }
  result.truth = true_blocks(stack, m.camera);
  return result;
}

Rendered render(const core::Stack& stack, const CameraSetup& camera, const Nuisance& nuisance,
                const cv::Mat* projector_image, const ProjectorSetup& projector, uint64_t seed) {
  return Renderer(camera, projector).render(stack, nuisance, projector_image, seed);
}

}  // namespace bricklayer::simcam
