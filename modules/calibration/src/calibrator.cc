#include "bricklayer/calibration/calibrator.h"

#include <Eigen/Dense>
#include <opencv2/aruco.hpp>
#include <opencv2/calib3d.hpp>
#include <opencv2/imgproc.hpp>

#include <algorithm>
#include <cmath>
#include <map>
#include <optional>
#include <sstream>
#include <stdexcept>

#include "bricklayer/board/calibration_file.h"
#include "bricklayer/board/mapping.h"
#include "bricklayer/patterns/patterns.h"

namespace bricklayer::calibration {
// The shared board and pattern libraries, by the short names the computation reads best with.
using board::apply_homography;
using board::camera_to_projector;
using board::distort_point;
using board::undistort_point;
using board::validate_calibration;
using patterns::kMarkerSetGrid;
using patterns::kMarkerSetSelfCheck;
using patterns::kMarkerSetShiftedGrid;
using patterns::marker_layout;
using patterns::MarkerPlacement;
namespace {

constexpr double kNominalFocalPerWidth = 0.875;  // 560 px at 640: a typical webcam; see header
constexpr double kOutlierCameraPx = 3.0;

bricklayer::command_t show(int32_t pattern, int32_t index, int r, int g, int b) {
  bricklayer::command_t cmd{};
  cmd.command = bricklayer::command_t::SHOW_PATTERN;
  cmd.pattern = pattern;
  cmd.index = index;
  cmd.red = static_cast<int16_t>(r);
  cmd.green = static_cast<int16_t>(g);
  cmd.blue = static_cast<int16_t>(b);
  cmd.argument = "";
  return cmd;
}

cv::Ptr<cv::aruco::Dictionary> dictionary() {
  static const cv::Ptr<cv::aruco::Dictionary> dict = cv::aruco::getPredefinedDictionary(cv::aruco::DICT_4X4_250);
  return dict;
}

std::string fmt(double v, int precision = 3) {
  std::ostringstream out;
  out.setf(std::ios::fixed);
  out.precision(precision);
  out << v;
  return out.str();
}

// The model: projector pixel -> normalised projector (pn) -> homography G -> normalised ideal camera
// (x) -> radial distortion (k1, k2) about the distortion centre -> camera pixel. Parameters q:
// G's first 8 entries (G22 = 1), k1, k2, the distortion centre's offset from the image centre
// (camera px), and the corner bias (camera px, see FitPoint).
constexpr int kParams = 13;
using Params = Eigen::Matrix<double, kParams, 1>;

struct Model {
  double f = 1;
  cv::Point2d c;
  cv::Point2d pc;
  double ps = 1;

  cv::Point2d project(const Params& q, cv::Point2d p) const {
    const double u = (p.x - pc.x) / ps;
    const double v = (p.y - pc.y) / ps;
    const double w = q[6] * u + q[7] * v + 1.0;
    const double x = (q[0] * u + q[1] * v + q[2]) / w;
    const double y = (q[3] * u + q[4] * v + q[5]) / w;
    // The distortion centre (principal point) is c + (q[10], q[11]); x, y are relative to c, so
    // shift them to the centre before distorting and back after.
    const double xs = x - q[10] / f;
    const double ys = y - q[11] / f;
    const double r2 = xs * xs + ys * ys;
    const double radial = 1 + r2 * (q[8] + r2 * q[9]);
    return {f * xs * radial + c.x + q[10], f * ys * radial + c.y + q[11]};
  }
};

// One observation in the fit: a marker corner (anchor = the marker's centre, projector pixels) or a
// centre (no anchor). Detected corners sit q[12] camera pixels further towards the marker's centre
// than the true corners (blur rounds the corner; cornerSubPix converges inside it), so the model
// moves the predicted corner by q[12] along the diagonal. Corners reach half a marker closer to the
// image border than centres, where the lens matters most.
struct FitPoint {
  cv::Point2d projector;
  cv::Point2d camera;
  cv::Point2d anchor;
  bool has_anchor = false;
  size_t owner = 0;  // index of the correspondence
};

cv::Point2d predict(const Model& model, const Params& q, const FitPoint& p) {
  cv::Point2d m = model.project(q, p.projector);
  if (p.has_anchor) {
    const cv::Point2d d = model.project(q, p.anchor) - m;
    const double n = std::hypot(d.x, d.y);
    if (n > 1e-9) m += d * (q[12] / n);
  }
  return m;
}

// Levenberg-Marquardt with a numeric Jacobian (10 parameters, a few hundred points: microseconds
// per iteration, no need for more machinery).
Params levenberg_marquardt(const Model& model, Params q, const std::vector<FitPoint>& pts) {
  const int n = static_cast<int>(pts.size());
  auto residuals = [&](const Params& params) {
    Eigen::VectorXd r(2 * n);
    for (int i = 0; i < n; ++i) {
      const cv::Point2d m = predict(model, params, pts[i]);
      r[2 * i] = m.x - pts[i].camera.x;
      r[2 * i + 1] = m.y - pts[i].camera.y;
    }
    return r;
  };
  Eigen::VectorXd r = residuals(q);
  double cost = r.squaredNorm();
  double lambda = 1e-3;
  Eigen::MatrixXd jac(2 * n, kParams);
  for (int iteration = 0; iteration < 100; ++iteration) {
    for (int k = 0; k < kParams; ++k) {
      Params qp = q;
      const double h = 1e-7 * std::max(1.0, std::abs(q[k]));
      qp[k] += h;
      jac.col(k) = (residuals(qp) - r) / h;
    }
    const Eigen::Matrix<double, kParams, kParams> jtj = jac.transpose() * jac;
    const Params jtr = jac.transpose() * r;
    bool improved = false;
    for (int attempt = 0; attempt < 10; ++attempt) {
      Eigen::Matrix<double, kParams, kParams> a = jtj;
      a.diagonal() += lambda * jtj.diagonal().cwiseMax(1e-12);
      const Params step = a.ldlt().solve(-jtr);
      const Params candidate = q + step;
      const Eigen::VectorXd rc = residuals(candidate);
      const double c = rc.squaredNorm();
      if (std::isfinite(c) && c < cost) {
        const double gain = (cost - c) / std::max(cost, 1e-300);
        q = candidate;
        r = rc;
        cost = c;
        lambda = std::max(lambda / 10, 1e-12);
        improved = true;
        if (gain < 1e-12 || step.norm() < 1e-14) return q;
        break;
      }
      lambda *= 10;
    }
    if (!improved) break;
  }
  return q;
}

cv::Scalar central_median(const cv::Mat& bgr) {
  const cv::Rect roi(bgr.cols * 4 / 10, bgr.rows * 4 / 10, bgr.cols * 2 / 10, bgr.rows * 2 / 10);
  std::vector<cv::Mat> channels;
  cv::split(bgr(roi), channels);
  cv::Scalar out;
  for (int ch = 0; ch < 3; ++ch) {
    // Median of an 8-bit channel from its histogram.
    int hist[256] = {0};
    for (int y = 0; y < channels[ch].rows; ++y) {
      const uchar* row = channels[ch].ptr<uchar>(y);
      for (int x = 0; x < channels[ch].cols; ++x) ++hist[row[x]];
    }
    const int total = channels[ch].rows * channels[ch].cols;
    int cumulative = 0;
    int level = 0;
    for (; level < 256; ++level) {
      cumulative += hist[level];
      if (2 * cumulative >= total) break;
    }
    // Interpolate within the bin for sub-level resolution.
    const int before = cumulative - hist[std::min(level, 255)];
    const double frac = hist[std::min(level, 255)] > 0 ? (total / 2.0 - before) / hist[std::min(level, 255)] : 0.5;
    out[ch] = level - 0.5 + frac;
  }
  return out;
}

// The intersection of a quadrilateral's diagonals: the image of the square's centre under any
// homography, and unmoved when blur pulls the detected corners inwards symmetrically.
std::optional<cv::Point2d> diagonal_intersection(const std::array<cv::Point2d, 4>& q) {
  const cv::Point2d d1 = q[2] - q[0];
  const cv::Point2d d2 = q[3] - q[1];
  const double denom = d1.x * d2.y - d1.y * d2.x;
  if (std::abs(denom) < 1e-9) return std::nullopt;
  const cv::Point2d w = q[1] - q[0];
  const double t = (w.x * d2.y - w.y * d2.x) / denom;
  if (t <= 0 || t >= 1) return std::nullopt;  // not a convex quadrilateral
  return q[0] + t * d1;
}

}  // namespace

const char* to_string(CalibrationStatus status) {
  switch (status) {
    case CalibrationStatus::kOk: return "ok";
    case CalibrationStatus::kBadFrames: return "bad frames";
    case CalibrationStatus::kTooFewPoints: return "too few markers";
    case CalibrationStatus::kSaturated: return "camera saturated";
    case CalibrationStatus::kErrorTooHigh: return "reprojection error too high";
    case CalibrationStatus::kInvalid: return "invalid result";
  }
  return "unknown";
}

std::vector<CalibrationStep> calibration_steps(const CalibrationOptions& options) {
  using C = bricklayer::command_t;
  const int d = std::clamp(options.colour_drive, 1, 255);
  return {
      {show(C::PATTERN_SOLID, 0, 0, 0, 0), "black (ambient light)"},
      {show(C::PATTERN_SOLID, 0, 0, 0, d), "blue (colour mixing)"},
      {show(C::PATTERN_SOLID, 0, 0, d, 0), "green (colour mixing)"},
      {show(C::PATTERN_SOLID, 0, d, 0, 0), "red (colour mixing)"},
      {show(C::PATTERN_MARKERS, kMarkerSetGrid, 0, 0, 0), "marker grid (registration)"},
      {show(C::PATTERN_MARKERS, kMarkerSetShiftedGrid, 0, 0, 0), "shifted marker grid (registration)"},
  };
}

std::vector<Correspondence> detect_marker_correspondences(const cv::Mat& frame, int set, cv::Size projector_size) {
  std::vector<Correspondence> out;
  if (frame.empty()) return out;
  cv::Mat gray;
  if (frame.channels() == 3) {
    cv::cvtColor(frame, gray, cv::COLOR_BGR2GRAY);
  } else if (frame.channels() == 1) {
    gray = frame;
  } else {
    return out;
  }
  std::map<int, MarkerPlacement> layout;
  for (const MarkerPlacement& m : marker_layout(set, projector_size)) layout[m.id] = m;
  auto params = cv::aruco::DetectorParameters::create();
  params->cornerRefinementMethod = cv::aruco::CORNER_REFINE_SUBPIX;
  params->cornerRefinementWinSize = 4;
  params->cornerRefinementMinAccuracy = 0.01;
  params->cornerRefinementMaxIterations = 50;
  std::vector<int> ids;
  std::vector<std::vector<cv::Point2f>> corners;
  cv::aruco::detectMarkers(gray, dictionary(), corners, ids, params);
  std::map<int, int> seen;
  for (int id : ids) ++seen[id];
  for (size_t i = 0; i < ids.size(); ++i) {
    auto it = layout.find(ids[i]);
    if (it == layout.end() || seen[ids[i]] != 1 || corners[i].size() != 4) continue;  // foreign or ambiguous
    std::array<cv::Point2d, 4> camera_corners;
    std::array<cv::Point2d, 4> projector_corners;
    for (int k = 0; k < 4; ++k) {
      camera_corners[k] = cv::Point2d(corners[i][k]);
      projector_corners[k] = cv::Point2d(it->second.corners[k]);
    }
    const auto camera_centre = diagonal_intersection(camera_corners);
    if (!camera_centre) continue;
    out.push_back({*camera_centre, *diagonal_intersection(projector_corners), camera_corners, projector_corners, true});
  }
  return out;
}

void recentre_undistorted(std::vector<Correspondence>& points, const bricklayer::calibration_t& cal) {
  for (Correspondence& p : points) {
    std::array<cv::Point2d, 4> ideal;
    for (int k = 0; k < 4; ++k) ideal[k] = undistort_point(cal, p.camera_corners[k]);
    if (const auto centre = diagonal_intersection(ideal)) p.camera = distort_point(cal, *centre);
  }
}

LensFit fit_lens_and_homography(const std::vector<Correspondence>& points, cv::Size camera_size) {
  if (points.size() < 8) throw std::runtime_error("lens fit needs at least 8 correspondences, got " + std::to_string(points.size()));
  Model model;
  model.f = kNominalFocalPerWidth * camera_size.width;
  model.c = cv::Point2d((camera_size.width - 1) / 2.0, (camera_size.height - 1) / 2.0);
  double px_min = 1e300, px_max = -1e300, py_min = 1e300, py_max = -1e300;
  for (const auto& p : points) {
    px_min = std::min(px_min, p.projector.x);
    px_max = std::max(px_max, p.projector.x);
    py_min = std::min(py_min, p.projector.y);
    py_max = std::max(py_max, p.projector.y);
  }
  model.pc = cv::Point2d((px_min + px_max) / 2, (py_min + py_max) / 2);
  model.ps = std::max(1.0, std::max(px_max - px_min, py_max - py_min) / 2);

  // Initial homography between the normalised coordinates, ignoring distortion.
  std::vector<cv::Point2d> src, dst;
  for (const auto& p : points) {
    src.emplace_back((p.projector.x - model.pc.x) / model.ps, (p.projector.y - model.pc.y) / model.ps);
    dst.emplace_back((p.camera.x - model.c.x) / model.f, (p.camera.y - model.c.y) / model.f);
  }
  cv::Mat h0 = cv::findHomography(src, dst, cv::RANSAC, 3.0 / model.f);
  if (h0.empty()) h0 = cv::findHomography(src, dst, 0);
  if (h0.empty()) throw std::runtime_error("lens fit: no homography fits the detected markers (degenerate layout)");
  h0 /= h0.at<double>(2, 2);
  Params q;
  for (int k = 0; k < 8; ++k) q[k] = h0.at<double>(k / 3, k % 3);
  q[8] = 0;
  q[9] = 0;
  q[10] = 0;
  q[11] = 0;

  q[12] = 0;

  // Corners when every correspondence has them (detected markers), else the points themselves.
  std::vector<FitPoint> all;
  for (size_t i = 0; i < points.size(); ++i) {
    const Correspondence& c = points[i];
    if (c.has_corners) {
      for (int k = 0; k < 4; ++k)
        if (c.corner_used[k]) all.push_back({c.projector_corners[k], c.camera_corners[k], c.projector, true, i});
    } else {
      all.push_back({c.projector, c.camera, c.projector, false, i});
    }
  }
  std::vector<FitPoint> used = all;
  std::vector<bool> inlier(points.size(), true);
  for (int round = 0; round < 3; ++round) {
    q = levenberg_marquardt(model, q, used);
    // Re-select inliers from all points against the current fit: a correspondence is an inlier
    // when all of its observations are.
    std::vector<bool> now(points.size(), true);
    for (const FitPoint& p : all) {
      if (cv::norm(predict(model, q, p) - p.camera) >= kOutlierCameraPx) now[p.owner] = false;
    }
    size_t changed = 0;
    for (size_t i = 0; i < points.size(); ++i) changed += now[i] != inlier[i];
    inlier = now;
    used.clear();
    for (const FitPoint& p : all) {
      if (inlier[p.owner]) used.push_back(p);
    }
    if (used.size() < 8) throw std::runtime_error("lens fit: fewer than 8 correspondences agree with the fit");
    if (changed == 0) break;
  }

  LensFit fit;
  fit.inlier = inlier;
  fit.corner_bias_px = q[12];
  double sum2 = 0;
  for (const auto& p : used) {
    const cv::Point2d m = predict(model, q, p);
    sum2 += (m.x - p.camera.x) * (m.x - p.camera.x) + (m.y - p.camera.y) * (m.y - p.camera.y);
  }
  fit.rms_camera_px = std::sqrt(sum2 / used.size());
  fit.camera_matrix = cv::Matx33d(model.f, 0, model.c.x + q[10], 0, model.f, model.c.y + q[11], 0, 0, 1);
  fit.distortion = cv::Vec<double, 5>(q[8], q[9], 0, 0, 0);
  const cv::Matx33d g(q[0], q[1], q[2], q[3], q[4], q[5], q[6], q[7], 1.0);
  const cv::Matx33d to_normalised(1 / model.f, 0, -model.c.x / model.f, 0, 1 / model.f, -model.c.y / model.f, 0, 0, 1);
  const cv::Matx33d from_projector_normalised(model.ps, 0, model.pc.x, 0, model.ps, model.pc.y, 0, 0, 1);
  cv::Matx33d h = from_projector_normalised * g.inv() * to_normalised;
  h *= 1.0 / h(2, 2);
  fit.camera_to_projector = h;
  return fit;
}

ColourMeasurement measure_colour_mixing(const cv::Mat& black, const cv::Mat& blue, const cv::Mat& green,
                                        const cv::Mat& red, int drive) {
  ColourMeasurement m;
  const cv::Scalar b0 = central_median(black);
  const cv::Scalar responses[3] = {central_median(blue), central_median(green), central_median(red)};
  m.ambient = cv::Vec3d(b0[0], b0[1], b0[2]);
  for (int j = 0; j < 3; ++j) {
    for (int i = 0; i < 3; ++i) {
      m.mixing(i, j) = (responses[j][i] - b0[i]) / drive;
      if (responses[j][i] > 250) m.saturated = true;
    }
  }
  return m;
}

CalibrationResult compute_calibration(const std::vector<cv::Mat>& frames, const CalibrationOptions& options, int64_t utime) {
  CalibrationResult result;
  const auto steps = calibration_steps(options);
  if (frames.size() != steps.size()) {
    result.message = "expected " + std::to_string(steps.size()) + " camera frames (one per pattern), got " + std::to_string(frames.size());
    return result;
  }
  const cv::Size camera_size = frames[0].size();
  for (size_t i = 0; i < frames.size(); ++i) {
    if (frames[i].empty() || frames[i].type() != CV_8UC3 || frames[i].size() != camera_size) {
      result.message = "camera frame for step " + std::to_string(i + 1) + " (" + steps[i].description +
                       ") is empty, not 8-bit BGR, or a different size from the first";
      return result;
    }
  }
  if (camera_size.width < 16 || camera_size.height < 16) {
    result.message = "camera frames too small";
    return result;
  }

  // Colour.
  const ColourMeasurement colour = measure_colour_mixing(frames[0], frames[1], frames[2], frames[3], std::clamp(options.colour_drive, 1, 255));

  // Registration.
  std::vector<Correspondence> points = detect_marker_correspondences(frames[4], kMarkerSetGrid, options.projector_size);
  const auto more = detect_marker_correspondences(frames[5], kMarkerSetShiftedGrid, options.projector_size);
  points.insert(points.end(), more.begin(), more.end());
  result.correspondences = static_cast<int>(points.size());
  if (static_cast<int>(points.size()) < std::max(8, options.min_correspondences)) {
    result.status = CalibrationStatus::kTooFewPoints;
    result.message = "only " + std::to_string(points.size()) + " markers detected (need " +
                     std::to_string(std::max(8, options.min_correspondences)) +
                     "): is the projector on and pointing at the board, the board empty, the camera in focus?";
    return result;
  }
  bricklayer::calibration_t& cal = result.calibration;
  cal.utime = utime;
  cal.camera_width = camera_size.width;
  cal.camera_height = camera_size.height;
  cal.projector_width = options.projector_size.width;
  cal.projector_height = options.projector_size.height;
  LensFit fit;
  auto take_fit = [&](const LensFit& f) {
    fit = f;
    cal.camera_matrix[0] = f.camera_matrix(0, 0);
    cal.camera_matrix[1] = f.camera_matrix(1, 1);
    cal.camera_matrix[2] = f.camera_matrix(0, 2);
    cal.camera_matrix[3] = f.camera_matrix(1, 2);
    for (int i = 0; i < 5; ++i) cal.distortion[i] = f.distortion[i];
    for (int i = 0; i < 9; ++i) cal.camera_to_projector[i] = f.camera_to_projector(i / 3, i % 3);
  };
  const double scale = static_cast<double>(camera_size.width) / options.projector_size.width;
  const cv::Matx33d rectified_from_projector(scale, 0, 0, 0, scale, 0, 0, 0, 1);
  // The shelf in the projector's light on the board, seen in the rectified frame of the current fit
  // (ambient and shadows cancel).
  auto find_shelf = [&]() {
    const cv::Matx33d rectified_from_camera = rectified_from_projector * fit.camera_to_projector;
    cv::Mat light = cv::Mat::zeros(camera_size, CV_32F);
    for (int f = 1; f <= 3; ++f) {
      cv::Mat diff;
      cv::absdiff(frames[f], frames[0], diff);
      cv::Mat gray;
      cv::cvtColor(diff, gray, cv::COLOR_BGR2GRAY);
      cv::accumulate(gray, light);
    }
    const cv::Matx33d camera_from_rectified = rectified_from_camera.inv();
    cv::Mat map_x(camera_size, CV_32F), map_y(camera_size, CV_32F);
    for (int y = 0; y < camera_size.height; ++y) {
      for (int x = 0; x < camera_size.width; ++x) {
        const cv::Point2d c = distort_point(cal, apply_homography(camera_from_rectified, cv::Point2d(x, y)));
        map_x.at<float>(y, x) = static_cast<float>(c.x);
        map_y.at<float>(y, x) = static_cast<float>(c.y);
      }
    }
    cv::Mat rectified;
    cv::remap(light + 1.0f, rectified, map_x, map_y, cv::INTER_LINEAR, cv::BORDER_CONSTANT, cv::Scalar(0));
    return find_shelf_corner(rectified, options.board);
  };
  try {
    take_fit(fit_lens_and_homography(points, camera_size));
    if (options.board_from_shelf) {
      result.shelf = find_shelf();
      // A corner whose refinement window meets the shelf's step is pulled towards it (a few tenths of
      // a camera pixel, all in one direction along the bottom row): the fit bends there, and the
      // mapping is off by up to 2 projector px near the shelf. Such markers are left out and the fit
      // made again; the shelf is then found again in the refitted frame.
      if (result.shelf.found && options.shelf_clearance_camera_px > 0) {
        const cv::Matx33d rectified_from_camera = rectified_from_projector * fit.camera_to_projector;
        const cv::Matx33d camera_from_rectified = rectified_from_camera.inv();
        const cv::Point2d corner = result.shelf.corner;
        const cv::Point2d along(-std::cos(result.shelf.angle_rad), -std::sin(result.shelf.angle_rad));  // the top, leftwards
        const cv::Point2d down(-std::sin(result.shelf.angle_rad), std::cos(result.shelf.angle_rad));  // the end, downwards
        // Camera pixels between a camera point and the nearest point of a ray of the shelf outline.
        auto distance_to_ray = [&](cv::Point2d camera_px, cv::Point2d rectified, cv::Point2d dir) {
          const double t = std::max(0.0, (rectified - corner).dot(dir));
          const cv::Point2d foot = corner + t * dir;
          return cv::norm(distort_point(cal, apply_homography(camera_from_rectified, foot)) - camera_px);
        };
        int near_corners = 0;
        for (Correspondence& p : points) {
          if (!p.has_corners) continue;
          bool near = false;
          for (int k = 0; k < 4; ++k) {
            const cv::Point2d cam = p.camera_corners[k];
            const cv::Point2d r = apply_homography(rectified_from_camera, undistort_point(cal, cam));
            p.corner_used[k] = distance_to_ray(cam, r, along) >= options.shelf_clearance_camera_px &&
                               distance_to_ray(cam, r, down) >= options.shelf_clearance_camera_px;
            near = near || !p.corner_used[k];
            near_corners += !p.corner_used[k];
          }
          result.near_shelf += near;
        }
        if (near_corners > 0) {
          take_fit(fit_lens_and_homography(points, camera_size));
          result.shelf = find_shelf();
        }
      }
    }
    // The centres the reprojection error is reported on, taken in undistorted pixels.
    recentre_undistorted(points, cal);
  } catch (const std::exception& e) {
    result.status = CalibrationStatus::kTooFewPoints;
    result.message = e.what();
    return result;
  }

  const cv::Matx33d rectified_from_camera = rectified_from_projector * fit.camera_to_projector;
  cv::Matx33d board_anchor = cv::Matx33d::eye();  // rectified -> rectified: the shelf correction
  if (options.board_from_shelf && result.shelf.found) {
    // Rotate about the detected corner so the shelf top is level, then move the corner onto the
    // geometry's (edge, surface).
    const double ca = std::cos(-result.shelf.angle_rad), sa = std::sin(-result.shelf.angle_rad);
    const cv::Point2d c = result.shelf.corner;
    const cv::Matx33d to_origin(1, 0, -c.x, 0, 1, -c.y, 0, 0, 1);
    const cv::Matx33d rotate(ca, -sa, 0, sa, ca, 0, 0, 0, 1);
    const cv::Matx33d to_nominal(1, 0, options.board.edge_x_px, 0, 1, options.board.surface_y_px, 0, 0, 1);
    board_anchor = to_nominal * rotate * to_origin;
  }
  const auto board = options.board.camera_to_board();
  const cv::Matx33d board_from_rectified(board.data());
  cv::Matx33d to_board = board_from_rectified * board_anchor * rectified_from_camera;
  for (int i = 0; i < 9; ++i) cal.camera_to_board[i] = to_board(i / 3, i % 3);
  for (int i = 0; i < 9; ++i) cal.colour_mixing[i] = colour.mixing(i / 3, i % 3);
  for (int i = 0; i < 3; ++i) cal.ambient_bgr[i] = colour.ambient[i];
  cal.block_height = options.board.block_height_px / options.board.block_length_px;

  double sum = 0, max = 0;
  cv::Point2d worst_at;
  int inliers = 0;
  int counted = 0;  // markers whose centre is judged: every corner used
  for (size_t i = 0; i < points.size(); ++i) {
    if (!points[i].all_corners_used()) continue;
    ++counted;
    if (!fit.inlier[i]) continue;
    const double e = cv::norm(camera_to_projector(cal, points[i].camera) - points[i].projector);
    sum += e;
    if (e > max) worst_at = points[i].projector;
    max = std::max(max, e);
    ++inliers;
  }
  result.inliers = inliers;
  cal.reprojection_error_mean_px = inliers > 0 ? sum / inliers : 0.0;
  cal.reprojection_error_max_px = max;

  const std::string summary = std::to_string(inliers) + " of " + std::to_string(counted) +
                              " markers used" +
                              (result.near_shelf > 0 ? " (" + std::to_string(result.near_shelf) + " more with corners left out at the shelf edge)" : std::string()) +
                              ", reprojection error mean " + fmt(cal.reprojection_error_mean_px) +
                              " px, max " + fmt(cal.reprojection_error_max_px) + " px (projector pixels), k1 " +
                              fmt(cal.distortion[0], 4) + ", k2 " + fmt(cal.distortion[1], 4);
  if (colour.saturated) {
    result.status = CalibrationStatus::kSaturated;
    result.message = "camera saturated while measuring colour mixing: lower the camera exposure or --colour-drive (" +
                     std::to_string(options.colour_drive) + "); " + summary;
    return result;
  }
  if (inliers < options.min_correspondences || inliers * 10 < counted * 8) {
    result.status = CalibrationStatus::kTooFewPoints;
    result.message = "too many marker corners disagree with the fit (reflections? something on the board?): " + summary;
    return result;
  }
  if (cal.reprojection_error_mean_px > options.max_error_px) {
    result.status = CalibrationStatus::kErrorTooHigh;
    result.message = "calibration rejected: mean reprojection error " + fmt(cal.reprojection_error_mean_px) +
                     " px exceeds --max-error-px " + fmt(options.max_error_px) +
                     " (camera out of focus, moving, or the board not flat?); " + summary;
    return result;
  }
  if (cal.reprojection_error_max_px > options.max_point_error_px) {
    result.status = CalibrationStatus::kErrorTooHigh;
    result.message = "calibration rejected: the largest reprojection error " + fmt(cal.reprojection_error_max_px) +
                     " px (at the marker drawn at projector pixel (" + fmt(worst_at.x, 0) + ", " + fmt(worst_at.y, 0) +
                     ")) exceeds --max-point-error-px " + fmt(options.max_point_error_px) +
                     ": the mapping is bent there (something on the board or a reflection near that marker, the board not flat, "
                     "the camera out of focus?); " + summary;
    return result;
  }
  try {
    validate_calibration(cal);
  } catch (const std::exception& e) {
    result.status = CalibrationStatus::kInvalid;
    result.message = std::string("calibration rejected: ") + e.what() + "; " + summary;
    return result;
  }
  result.status = CalibrationStatus::kOk;
  result.message = "calibration ok: " + summary + "; board frame: " +
                   (!options.board_from_shelf ? std::string("from --board as given")
                    : result.shelf.found       ? result.shelf.message
                                               : "shelf not found (" + result.shelf.message + "), --board geometry as given");
  return result;
}

ShelfCorner find_shelf_corner(const cv::Mat& light, const BoardGeometry& nominal) {
  ShelfCorner out;
  if (light.empty() || light.type() != CV_32F) {
    out.message = "no light image";
    return out;
  }
  cv::Mat smooth;
  cv::GaussianBlur(light, smooth, cv::Size(0, 0), 1.2);
  auto valid = [&](int x, int y) { return x >= 0 && y >= 0 && x < light.cols && y < light.rows && light.at<float>(y, x) > 0; };
  auto at = [&](int x, int y) { return smooth.at<float>(y, x); };

  // 1. The shelf top: in each column, the strongest bright-above / dark-below step near the nominal row.
  struct Hit { double x, y; };
  std::vector<Hit> hits;
  const int y_lo = std::max(3, static_cast<int>(nominal.surface_y_px - 90));
  const int y_hi = std::min(light.rows - 4, static_cast<int>(nominal.surface_y_px + 40));
  for (int x = 4; x < light.cols - 4; x += 3) {
    double best = 0;
    int best_y = -1;
    for (int y = y_lo; y <= y_hi; ++y) {
      // Well inside the seen part: the blur mixes the unseen border in within ~4 px.
      if (!valid(x, y - 7) || !valid(x, y + 7) || !valid(x - 5, y) || !valid(x + 5, y)) continue;
      const double above = at(x, y - 3), below = at(x, y + 3);
      const double drop = (above - below) / std::max(1e-3, static_cast<double>(above));
      if (drop > best) {
        best = drop;
        best_y = y;
      }
    }
    if (best < 0.15 || best_y < 0) continue;  // no shelf in this column (glass all the way)
    // Sub-pixel: parabola through the step strength around the best row.
    auto step = [&](int y) { return static_cast<double>(at(x, y - 2) - at(x, y + 2)); };
    const double a = step(best_y - 1), b = step(best_y), c = step(best_y + 1);
    const double den = a - 2 * b + c;
    const double dy = std::abs(den) > 1e-9 ? std::clamp(0.5 * (a - c) / den, -0.5, 0.5) : 0.0;
    hits.push_back({static_cast<double>(x), best_y + dy});
  }
  if (hits.size() < 10) {
    out.message = "shelf top not seen (" + std::to_string(hits.size()) + " columns)";
    return out;
  }
  // The shelf occupies the left part: its end is where the run of hits starting at the left stops.
  std::sort(hits.begin(), hits.end(), [](const Hit& p, const Hit& q) { return p.x < q.x; });
  // A hit continues the run when it is near the run's last few hits' median height, not just the last hit's:
  // under harsh noise single columns' steps scatter by 3-5 px, and a run broken at one of them ended the shelf
  // a few blocks in (its end then not seen, the board frame left as given: the origin 0.14 block lengths off).
  std::vector<Hit> run;
  auto recent_y = [&run]() {
    std::vector<double> ys;
    for (size_t i = run.size() > 5 ? run.size() - 5 : 0; i < run.size(); ++i) ys.push_back(run[i].y);
    std::nth_element(ys.begin(), ys.begin() + ys.size() / 2, ys.end());
    return ys[ys.size() / 2];
  };
  for (const Hit& h : hits) {
    if (!run.empty() && (h.x - run.back().x > 12 || std::abs(h.y - recent_y()) > 4)) {
      if (run.size() >= 10) break;  // the first long run is the shelf
      run.clear();
    }
    run.push_back(h);
  }
  if (run.size() < 10) {
    out.message = "shelf top not continuous";
    return out;
  }
  // 2. Line fit y = m x + k (least squares, then once more without points more than 1 px off).
  auto fit_line = [](const std::vector<Hit>& pts, double& m, double& k) {
    double sx = 0, sy = 0, sxx = 0, sxy = 0;
    for (const Hit& p : pts) { sx += p.x; sy += p.y; sxx += p.x * p.x; sxy += p.x * p.y; }
    const double n = static_cast<double>(pts.size());
    const double den = n * sxx - sx * sx;
    m = std::abs(den) > 1e-9 ? (n * sxy - sx * sy) / den : 0.0;
    k = (sy - m * sx) / n;
  };
  // Leave out the last few columns before the end: the step fades there.
  std::vector<Hit> inner(run.begin(), run.end() - std::min<size_t>(3, run.size() / 4));
  double m = 0, k = 0;
  fit_line(inner, m, k);
  std::vector<Hit> kept;
  for (const Hit& h : inner) if (std::abs(h.y - (m * h.x + k)) < 1.0) kept.push_back(h);
  if (kept.size() >= 10) fit_line(kept, m, k);

  // 3. The shelf end: along a band just below the shelf top, the strongest dark-left / bright-right step.
  const double x_guess = run.back().x;
  double best = 0;
  int best_x = -1;
  std::vector<double> profile(light.cols, 0.0);
  for (int x = 2; x < light.cols - 2; ++x) {
    double sum = 0;
    int n = 0;
    for (int d = 3; d <= 15; ++d) {
      const int y = static_cast<int>(std::lround(m * x + k)) + d;
      if (!valid(x - 5, y) || !valid(x + 5, y) || !valid(x, y + 4)) break;  // a thinner band near the frame bottom
      sum += at(x, y);
      ++n;
    }
    if (n < 3) n = 0;
    profile[x] = n > 0 ? sum / n : -1;
  }
  for (int x = std::max(4, static_cast<int>(x_guess) - 15); x <= std::min(light.cols - 5, static_cast<int>(x_guess) + 15); ++x) {
    if (profile[x - 3] < 0 || profile[x + 3] < 0) continue;
    const double rise = (profile[x + 3] - profile[x - 3]) / std::max(1e-3, profile[x + 3]);
    if (rise > best) {
      best = rise;
      best_x = x;
    }
  }
  if (best < 0.15 || best_x < 0) {
    out.message = "shelf end not seen";
    return out;
  }
  auto rise_at = [&](int x) { return profile[x + 2] - profile[x - 2]; };
  const double a = rise_at(best_x - 1), b = rise_at(best_x), c = rise_at(best_x + 1);
  const double den = a - 2 * b + c;
  const double dx = std::abs(den) > 1e-9 ? std::clamp(0.5 * (a - c) / den, -0.5, 0.5) : 0.0;
  const double edge = best_x + dx;
  out.found = true;
  out.corner = cv::Point2d(edge, m * edge + k);
  out.angle_rad = std::atan(m);
  out.columns = static_cast<int>(kept.size());
  out.message = "shelf corner at (" + fmt(out.corner.x, 1) + ", " + fmt(out.corner.y, 1) + ") rectified px, tilt " +
                fmt(out.angle_rad * 180 / M_PI, 2) + " degrees";
  return out;
}

bricklayer::command_t self_check_command() { return show(bricklayer::command_t::PATTERN_MARKERS, kMarkerSetSelfCheck, 0, 0, 0); }

SelfCheckResult self_check(const bricklayer::calibration_t& cal, const cv::Mat& frame) {
  SelfCheckResult r;
  const cv::Size projector_size(cal.projector_width, cal.projector_height);
  auto points = detect_marker_correspondences(frame, kMarkerSetSelfCheck, projector_size);
  recentre_undistorted(points, cal);  // large markers: the distorted diagonals are visibly curved
  r.markers_found = static_cast<int>(points.size());
  if (points.empty()) {
    r.message = "self-check: no self-check marker seen (is the board empty and the projector showing the check?)";
    return r;
  }
  double sum = 0;
  for (const auto& p : points) {
    const double e = cv::norm(camera_to_projector(cal, p.camera) - p.projector);
    sum += e;
    r.drift_max_px = std::max(r.drift_max_px, e);
  }
  r.measured = true;
  r.drift_mean_px = sum / points.size();
  r.message = "self-check: " + std::to_string(r.markers_found) + " markers, drift mean " + fmt(r.drift_mean_px, 2) +
              " px, max " + fmt(r.drift_max_px, 2) + " px (projector pixels)";
  return r;
}

}  // namespace bricklayer::calibration
