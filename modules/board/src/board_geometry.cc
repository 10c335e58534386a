#include "bricklayer/board/board_geometry.h"

#include <cmath>
#include <fstream>
#include <set>
#include <sstream>
#include <stdexcept>

#include <nlohmann/json.hpp>

namespace bricklayer {

BoardGeometry parse_board_geometry(const std::string& json_text) {
  nlohmann::json j;
  try {
    j = nlohmann::json::parse(json_text);
  } catch (const nlohmann::json::exception& e) {
    throw std::runtime_error(std::string("board geometry is not valid JSON: ") + e.what());
  }
  if (!j.is_object()) throw std::runtime_error("board geometry must be a JSON object");
  const std::set<std::string> keys = {"edge_x_px", "surface_y_px", "block_length_px", "block_height_px"};
  for (const auto& [key, value] : j.items()) {
    if (!keys.count(key)) throw std::runtime_error("board geometry: unknown key '" + key + "'");
  }
  auto number = [&](const char* key) {
    if (!j.contains(key)) throw std::runtime_error(std::string("board geometry: missing key '") + key + "'");
    if (!j[key].is_number()) throw std::runtime_error(std::string("board geometry: '") + key + "' must be a number");
    double v = j[key].get<double>();
    if (!std::isfinite(v)) throw std::runtime_error(std::string("board geometry: '") + key + "' must be finite");
    return v;
  };
  BoardGeometry g;
  g.edge_x_px = number("edge_x_px");
  g.surface_y_px = number("surface_y_px");
  g.block_length_px = number("block_length_px");
  g.block_height_px = number("block_height_px");
  if (g.block_length_px <= 0 || g.block_height_px <= 0)
    throw std::runtime_error("board geometry: block_length_px and block_height_px must be positive");
  return g;
}

BoardGeometry load_board_geometry(const std::string& path) {
  std::ifstream in(path);
  if (!in) throw std::runtime_error("cannot read board geometry file '" + path + "'");
  std::stringstream text;
  text << in.rdbuf();
  return parse_board_geometry(text.str());
}

}  // namespace bricklayer
