#include "bricklayer/simcam/scenario.h"

#include <cmath>
#include <fstream>
#include <set>
#include <sstream>
#include <stdexcept>

#include <nlohmann/json.hpp>

namespace bricklayer::simcam {
namespace {

void check_keys(const nlohmann::json& object, const std::set<std::string>& allowed, const std::string& where) {
  for (const auto& [key, value] : object.items()) {
    if (!allowed.count(key)) throw std::runtime_error(where + ": unknown key '" + key + "'");
  }
}

double finite_number(const nlohmann::json& value, const std::string& what) {
  if (!value.is_number()) throw std::runtime_error(what + " must be a number");
  double v = value.get<double>();
  if (!std::isfinite(v)) throw std::runtime_error(what + " must be finite");
  return v;
}

}  // namespace

const core::Stack& Scenario::stack_at(double t) const {
  size_t index = 0;
  for (size_t i = 0; i < keyframes.size(); ++i) {
    if (keyframes[i].t <= t) index = i;
  }
  return keyframes[index].stack;
}

Scenario parse_scenario(const std::string& json_text, const std::string& name) {
  nlohmann::json j;
  try {
    j = nlohmann::json::parse(json_text);
  } catch (const nlohmann::json::exception& e) {
    throw std::runtime_error(name + ": not valid JSON: " + e.what());
  }
  if (!j.is_object()) throw std::runtime_error(name + ": a scenario must be a JSON object");
  check_keys(j, {"description", "nuisance", "seed", "duration_s", "block_height", "keyframes"}, name);

  Scenario s;
  if (j.contains("description")) {
    if (!j["description"].is_string()) throw std::runtime_error(name + ": 'description' must be a string");
    s.description = j["description"].get<std::string>();
  }
  try {
    s.nuisance = Nuisance::named(j.value("nuisance", std::string("clean")));
  } catch (const std::exception& e) {
    throw std::runtime_error(name + ": " + e.what());
  }
  if (j.contains("seed")) {
    if (!j["seed"].is_number_unsigned()) throw std::runtime_error(name + ": 'seed' must be a non-negative integer");
    s.seed = j["seed"].get<uint64_t>();
  }
  double block_height = 1.0 / 3.0;
  if (j.contains("block_height")) {
    block_height = finite_number(j["block_height"], name + ": 'block_height'");
    if (block_height <= 0) throw std::runtime_error(name + ": 'block_height' must be positive");
  }
  if (!j.contains("keyframes") || !j["keyframes"].is_array() || j["keyframes"].empty())
    throw std::runtime_error(name + ": 'keyframes' must be a non-empty array");

  core::StackLimits limits;
  double previous_t = -1.0;
  for (size_t k = 0; k < j["keyframes"].size(); ++k) {
    const auto& key = j["keyframes"][k];
    const std::string where = name + ": key frame " + std::to_string(k);
    if (!key.is_object()) throw std::runtime_error(where + " must be an object");
    check_keys(key, {"t", "blocks"}, where);
    if (!key.contains("t")) throw std::runtime_error(where + ": missing 't'");
    KeyFrame frame;
    frame.t = finite_number(key["t"], where + ": 't'");
    if (frame.t < 0 || frame.t <= previous_t)
      throw std::runtime_error(where + ": 't' must be >= 0 and later than the previous key frame");
    previous_t = frame.t;
    nlohmann::json stack_json = {{"block_length", 1.0}, {"block_height", block_height}, {"table_edge", 0.0},
                                 {"blocks", key.value("blocks", nlohmann::json::array())}};
    try {
      frame.stack = core::stack_from_json(stack_json, limits);
    } catch (const std::exception& e) {
      throw std::runtime_error(where + ": " + e.what());
    }
    s.keyframes.push_back(std::move(frame));
  }
  if (j.contains("duration_s")) {
    s.duration_s = finite_number(j["duration_s"], name + ": 'duration_s'");
    if (s.duration_s <= s.keyframes.back().t)
      throw std::runtime_error(name + ": 'duration_s' must be later than the last key frame");
  } else {
    s.duration_s = s.keyframes.back().t + 5.0;
  }
  return s;
}

Scenario load_scenario(const std::string& path) {
  std::ifstream in(path);
  if (!in) throw std::runtime_error("cannot read scenario file '" + path + "'");
  std::stringstream text;
  text << in.rdbuf();
  return parse_scenario(text.str(), path);
}

}  // namespace bricklayer::simcam
