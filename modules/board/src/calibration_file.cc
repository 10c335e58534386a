#include "bricklayer/board/calibration_file.h"

#include <nlohmann/json.hpp>

#include <opencv2/core.hpp>

#include <array>
#include <cmath>
#include <cstdio>
#include <fstream>
#include <limits>
#include <set>
#include <sstream>

#include "bricklayer/board/board_geometry.h"
#include "bricklayer/board/mapping.h"

namespace bricklayer::board {
namespace {

using nlohmann::json;

constexpr const char* kFormat = "bricklayer-calibration";
constexpr int kVersion = 1;
constexpr size_t kMaxFileBytes = 1 << 20;

[[noreturn]] void fail(const std::string& what) { throw CalibrationFileError("calibration: " + what); }

std::string fmt(double v) {
  std::ostringstream out;
  out << v;
  return out.str();
}

void check_finite(const char* name, const double* values, int count) {
  for (int i = 0; i < count; ++i) {
    if (!std::isfinite(values[i])) fail(std::string(name) + "[" + std::to_string(i) + "] is not a finite number");
  }
}

void check_size(const char* name, int32_t value) {
  if (value < 16 || value > 8192) fail(std::string(name) + " = " + std::to_string(value) + " out of range 16..8192");
}

// A homography must be invertible and keep every point of the camera image on one side of its
// horizon (w > 0 after normalising), or it folds the image over itself.
void check_homography(const char* name, const double* h, int width, int height) {
  check_finite(name, h, 9);
  cv::Matx33d m(h);
  const double norm = cv::norm(m);
  if (norm == 0) fail(std::string(name) + " is all zeros");
  m *= 1.0 / norm;
  const double det = cv::determinant(m);
  if (std::abs(det) < 1e-12) fail(std::string(name) + " is singular (determinant " + fmt(det) + " after normalising)");
  const cv::Matx33d inv = m.inv();
  if (!std::isfinite(cv::norm(inv)) || cv::norm(inv) > 1e12) fail(std::string(name) + " is ill-conditioned (not invertible)");
  double sign = 0;
  const double xs[4] = {0.0, double(width), double(width), 0.0};
  const double ys[4] = {0.0, 0.0, double(height), double(height)};
  for (int i = 0; i < 4; ++i) {
    const double w = m(2, 0) * xs[i] + m(2, 1) * ys[i] + m(2, 2);
    if (std::abs(w) < 1e-12) fail(std::string(name) + " sends a camera corner to infinity");
    if (sign == 0) sign = w;
    if ((w > 0) != (sign > 0)) fail(std::string(name) + " has its horizon inside the camera image (folds the image over)");
  }
}

// The radial distortion must be monotonic out to the image corners, else undistortion is ambiguous.
void check_lens(const bricklayer::calibration_t& cal) {
  const double* k = cal.camera_matrix;
  check_finite("camera_matrix", k, 4);
  check_finite("distortion", cal.distortion, 5);
  if (k[0] <= 0 || k[1] <= 0) fail("camera_matrix focal lengths must be positive (got fx=" + fmt(k[0]) + ", fy=" + fmt(k[1]) + ")");
  if (k[0] > 100.0 * cal.camera_width || k[1] > 100.0 * cal.camera_width) fail("camera_matrix focal length implausibly large (more than 100 x the image width)");
  if (k[2] < 0 || k[2] > cal.camera_width || k[3] < 0 || k[3] > cal.camera_height) {
    fail("camera_matrix principal point (" + fmt(k[2]) + ", " + fmt(k[3]) + ") outside the " +
         std::to_string(cal.camera_width) + "x" + std::to_string(cal.camera_height) + " image");
  }
  const double* d = cal.distortion;
  for (int i = 0; i < 5; ++i) {
    const double limit = (i == 2 || i == 3) ? 0.5 : 10.0;
    if (std::abs(d[i]) > limit) fail("distortion[" + std::to_string(i) + "] = " + fmt(d[i]) + " implausible (|value| > " + fmt(limit) + ")");
  }
  const double rx = std::max(k[2], cal.camera_width - k[2]) / k[0];
  const double ry = std::max(k[3], cal.camera_height - k[3]) / k[1];
  const double r_max = std::sqrt(rx * rx + ry * ry) * 1.05;
  double previous = 0;
  for (int i = 1; i <= 200; ++i) {
    const double r = r_max * i / 200.0;
    const double r2 = r * r;
    const double distorted = r * (1 + r2 * (d[0] + r2 * (d[1] + r2 * d[4])));
    if (distorted <= previous) fail("distortion folds over inside the image (radial model not monotonic at r = " + fmt(r) + ")");
    previous = distorted;
  }
}

void check_all(const bricklayer::calibration_t& cal) {
  if (cal.utime < 0) fail("utime must not be negative");
  check_size("camera_width", cal.camera_width);
  check_size("camera_height", cal.camera_height);
  check_size("projector_width", cal.projector_width);
  check_size("projector_height", cal.projector_height);
  check_lens(cal);
  check_homography("camera_to_projector", cal.camera_to_projector, cal.camera_width, cal.camera_height);
  check_homography("camera_to_board", cal.camera_to_board, cal.camera_width, cal.camera_height);
  check_finite("colour_mixing", cal.colour_mixing, 9);
  for (int i = 0; i < 9; ++i) {
    if (cal.colour_mixing[i] < -0.5 || cal.colour_mixing[i] > 5.0) fail("colour_mixing[" + std::to_string(i) + "] = " + fmt(cal.colour_mixing[i]) + " outside -0.5..5");
  }
  for (int i = 0; i < 3; ++i) {
    if (cal.colour_mixing[4 * i] <= 0) fail("colour_mixing diagonal entry " + std::to_string(i) + " must be positive (a projector channel the camera does not see)");
  }
  const double det = cv::determinant(colour_mixing(cal));
  if (!(std::abs(det) > 1e-6)) fail("colour_mixing is singular (determinant " + fmt(det) + ")");
  check_finite("ambient_bgr", cal.ambient_bgr, 3);
  for (int i = 0; i < 3; ++i) {
    if (cal.ambient_bgr[i] < 0 || cal.ambient_bgr[i] > 255) fail("ambient_bgr[" + std::to_string(i) + "] = " + fmt(cal.ambient_bgr[i]) + " outside 0..255");
  }
  if (!std::isfinite(cal.block_height) || cal.block_height <= 0 || cal.block_height > 10) fail("block_height = " + fmt(cal.block_height) + " outside (0, 10] block lengths");
  const double mean = cal.reprojection_error_mean_px;
  const double max = cal.reprojection_error_max_px;
  if (!std::isfinite(mean) || !std::isfinite(max) || mean < 0 || max < 0) fail("reprojection errors must be finite and non-negative");
  if (mean > max + 1e-9) fail("reprojection_error_mean_px (" + fmt(mean) + ") exceeds reprojection_error_max_px (" + fmt(max) + ")");
  check_finite("board_x_accuracy", cal.board_x_accuracy, 3);
  for (int i = 0; i < 3; ++i) {
    // A bound of a block length or more per block length says nothing a knife-edge verdict could use.
    if (cal.board_x_accuracy[i] < 0 || cal.board_x_accuracy[i] > 1)
      fail("board_x_accuracy[" + std::to_string(i) + "] = " + fmt(cal.board_x_accuracy[i]) + " outside 0..1 block lengths");
  }
}

bool accuracy_stated(const bricklayer::calibration_t& cal) {
  return cal.board_x_accuracy[0] != 0 || cal.board_x_accuracy[1] != 0 || cal.board_x_accuracy[2] != 0;
}

// Optional: written only once the scale step stated it, so files without it (older ones, and every file
// before the scale step) load as "not stated", and files of unscaled calibrations stay readable by older builds.
constexpr const char* kAccuracyKey = "board_x_accuracy";

const std::array<const char*, 16> kKeys = {
    "format", "version", "utime", "camera_width", "camera_height", "projector_width", "projector_height",
    "camera_matrix", "distortion", "camera_to_projector", "camera_to_board", "colour_mixing",
    "ambient_bgr", "block_height", "reprojection_error_mean_px", "reprojection_error_max_px"};

template <typename T>
T get_integer(const json& j, const char* key) {
  const json& v = j.at(key);
  if (!v.is_number_integer()) fail(std::string("\"") + key + "\" must be an integer");
  if (v.is_number_unsigned()) {
    const auto u = v.get<uint64_t>();
    if (u > static_cast<uint64_t>(std::numeric_limits<T>::max())) fail(std::string("\"") + key + "\" out of range");
    return static_cast<T>(u);
  }
  const auto s = v.get<int64_t>();
  if (s < std::numeric_limits<T>::min() || s > std::numeric_limits<T>::max()) fail(std::string("\"") + key + "\" out of range");
  return static_cast<T>(s);
}

double get_number(const json& v, const std::string& what) {
  if (!v.is_number()) fail(what + " must be a number");
  const double d = v.get<double>();
  if (!std::isfinite(d)) fail(what + " is not a finite number");
  return d;
}

void get_array(const json& j, const char* key, double* out, size_t count) {
  const json& v = j.at(key);
  if (!v.is_array() || v.size() != count) {
    fail(std::string("\"") + key + "\" must be an array of " + std::to_string(count) + " numbers" +
         (v.is_array() ? " (got " + std::to_string(v.size()) + ")" : ""));
  }
  for (size_t i = 0; i < count; ++i) out[i] = get_number(v[i], std::string("\"") + key + "\"[" + std::to_string(i) + "]");
}

}  // namespace

void validate_calibration(const bricklayer::calibration_t& cal) { check_all(cal); }

bricklayer::calibration_t default_calibration() {
  bricklayer::calibration_t cal{};
  cal.utime = 0;
  cal.camera_width = kDefaultCameraWidth;
  cal.camera_height = kDefaultCameraHeight;
  cal.projector_width = kDefaultProjectorWidth;
  cal.projector_height = kDefaultProjectorHeight;
  cal.camera_matrix[0] = 0.875 * kDefaultCameraWidth;
  cal.camera_matrix[1] = 0.875 * kDefaultCameraWidth;
  cal.camera_matrix[2] = (kDefaultCameraWidth - 1) / 2.0;
  cal.camera_matrix[3] = (kDefaultCameraHeight - 1) / 2.0;
  for (int i = 0; i < 9; ++i) cal.camera_to_projector[i] = kDefaultCameraToProjector[i];
  const BoardGeometry board;
  const auto to_board = board.camera_to_board();
  for (int i = 0; i < 9; ++i) cal.camera_to_board[i] = to_board[i];
  const double mixing[9] = {0.55, 0.10, 0.02, 0.12, 0.60, 0.14, 0.02, 0.08, 0.58};
  for (int i = 0; i < 9; ++i) cal.colour_mixing[i] = mixing[i];
  for (int i = 0; i < 3; ++i) cal.ambient_bgr[i] = 4.0;
  cal.block_height = board.block_height_px / board.block_length_px;
  return cal;
}

bricklayer::calibration_t parse_calibration_json(const std::string& text) {
  if (text.size() > kMaxFileBytes) fail("file larger than 1 MB (" + std::to_string(text.size()) + " bytes); not a calibration file");
  json j;
  try {
    j = json::parse(text);
  } catch (const json::exception& e) {
    fail(std::string("not valid JSON: ") + e.what());
  }
  if (!j.is_object()) fail("top level must be a JSON object");
  const std::set<std::string> known(kKeys.begin(), kKeys.end());
  for (auto it = j.begin(); it != j.end(); ++it) {
    if (!known.count(it.key()) && it.key() != kAccuracyKey) fail("unknown key \"" + it.key() + "\" (expected exactly: format, version, utime, camera_width, ...)");
  }
  for (const char* key : kKeys) {
    if (!j.contains(key)) fail(std::string("missing key \"") + key + "\" (every key is required)");
  }
  if (!j.at("format").is_string() || j.at("format").get<std::string>() != kFormat) fail(std::string("\"format\" must be \"") + kFormat + "\"");
  if (get_integer<int32_t>(j, "version") != kVersion) fail("\"version\" " + j.at("version").dump() + " not supported (this build reads version 1)");

  bricklayer::calibration_t cal{};
  cal.utime = get_integer<int64_t>(j, "utime");
  cal.camera_width = get_integer<int32_t>(j, "camera_width");
  cal.camera_height = get_integer<int32_t>(j, "camera_height");
  cal.projector_width = get_integer<int32_t>(j, "projector_width");
  cal.projector_height = get_integer<int32_t>(j, "projector_height");
  get_array(j, "camera_matrix", cal.camera_matrix, 4);
  get_array(j, "distortion", cal.distortion, 5);
  get_array(j, "camera_to_projector", cal.camera_to_projector, 9);
  get_array(j, "camera_to_board", cal.camera_to_board, 9);
  get_array(j, "colour_mixing", cal.colour_mixing, 9);
  get_array(j, "ambient_bgr", cal.ambient_bgr, 3);
  cal.block_height = get_number(j.at("block_height"), "\"block_height\"");
  cal.reprojection_error_mean_px = get_number(j.at("reprojection_error_mean_px"), "\"reprojection_error_mean_px\"");
  cal.reprojection_error_max_px = get_number(j.at("reprojection_error_max_px"), "\"reprojection_error_max_px\"");
  if (j.contains(kAccuracyKey)) get_array(j, kAccuracyKey, cal.board_x_accuracy, 3);
  check_all(cal);
  return cal;
}

std::string calibration_to_json(const bricklayer::calibration_t& cal) {
  check_all(cal);
  auto arr = [](const double* v, int n) { return std::vector<double>(v, v + n); };
  json j;
  j["format"] = kFormat;
  j["version"] = kVersion;
  j["utime"] = cal.utime;
  j["camera_width"] = cal.camera_width;
  j["camera_height"] = cal.camera_height;
  j["projector_width"] = cal.projector_width;
  j["projector_height"] = cal.projector_height;
  j["camera_matrix"] = arr(cal.camera_matrix, 4);
  j["distortion"] = arr(cal.distortion, 5);
  j["camera_to_projector"] = arr(cal.camera_to_projector, 9);
  j["camera_to_board"] = arr(cal.camera_to_board, 9);
  j["colour_mixing"] = arr(cal.colour_mixing, 9);
  j["ambient_bgr"] = arr(cal.ambient_bgr, 3);
  j["block_height"] = cal.block_height;
  j["reprojection_error_mean_px"] = cal.reprojection_error_mean_px;
  j["reprojection_error_max_px"] = cal.reprojection_error_max_px;
  if (accuracy_stated(cal)) j[kAccuracyKey] = arr(cal.board_x_accuracy, 3);
  return j.dump(2) + "\n";
}

bricklayer::calibration_t load_calibration(const std::string& path) {
  std::ifstream in(path, std::ios::binary);
  if (!in) throw CalibrationFileError("calibration file " + path + ": cannot open (run bricklayer-calibrate to create it)");
  std::string text;
  char buffer[65536];
  while (in.read(buffer, sizeof buffer) || in.gcount() > 0) {
    text.append(buffer, static_cast<size_t>(in.gcount()));
    if (text.size() > kMaxFileBytes) throw CalibrationFileError("calibration file " + path + ": larger than 1 MB; not a calibration file");
  }
  try {
    return parse_calibration_json(text);
  } catch (const CalibrationFileError& e) {
    throw CalibrationFileError("calibration file " + path + ": " + e.what());
  }
}

void save_calibration(const std::string& path, const bricklayer::calibration_t& cal) {
  const std::string text = calibration_to_json(cal);
  const std::string tmp = path + ".tmp";
  {
    std::ofstream out(tmp, std::ios::binary | std::ios::trunc);
    if (!out) throw CalibrationFileError("calibration file " + tmp + ": cannot write");
    out << text;
    out.flush();
    if (!out) throw CalibrationFileError("calibration file " + tmp + ": write failed");
  }
  if (std::rename(tmp.c_str(), path.c_str()) != 0) {
    std::remove(tmp.c_str());
    throw CalibrationFileError("calibration file " + path + ": cannot rename " + tmp + " over it");
  }
}

}  // namespace bricklayer::board
