#include "bricklayer/study/problem.h"

#include <cmath>
#include <filesystem>
#include <fstream>
#include <sstream>

#include <nlohmann/json.hpp>

namespace bricklayer::study {
namespace {

double number(const nlohmann::json& value, const std::string& key) {
  if (!value.is_number()) throw ProblemError("\"" + key + "\" must be a number, got " + std::string(value.type_name()));
  const double v = value.get<double>();
  if (!std::isfinite(v)) throw ProblemError("\"" + key + "\" must be finite");
  return v;
}

int32_t integer(const nlohmann::json& value, const std::string& key, int64_t lo, int64_t hi) {
  if (!value.is_number_integer()) {
    throw ProblemError("\"" + key + "\" must be an integer, got " + std::string(value.type_name()));
  }
  const int64_t v = value.get<int64_t>();
  if (v < lo || v > hi) {
    throw ProblemError("\"" + key + "\" must be in " + std::to_string(lo) + ".." + std::to_string(hi) + ", got " +
                       std::to_string(v));
  }
  return static_cast<int32_t>(v);
}

std::string text(const nlohmann::json& value, const std::string& key) {
  if (!value.is_string()) throw ProblemError("\"" + key + "\" must be a string, got " + std::string(value.type_name()));
  return value.get<std::string>();
}

int64_t milliseconds(const nlohmann::json& value, const std::string& key) {
  const double s = number(value, key);
  if (s < 0 || s > 24 * 3600) throw ProblemError("\"" + key + "\" must be in 0..86400 seconds, got " + value.dump());
  return static_cast<int64_t>(std::llround(s * 1000.0));
}

std::vector<Placement> placements(const nlohmann::json& value) {
  if (!value.is_array()) throw ProblemError("\"solution\" must be an array of {\"row\", \"x\"}");
  std::vector<Placement> out;
  for (size_t i = 0; i < value.size(); ++i) {
    const auto& item = value[i];
    const std::string where = "solution[" + std::to_string(i) + "]";
    if (!item.is_object()) throw ProblemError(where + " must be an object with \"row\" and \"x\"");
    Placement p;
    bool row = false;
    bool x = false;
    for (const auto& [key, v] : item.items()) {
      if (key == "row") {
        p.row = integer(v, where + ".row", 0, 1000);
        row = true;
      } else if (key == "x") {
        p.x = number(v, where + ".x");
        x = true;
      } else if (key != "comment") {
        throw ProblemError(where + ": unknown key \"" + key + "\" (expected row, x, comment)");
      }
    }
    if (!row || !x) throw ProblemError(where + " needs both \"row\" and \"x\"");
    out.push_back(p);
  }
  return out;
}

}  // namespace

std::string to_string(ProblemKind kind) { return kind == ProblemKind::kStabilise ? "stabilise" : "score"; }

Problem parse_problem(std::string_view text_in, const std::string& fallback_name) {
  nlohmann::json json;
  try {
    json = nlohmann::json::parse(text_in);
  } catch (const nlohmann::json::exception& e) {
    throw ProblemError(std::string("not valid JSON: ") + e.what());
  }
  if (!json.is_object()) throw ProblemError("a problem file must hold one JSON object");
  Problem p;
  p.name = fallback_name;
  const auto kind = json.find("kind");
  if (kind == json.end()) throw ProblemError("missing key \"kind\" (\"stabilise\" or \"score\")");
  const std::string kind_name = text(*kind, "kind");
  if (kind_name == "stabilise") {
    p.kind = ProblemKind::kStabilise;
  } else if (kind_name == "score") {
    p.kind = ProblemKind::kScore;
  } else {
    throw ProblemError("\"kind\" must be \"stabilise\" or \"score\", got \"" + kind_name + "\"");
  }
  const bool stabilise = p.kind == ProblemKind::kStabilise;
  bool has_pile = false;
  bool has_minimum = false;
  bool has_score = false;
  bool has_blocks = false;
  for (const auto& [key_ref, value] : json.items()) {
    const std::string key = key_ref;  // a structured binding cannot be captured by a lambda (C++17; clang 14)
    auto only = [&](bool allowed) {
      if (!allowed) throw ProblemError("\"" + key + "\" does not belong in a \"" + kind_name + "\" problem");
    };
    if (key == "kind") {
    } else if (key == "name") {
      p.name = text(value, key);
      if (p.name.empty()) throw ProblemError("\"name\" must not be empty");
    } else if (key == "description") {
      p.description = text(value, key);
    } else if (key == "instruction") {
      p.instruction = text(value, key);
    } else if (key == "time_limit_s") {
      p.time_limit_ms = milliseconds(value, key);
    } else if (key == "pile") {
      only(stabilise);
      try {
        p.pile = normalised(core::stack_from_json(value));
      } catch (const core::StackError& e) {
        throw ProblemError(std::string("\"pile\": ") + e.what());
      }
      has_pile = true;
    } else if (key == "minimum_added") {
      only(stabilise);
      p.minimum_added = integer(value, key, 0, 100);
      has_minimum = true;
    } else if (key == "solution") {
      only(stabilise);
      p.solution = placements(value);
    } else if (key == "position_tolerance") {
      only(stabilise);
      p.position_tolerance = number(value, key);
      if (p.position_tolerance < 0 || p.position_tolerance > 0.05) {
        throw ProblemError("\"position_tolerance\" must be in 0..0.05 block lengths");
      }
    } else if (key == "match_tolerance") {
      only(stabilise);
      p.match_tolerance = number(value, key);
      if (p.match_tolerance <= 0 || p.match_tolerance > 0.5) {
        throw ProblemError("\"match_tolerance\" must be in (0, 0.5] block lengths");
      }
    } else if (key == "max_added") {
      only(stabilise);
      p.max_added = integer(value, key, 0, 4);
    } else if (key == "min_score") {
      only(!stabilise);
      p.min_score = integer(value, key, 1, 100000);
      has_score = true;
    } else if (key == "max_blocks") {
      only(!stabilise);
      p.max_blocks = integer(value, key, 1, 1000);
      has_blocks = true;
    } else if (key == "hold_s") {
      only(!stabilise);
      p.hold_ms = milliseconds(value, key);
    } else if (key == "comment") {
    } else {
      throw ProblemError("unknown key \"" + key +
                         "\" (expected kind, name, description, instruction, time_limit_s, and for stabilise: pile, "
                         "minimum_added, solution, position_tolerance, match_tolerance, max_added; for score: "
                         "min_score, max_blocks, hold_s)");
    }
  }
  if (p.instruction.empty()) throw ProblemError("missing key \"instruction\" (what the display tells the subject)");
  if (stabilise) {
    if (!has_pile) throw ProblemError("missing key \"pile\"");
    if (p.pile.blocks.empty()) throw ProblemError("\"pile\" has no blocks");
    if (!has_minimum) throw ProblemError("missing key \"minimum_added\" (the checker verifies it)");
    if (static_cast<int32_t>(p.solution.size()) != p.minimum_added) {
      throw ProblemError("\"solution\" has " + std::to_string(p.solution.size()) + " blocks, \"minimum_added\" says " +
                         std::to_string(p.minimum_added));
    }
    if (p.max_added < p.minimum_added) throw ProblemError("\"max_added\" is below \"minimum_added\"");
  } else {
    if (!has_score) throw ProblemError("missing key \"min_score\"");
    if (!has_blocks) throw ProblemError("missing key \"max_blocks\"");
    if (p.time_limit_ms <= 0) throw ProblemError("a score problem needs a positive \"time_limit_s\"");
  }
  return p;
}

Problem load_problem(const std::string& path) {
  std::ifstream in(path);
  if (!in) throw ProblemError(path + ": cannot be read");
  std::stringstream buffer;
  buffer << in.rdbuf();
  try {
    return parse_problem(buffer.str(), std::filesystem::path(path).stem().string());
  } catch (const ProblemError& e) {
    throw ProblemError(path + ": " + e.what());
  }
}

}  // namespace bricklayer::study
