#include "bricklayer/common/flags.h"

#include <cmath>
#include <cstdio>
#include <iostream>
#include <sstream>

namespace bricklayer {

Flags::Flags(std::string program, std::string summary) : program_(std::move(program)), summary_(std::move(summary)) {
  add_bool("help", "print this help and exit");
}

void Flags::add(const std::string& name, const std::string& default_value, const std::string& help) {
  specs_[name] = Spec{default_value, help, false};
  order_.push_back(name);
}

void Flags::add_bool(const std::string& name, const std::string& help) {
  specs_[name] = Spec{"false", help, true};
  order_.push_back(name);
}

void Flags::add_positional(const std::string& name, const std::string& help, bool required) {
  positional_specs_.emplace_back(name, help);
  if (required) ++required_positionals_;
}

void Flags::add_positional_list(const std::string& name, const std::string& help) {
  add_positional(name + "...", help, true);
  positional_list_ = true;
}

bool Flags::parse(int argc, const char* const* argv) {
  bool only_positional = false;
  for (int i = 1; i < argc; ++i) {
    std::string arg = argv[i];
    if (only_positional || arg.size() < 3 || arg.rfind("--", 0) != 0) {
      if (arg == "--") { only_positional = true; continue; }
      positional_.push_back(arg);
      continue;
    }
    std::string name = arg.substr(2);
    std::string value;
    bool has_value = false;
    if (auto eq = name.find('='); eq != std::string::npos) {
      value = name.substr(eq + 1);
      name = name.substr(0, eq);
      has_value = true;
    }
    auto spec = specs_.find(name);
    if (spec == specs_.end()) throw FlagError("unknown flag --" + name + " (see --help)");
    if (spec->second.is_bool) {
      if (has_value && value != "true" && value != "false")
        throw FlagError("flag --" + name + " takes no value or true/false, got '" + value + "'");
      values_[name] = has_value ? value : "true";
    } else {
      if (!has_value) {
        if (i + 1 >= argc) throw FlagError("flag --" + name + " needs a value");
        value = argv[++i];
      }
      values_[name] = value;
    }
  }
  if (get_bool("help")) {
    std::cout << help();
    return false;
  }
  if (positional_.size() < required_positionals_) {
    throw FlagError("expected " + std::to_string(required_positionals_) + " argument(s), got " +
                    std::to_string(positional_.size()) + " (see --help)");
  }
  if (!positional_list_ && positional_.size() > positional_specs_.size()) {
    throw FlagError("unexpected argument '" + positional_[positional_specs_.size()] + "' (see --help)");
  }
  return true;
}

std::string Flags::get(const std::string& name) const {
  if (auto v = values_.find(name); v != values_.end()) return v->second;
  auto spec = specs_.find(name);
  if (spec == specs_.end()) throw std::logic_error("flag --" + name + " was never declared");
  return spec->second.default_value;
}

bool Flags::get_bool(const std::string& name) const { return get(name) == "true"; }

int64_t Flags::get_int(const std::string& name) const {
  std::string text = get(name);
  try {
    size_t used = 0;
    long long v = std::stoll(text, &used);
    if (used != text.size()) throw std::invalid_argument(text);
    return v;
  } catch (const std::exception&) {
    throw FlagError("flag --" + name + " expects an integer, got '" + text + "'");
  }
}

double Flags::get_double(const std::string& name) const {
  std::string text = get(name);
  try {
    size_t used = 0;
    double v = std::stod(text, &used);
    if (used != text.size() || !std::isfinite(v)) throw std::invalid_argument(text);
    return v;
  } catch (const std::exception&) {
    throw FlagError("flag --" + name + " expects a finite number, got '" + text + "'");
  }
}

bool Flags::was_set(const std::string& name) const { return values_.count(name) > 0; }

std::string Flags::help() const {
  std::ostringstream out;
  out << "usage: " << program_ << " [flags]";
  for (const auto& [name, help] : positional_specs_) out << " " << name;
  out << "\n\n" << summary_ << "\n";
  if (!positional_specs_.empty()) {
    out << "\narguments:\n";
    for (const auto& [name, help] : positional_specs_) out << "  " << name << "  " << help << "\n";
  }
  out << "\nflags:\n";
  for (const auto& name : order_) {
    const Spec& spec = specs_.at(name);
    out << "  --" << name;
    if (!spec.is_bool) out << "=VALUE";
    out << "  " << spec.help;
    if (!spec.is_bool && !spec.default_value.empty()) out << " (default: " << spec.default_value << ")";
    out << "\n";
  }
  return out.str();
}

int run_main(const char* program, int (*body)(int, char**), int argc, char** argv) {
  try {
    return body(argc, argv);
  } catch (const FlagError& e) {
    std::fprintf(stderr, "%s: error: %s\n", program, e.what());
    return 2;
  } catch (const std::exception& e) {
    std::fprintf(stderr, "%s: error: %s\n", program, e.what());
    return 1;
  }
}

}  // namespace bricklayer
