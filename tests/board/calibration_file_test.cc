// The calibration file: round trip, and every kind of bad file rejected with a message naming it.
#include <catch2/catch.hpp>

#include <nlohmann/json.hpp>

#include <cstdio>
#include <fstream>
#include <string>
#include <unistd.h>

#include "bricklayer/board/calibration_file.h"
#include "bricklayer/board/mapping.h"

namespace board = bricklayer::board;
using nlohmann::json;

namespace {

json valid_json() {
  bricklayer::calibration_t c = board::default_calibration();
  c.distortion[0] = -0.08;
  c.distortion[1] = 0.01;
  c.reprojection_error_mean_px = 0.2;
  c.reprojection_error_max_px = 0.9;
  c.utime = 1763780000000000;
  return json::parse(board::calibration_to_json(c));
}

// Parses j and returns the error message ("" when it parsed).
std::string error_of(const json& j) {
  try {
    board::parse_calibration_json(j.dump());
    return "";
  } catch (const board::CalibrationFileError& e) {
    return e.what();
  }
}

std::string temp_path(const std::string& name) {
  return std::string("/tmp/bricklayer-calibration-test-") + std::to_string(::getpid()) + "-" + name;
}

}  // namespace

TEST_CASE("A calibration survives save and load exactly") {
  const json j = valid_json();
  const bricklayer::calibration_t c = board::parse_calibration_json(j.dump());
  const std::string path = temp_path("roundtrip.json");
  board::save_calibration(path, c);
  const bricklayer::calibration_t back = board::load_calibration(path);
  std::remove(path.c_str());
  CHECK(back.utime == c.utime);
  CHECK(back.camera_width == 640);
  CHECK(back.projector_height == 768);
  for (int i = 0; i < 9; ++i) {
    CHECK(back.camera_to_projector[i] == c.camera_to_projector[i]);
    CHECK(back.camera_to_board[i] == c.camera_to_board[i]);
    CHECK(back.colour_mixing[i] == c.colour_mixing[i]);
  }
  for (int i = 0; i < 5; ++i) CHECK(back.distortion[i] == c.distortion[i]);
  CHECK(back.reprojection_error_max_px == 0.9);
  // The mapping round-trips through the lens and the homography.
  const cv::Point2d p(601.5, 17.25);
  CHECK(cv::norm(board::camera_to_projector(back, board::projector_to_camera(back, p)) - p) < 1e-6);
  // The default maps like the shared default setup: projector = 1.6 x camera, board from BoardGeometry.
  const auto d = board::default_calibration();
  CHECK(cv::norm(board::camera_to_projector(d, {100, 200}) - cv::Point2d(160, 320)) < 1e-9);
  CHECK(cv::norm(board::camera_to_board(d, {320, 440}) - cv::Point2d(0, 0)) < 1e-9);
  CHECK(cv::norm(board::camera_to_board(d, {380, 380}) - cv::Point2d(1, 1)) < 1e-9);
}

TEST_CASE("The board x accuracy is optional: written when stated, a file without it loads as not stated") {
  // A file from before the scale step (or from before the key existed) has no board_x_accuracy.
  const json old = valid_json();
  CHECK_FALSE(old.contains("board_x_accuracy"));
  const bricklayer::calibration_t c = board::parse_calibration_json(old.dump());
  for (int i = 0; i < 3; ++i) CHECK(c.board_x_accuracy[i] == 0.0);
  // Stated: written, and read back exactly.
  bricklayer::calibration_t stated = c;
  stated.board_x_accuracy[0] = 0.006;
  stated.board_x_accuracy[1] = 0.0021;
  stated.board_x_accuracy[2] = 0.0037;
  const json j = json::parse(board::calibration_to_json(stated));
  REQUIRE(j.contains("board_x_accuracy"));
  CHECK(j["board_x_accuracy"].size() == 3);
  const bricklayer::calibration_t back = board::parse_calibration_json(j.dump());
  CHECK(back.board_x_accuracy[0] == 0.006);
  CHECK(back.board_x_accuracy[1] == 0.0021);
  CHECK(back.board_x_accuracy[2] == 0.0037);
  // The bus carries it too (validate_calibration judges what vision receives).
  stated.board_x_accuracy[2] = -1.0;
  CHECK_THROWS_WITH(board::validate_calibration(stated), Catch::Contains("board_x_accuracy[2]"));
}

TEST_CASE("Every key is required and unknown keys are refused") {
  CHECK(error_of(valid_json()).empty());
  const json base = valid_json();
  std::vector<std::string> keys;
  for (auto it = base.begin(); it != base.end(); ++it) keys.push_back(it.key());
  CHECK(keys.size() == 16);
  for (const std::string& key : keys) {
    json j = base;
    j.erase(key);
    const std::string e = error_of(j);
    INFO(e);
    CHECK(e.find("missing key \"" + key + "\"") != std::string::npos);
  }
  json j = valid_json();
  j["camera_to_projektor"] = j["camera_to_projector"];
  CHECK(error_of(j).find("unknown key \"camera_to_projektor\"") != std::string::npos);
}

TEST_CASE("Bad values are rejected with a message naming them") {
  struct Case {
    const char* what;
    std::function<void(json&)> spoil;
    const char* expect;
  };
  const std::vector<Case> cases = {
      {"wrong format", [](json& j) { j["format"] = "something-else"; }, "\"format\""},
      {"future version", [](json& j) { j["version"] = 2; }, "\"version\""},
      {"width as text", [](json& j) { j["camera_width"] = "640"; }, "\"camera_width\" must be an integer"},
      {"width fractional", [](json& j) { j["camera_width"] = 640.5; }, "\"camera_width\" must be an integer"},
      {"width huge", [](json& j) { j["camera_width"] = 1LL << 40; }, "\"camera_width\" out of range"},
      {"tiny projector", [](json& j) { j["projector_width"] = 8; }, "projector_width = 8 out of range"},
      {"short matrix", [](json& j) { j["camera_to_projector"].erase(8); }, "\"camera_to_projector\" must be an array of 9 numbers (got 8)"},
      {"not an array", [](json& j) { j["distortion"] = 0.1; }, "\"distortion\" must be an array of 5 numbers"},
      {"string in array", [](json& j) { j["colour_mixing"][4] = "x"; }, "\"colour_mixing\"[4] must be a number"},
      {"null in array", [](json& j) { j["ambient_bgr"][0] = nullptr; }, "\"ambient_bgr\"[0] must be a number"},
      {"negative focal", [](json& j) { j["camera_matrix"][0] = -500.0; }, "focal lengths must be positive"},
      {"principal point outside", [](json& j) { j["camera_matrix"][2] = 900.0; }, "principal point"},
      {"folding lens", [](json& j) { j["distortion"][0] = -3.0; j["distortion"][1] = 0.0; }, "folds over"},
      {"singular homography", [](json& j) { j["camera_to_projector"] = {1, 2, 3, 2, 4, 6, 0, 0, 1}; }, "camera_to_projector is singular"},
      {"zero homography", [](json& j) { j["camera_to_board"] = {0, 0, 0, 0, 0, 0, 0, 0, 0}; }, "camera_to_board is all zeros"},
      {"horizon in image", [](json& j) { j["camera_to_projector"] = {1, 0, 0, 0, 1, 0, -0.01, 0, 1}; }, "horizon inside the camera image"},
      {"singular mixing", [](json& j) { j["colour_mixing"] = {0.5, 0.5, 0, 0.5, 0.5, 0, 0, 0, 0.5}; }, "colour_mixing is singular"},
      {"dark channel", [](json& j) { j["colour_mixing"][8] = 0.0; }, "diagonal entry 2 must be positive"},
      {"ambient too bright", [](json& j) { j["ambient_bgr"][1] = 300.0; }, "ambient_bgr[1] = 300 outside 0..255"},
      {"block height zero", [](json& j) { j["block_height"] = 0.0; }, "block_height = 0"},
      {"mean above max", [](json& j) { j["reprojection_error_mean_px"] = 2.0; }, "exceeds reprojection_error_max_px"},
      {"negative error", [](json& j) { j["reprojection_error_max_px"] = -1.0; }, "non-negative"},
      {"negative utime", [](json& j) { j["utime"] = -5; }, "utime must not be negative"},
      {"accuracy short", [](json& j) { j["board_x_accuracy"] = {0.01, 0.002}; }, "\"board_x_accuracy\" must be an array of 3 numbers (got 2)"},
      {"accuracy negative", [](json& j) { j["board_x_accuracy"] = {0.01, -0.002, 0.0}; }, "board_x_accuracy[1] = -0.002 outside 0..1"},
      {"accuracy huge", [](json& j) { j["board_x_accuracy"] = {2.0, 0.0, 0.0}; }, "board_x_accuracy[0] = 2 outside 0..1"},
  };
  for (const Case& c : cases) {
    json j = valid_json();
    c.spoil(j);
    const std::string e = error_of(j);
    INFO(c.what << ": " << e);
    CHECK(e.find(c.expect) != std::string::npos);
    CHECK(e.rfind("calibration: ", 0) == 0);
  }
}

TEST_CASE("Text that is not a calibration file is rejected") {
  auto error_of_text = [](const std::string& text) {
    try {
      board::parse_calibration_json(text);
      return std::string();
    } catch (const board::CalibrationFileError& e) {
      return std::string(e.what());
    }
  };
  CHECK(error_of_text("").find("not valid JSON") != std::string::npos);
  CHECK(error_of_text("{\"format\": ").find("not valid JSON") != std::string::npos);
  CHECK(error_of_text("[1, 2, 3]").find("top level must be a JSON object") != std::string::npos);
  CHECK(error_of_text(std::string(2 << 20, ' ')).find("larger than 1 MB") != std::string::npos);
  CHECK_FALSE(error_of_text(std::string(100000, '[')).empty());  // deep nesting: an error, not a crash
  std::string huge = valid_json().dump();
  const auto at = huge.find("\"block_height\":");
  REQUIRE(at != std::string::npos);
  huge.insert(at + 15, "1e999");  // an overflowing number before the real value: invalid either way
  CHECK_FALSE(error_of_text(huge).empty());

  const std::string missing = temp_path("does-not-exist.json");
  try {
    board::load_calibration(missing);
    FAIL("loaded a missing file");
  } catch (const board::CalibrationFileError& e) {
    CHECK(std::string(e.what()).find(missing) != std::string::npos);
    CHECK(std::string(e.what()).find("bricklayer-calibrate") != std::string::npos);
  }
  const std::string broken = temp_path("broken.json");
  std::ofstream(broken) << "{\"format\": \"bricklayer-calibration\"}";
  try {
    board::load_calibration(broken);
    FAIL("loaded a broken file");
  } catch (const board::CalibrationFileError& e) {
    CHECK(std::string(e.what()).find(broken) != std::string::npos);
    CHECK(std::string(e.what()).find("missing key") != std::string::npos);
  }
  std::remove(broken.c_str());
  // save refuses an invalid calibration and leaves no file behind.
  bricklayer::calibration_t bad = board::default_calibration();
  bad.camera_to_projector[8] = std::nan("");
  const std::string target = temp_path("invalid.json");
  CHECK_THROWS_AS(board::save_calibration(target, bad), board::CalibrationFileError);
  CHECK_FALSE(std::ifstream(target).good());
}
