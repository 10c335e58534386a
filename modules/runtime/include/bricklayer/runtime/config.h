// A node's configuration: a plain struct whose fields are declared once, with name, default (the
// field's initial value), help and the rule a value must keep (Drake's Serialize(Archive*) habit).
// Flags, --help, validation of a struct built in code, the JSON a node records in its log and the
// launcher's profile check all visit the same declaration, so a default or a range is never written
// twice:
//
//   struct PredictionConfig {
//     std::string annotator = "exact";
//     double position_tolerance = 0.005;
//     template <typename Visitor> void visit(Visitor& v) {
//       v(param("annotator", annotator, "which blocks are red").one_of({"exact", "paper", "balance"}));
//       v(param("position-tolerance", position_tolerance, "block lengths a position may be off").range(0, 0.05));
//     }
//   };
//
// Field types: bool (a flag without value; its default must be false), int, int64_t, double,
// std::string.
#pragma once

#include <algorithm>
#include <cmath>
#include <cstdint>
#include <filesystem>
#include <functional>
#include <optional>
#include <sstream>
#include <stdexcept>
#include <string>
#include <type_traits>
#include <vector>

#include <nlohmann/json.hpp>

#include "bricklayer/common/flags.h"

namespace bricklayer::runtime {

template <typename T>
struct Param {
  static_assert(std::is_same_v<T, bool> || std::is_same_v<T, int> || std::is_same_v<T, int64_t> ||
                    std::is_same_v<T, double> || std::is_same_v<T, std::string>,
                "config fields are bool, int, int64_t, double or std::string");
  std::string name;
  T* value = nullptr;
  std::string help;
  std::optional<double> min, max;              // numbers: bounds
  bool min_open = false, max_open = false;     // ... excluded from the range
  std::vector<std::string> choices;            // strings: the allowed values
  std::function<std::string(const T&)> rule;   // any other rule: "" when the value keeps it, else why not
  bool file = false;                           // a path the module reads: it must exist ("" = none)
  bool folder = false;                         // a folder the module reads: it must exist ("" = none)
  bool positional = false;                     // given as an argument (in declaration order), not as --name

  Param& range(double lo, double hi) { min = lo; max = hi; return *this; }  // [lo, hi]
  Param& open_range(double lo, double hi) { range(lo, hi); min_open = max_open = true; return *this; }  // (lo, hi)
  Param& above_up_to(double lo, double hi) { range(lo, hi); min_open = true; return *this; }  // (lo, hi]
  Param& at_least(double lo) { min = lo; return *this; }
  Param& above(double lo) { min = lo; min_open = true; return *this; }
  Param& one_of(std::vector<std::string> allowed) { choices = std::move(allowed); return *this; }
  Param& must(std::function<std::string(const T&)> check) { rule = std::move(check); return *this; }
  Param& existing_file() { file = true; return *this; }
  Param& existing_folder() { folder = true; return *this; }
  Param& argument() { positional = true; return *this; }
};

template <typename T>
Param<T> param(std::string name, T& value, std::string help) {
  Param<T> p;
  p.name = std::move(name);
  p.value = &value;
  p.help = std::move(help);
  return p;
}

namespace config_detail {

template <typename T>
std::string to_text(const T& v) {
  if constexpr (std::is_same_v<T, bool>) {
    return v ? "true" : "false";
  } else if constexpr (std::is_same_v<T, std::string>) {
    return v;
  } else if constexpr (std::is_same_v<T, double>) {
    if (std::isfinite(v) && v == std::floor(v) && std::fabs(v) < 1e15) return std::to_string(static_cast<int64_t>(v));
    std::ostringstream out;
    out.precision(17);
    out << v;
    // The shortest text that reads back as the same double (0.005, not 0.0050000000000000001).
    for (int p = 1; p <= 17; ++p) {
      std::ostringstream s;
      s.precision(p);
      s << v;
      if (std::stod(s.str()) == v) return s.str();
    }
    return out.str();
  } else {
    return std::to_string(v);
  }
}

// Parses text as T; nullopt when it is not one.
template <typename T>
std::optional<T> from_text(const std::string& text) {
  try {
    size_t used = 0;
    if constexpr (std::is_same_v<T, bool>) {
      if (text == "true") return true;
      if (text == "false") return false;
      return std::nullopt;
    } else if constexpr (std::is_same_v<T, std::string>) {
      return text;
    } else if constexpr (std::is_same_v<T, double>) {
      const double v = std::stod(text, &used);
      if (used != text.size() || !std::isfinite(v)) return std::nullopt;
      return v;
    } else {
      const long long v = std::stoll(text, &used);
      if (used != text.size()) return std::nullopt;
      if constexpr (std::is_same_v<T, int>) {
        if (v < INT32_MIN || v > INT32_MAX) return std::nullopt;
      }
      return static_cast<T>(v);
    }
  } catch (const std::exception&) {
    return std::nullopt;
  }
}

template <typename T>
const char* type_name() {
  if constexpr (std::is_same_v<T, bool>) return "bool";
  else if constexpr (std::is_same_v<T, std::string>) return "string";
  else if constexpr (std::is_same_v<T, double>) return "number";
  else return "integer";
}

// "a number", "an integer", ...: for messages.
template <typename T>
const char* a_type_name() {
  if constexpr (std::is_same_v<T, bool>) return "true or false";
  else if constexpr (std::is_same_v<T, std::string>) return "a string";
  else if constexpr (std::is_same_v<T, double>) return "a finite number";
  else return "an integer";
}

inline std::string join(const std::vector<std::string>& items) {
  std::string out;
  for (const auto& s : items) out += (out.empty() ? "" : ", ") + s;
  return out;
}

// The rule in words, for --help and errors: [0, 0.05], (0, 0.5), >= 0, > 0, one of a, b.
template <typename T>
std::string rule_text(const Param<T>& p) {
  if (!p.choices.empty()) return "one of " + join(p.choices);
  if (p.min && p.max)
    return std::string(p.min_open ? "(" : "[") + to_text(*p.min) + ", " + to_text(*p.max) + (p.max_open ? ")" : "]");
  if (p.min) return (p.min_open ? "> " : ">= ") + to_text(*p.min);
  if (p.max) return (p.max_open ? "< " : "<= ") + to_text(*p.max);
  return "";
}

}  // namespace config_detail

// Why a value breaks its declaration; "" when it keeps it.
template <typename T>
std::string violation(const Param<T>& p, const T& v) {
  if constexpr (std::is_arithmetic_v<T> && !std::is_same_v<T, bool>) {
    if (!std::isfinite(static_cast<double>(v))) return "must be a finite number";
    const double d = static_cast<double>(v);
    const bool low = p.min && (p.min_open ? d <= *p.min : d < *p.min);
    const bool high = p.max && (p.max_open ? d >= *p.max : d > *p.max);
    if (low || high) {
      const std::string rule = config_detail::rule_text(p);
      return (rule[0] == '[' || rule[0] == '(' ? "must be in " : "must be ") + rule + ", got " + config_detail::to_text(v);
    }
  }
  if constexpr (std::is_same_v<T, std::string>) {
    if (!p.choices.empty() && std::find(p.choices.begin(), p.choices.end(), v) == p.choices.end())
      return "must be one of " + config_detail::join(p.choices) + ", got '" + v + "'";
  }
  if (p.rule) return p.rule(v);
  return "";
}

// The files and folders a configuration names that do not exist (the launcher's profile check).
template <typename T>
std::string missing_path(const Param<T>& p, const T& v) {
  if constexpr (std::is_same_v<T, std::string>) {
    if (v.empty()) return "";
    std::error_code ec;
    if (p.file && !std::filesystem::is_regular_file(v, ec)) return "no such file '" + v + "'";
    if (p.folder && !std::filesystem::is_directory(v, ec)) return "no such folder '" + v + "'";
  }
  return "";
}

// Declares one flag per field: --name (the default and the rule shown in --help).
template <typename Config>
void declare_flags(Flags& flags, Config& config) {
  auto declare = [&flags](auto&& p) {
    using T = std::remove_reference_t<decltype(*p.value)>;
    std::string help = p.help;
    const std::string rule = config_detail::rule_text(p);
    if (!rule.empty()) help += " [" + rule + "]";
    if (p.positional) {
      flags.add_positional(p.name, help);
    } else if constexpr (std::is_same_v<T, bool>) {
      if (*p.value) throw std::logic_error("config field '" + p.name + "' is a bool defaulting to true; name it for its true case");
      flags.add_bool(p.name, help);
    } else {
      flags.add(p.name, config_detail::to_text(*p.value), help);
    }
  };
  config.visit(declare);
}

// Reads every flag given into the fields and checks every field; throws FlagError naming the flag.
template <typename Config>
void read_flags(const Flags& flags, Config& config) {
  size_t argument = 0;
  auto read = [&flags, &argument](auto&& p) {
    using T = std::remove_reference_t<decltype(*p.value)>;
    const bool given = p.positional ? argument < flags.positional().size() : flags.was_set(p.name);
    if (given) {
      const std::string text = p.positional ? flags.positional()[argument++] : flags.get(p.name);
      const std::optional<T> v = config_detail::from_text<T>(text);
      if (!v)
        throw FlagError((p.positional ? p.name : "--" + p.name) + " expects " + config_detail::a_type_name<T>() +
                        ", got '" + text + "'");
      *p.value = *v;
    }
    if (const std::string why = violation(p, *p.value); !why.empty())
      throw FlagError((p.positional ? p.name : "--" + p.name) + " " + why);
  };
  config.visit(read);
}

// Checks every field of a configuration built in code; throws std::invalid_argument naming the field.
template <typename Config>
void validate(const Config& checked) {
  Config config = checked;  // visit() hands out pointers to fields: visit a copy
  auto check = [](auto&& p) {
    if (const std::string why = violation(p, *p.value); !why.empty())
      throw std::invalid_argument(p.name + " " + why);
  };
  config.visit(check);
}

// Every missing file or folder the configuration names, one line each ("--scenario: no such file ...").
template <typename Config>
std::vector<std::string> missing_paths(const Config& checked) {
  Config config = checked;
  std::vector<std::string> out;
  auto check = [&out](auto&& p) {
    if (const std::string why = missing_path(p, *p.value); !why.empty()) out.push_back("--" + p.name + ": " + why);
  };
  config.visit(check);
  return out;
}

// {"name": value, ...}: what a node records in its log, and what a replay starts from.
template <typename Config>
nlohmann::json to_json(const Config& recorded) {
  Config config = recorded;
  nlohmann::json out = nlohmann::json::object();
  auto put = [&out](auto&& p) { out[p.name] = *p.value; };
  config.visit(put);
  return out;
}

// Sets the fields named in j (others keep their values) and checks them; an unknown key or a value of
// the wrong type or out of its rule throws std::invalid_argument naming it.
template <typename Config>
void from_json(const nlohmann::json& j, Config& config) {
  if (!j.is_object()) throw std::invalid_argument("a configuration is a JSON object");
  std::vector<std::string> known;
  auto set = [&j, &known](auto&& p) {
    using T = std::remove_reference_t<decltype(*p.value)>;
    known.push_back(p.name);
    auto it = j.find(p.name);
    if (it == j.end()) return;
    T v;
    try {
      v = it->template get<T>();
    } catch (const std::exception&) {
      throw std::invalid_argument(p.name + " must be " + config_detail::a_type_name<T>());
    }
    if (const std::string why = violation(p, v); !why.empty()) throw std::invalid_argument(p.name + " " + why);
    *p.value = v;
  };
  config.visit(set);
  for (const auto& [key, value] : j.items())
    if (std::find(known.begin(), known.end(), key) == known.end())
      throw std::invalid_argument("unknown configuration key '" + key + "' (known: " + config_detail::join(known) + ")");
}

// Sets one field from text ("annotator=paper"), as a replay's --set does; throws std::invalid_argument.
template <typename Config>
void set_from_text(const std::string& assignment, Config& config) {
  const auto eq = assignment.find('=');
  if (eq == std::string::npos) throw std::invalid_argument("expected NAME=VALUE, got '" + assignment + "'");
  const std::string name = assignment.substr(0, eq), text = assignment.substr(eq + 1);
  bool found = false;
  std::vector<std::string> known;
  auto set = [&](auto&& p) {
    using T = std::remove_reference_t<decltype(*p.value)>;
    known.push_back(p.name);
    if (p.name != name) return;
    found = true;
    const std::optional<T> v = config_detail::from_text<T>(text);
    if (!v) throw std::invalid_argument(name + " expects " + config_detail::a_type_name<T>() + ", got '" + text + "'");
    if (const std::string why = violation(p, *v); !why.empty()) throw std::invalid_argument(name + " " + why);
    *p.value = *v;
  };
  config.visit(set);
  if (!found) throw std::invalid_argument("unknown configuration key '" + name + "' (known: " + config_detail::join(known) + ")");
}

// The declaration itself, for tools: [{"name", "type", "default", "help", "min", "max", "choices", "file"}].
template <typename Config>
nlohmann::json describe(const Config& described) {
  Config config = described;
  nlohmann::json out = nlohmann::json::array();
  auto add = [&out](auto&& p) {
    using T = std::remove_reference_t<decltype(*p.value)>;
    nlohmann::json d{{"name", p.name}, {"type", config_detail::type_name<T>()}, {"default", *p.value}, {"help", p.help}};
    if (p.min) d[p.min_open ? "above" : "min"] = *p.min;
    if (p.max) d[p.max_open ? "below" : "max"] = *p.max;
    if (!p.choices.empty()) d["choices"] = p.choices;
    if (p.file) d["file"] = true;
    if (p.folder) d["folder"] = true;
    out.push_back(std::move(d));
  };
  config.visit(add);
  return out;
}

}  // namespace bricklayer::runtime
