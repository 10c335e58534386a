#include "bricklayer/projection/best_overhang.h"

#include <cmath>
#include <fstream>
#include <sstream>
#include <stdexcept>

#include <nlohmann/json.hpp>

namespace bricklayer::projection {

BestOverhang BestOverhang::parse(const std::string& json_text) {
  nlohmann::json j;
  try {
    j = nlohmann::json::parse(json_text);
  } catch (const nlohmann::json::exception& e) {
    throw std::runtime_error(std::string("best overhang table is not valid JSON: ") + e.what());
  }
  if (!j.is_object()) throw std::runtime_error("best overhang table must be a JSON object {\"1\": 0.5, ...}");
  BestOverhang out;
  for (const auto& [key, value] : j.items()) {
    size_t used = 0;
    int n = 0;
    try {
      n = std::stoi(key, &used);
    } catch (const std::exception&) {
      used = 0;
    }
    if (used != key.size() || n <= 0)
      throw std::runtime_error("best overhang table: key '" + key + "' is not a positive block count");
    if (!value.is_number() || !std::isfinite(value.get<double>()) || value.get<double>() <= 0)
      throw std::runtime_error("best overhang table: value for '" + key + "' must be a positive number");
    out.table_[n] = value.get<double>();
  }
  return out;
}

BestOverhang BestOverhang::load(const std::string& path) {
  std::ifstream in(path);
  if (!in) throw std::runtime_error("cannot read best overhang table '" + path + "'");
  std::stringstream text;
  text << in.rdbuf();
  return parse(text.str());
}

std::optional<double> BestOverhang::best_for(int num_blocks) const {
  auto it = table_.find(num_blocks);
  if (it == table_.end()) return std::nullopt;
  return it->second;
}

}  // namespace bricklayer::projection
