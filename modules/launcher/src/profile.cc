#include "bricklayer/launcher/profile.h"

#include <algorithm>
#include <cstdio>
#include <filesystem>
#include <fstream>
#include <set>
#include <sstream>

#include <nlohmann/json.hpp>

#include "bricklayer/logger/logger_node.h"
#include "bricklayer/runtime/config.h"

namespace bricklayer::launcher {
namespace {

using nlohmann::json;

void check_keys(const json& obj, const std::set<std::string>& allowed, const std::string& where) {
  if (!obj.is_object()) throw ProfileError(where + ": expected an object");
  for (const auto& [key, value] : obj.items()) {
    if (!allowed.count(key)) {
      std::string list;
      for (const auto& a : allowed) list += (list.empty() ? "" : ", ") + a;
      throw ProfileError(where + ": unknown key '" + key + "' (allowed: " + list + ")");
    }
  }
}

double number(const json& obj, const std::string& key, double fallback, const std::string& where, double min = 0) {
  if (!obj.contains(key)) return fallback;
  const json& v = obj.at(key);
  if (!v.is_number()) throw ProfileError(where + ": '" + key + "' must be a number");
  double d = v.get<double>();
  if (!(d >= min)) throw ProfileError(where + ": '" + key + "' must be >= " + std::to_string(min));
  return d;
}

std::vector<std::string> strings(const json& v, const std::string& where) {
  if (!v.is_array()) throw ProfileError(where + ": expected an array of strings");
  std::vector<std::string> out;
  for (const auto& s : v) {
    if (!s.is_string()) throw ProfileError(where + ": expected an array of strings");
    out.push_back(s.get<std::string>());
  }
  return out;
}

ModuleSpec parse_module(const json& m, const std::string& where) {
  check_keys(m, {"name", "command", "command_with_display", "heartbeat", "restart", "ready_timeout_s",
                 "heartbeat_timeout_s", "backoff_max_s", "needs", "env", "when_closed"},
             where);
  ModuleSpec spec;
  if (!m.contains("name") || !m.at("name").is_string() || m.at("name").get<std::string>().empty())
    throw ProfileError(where + ": 'name' (a non-empty string) is required");
  spec.name = m.at("name").get<std::string>();
  const std::string w = where + " '" + spec.name + "'";
  if (!m.contains("command")) throw ProfileError(w + ": 'command' is required");
  spec.command = strings(m.at("command"), w + " command");
  if (spec.command.empty()) throw ProfileError(w + ": 'command' is empty");
  if (m.contains("command_with_display")) {
    spec.command_with_display = strings(m.at("command_with_display"), w + " command_with_display");
    if (spec.command_with_display.empty()) throw ProfileError(w + ": 'command_with_display' is empty");
  }
  spec.heartbeat = spec.name;
  if (m.contains("heartbeat")) {
    if (!m.at("heartbeat").is_string())
      throw ProfileError(w + ": 'heartbeat' must be the module name in its heartbeat, or \"\" for none");
    spec.heartbeat = m.at("heartbeat").get<std::string>();
  }
  if (m.contains("restart")) {
    if (!m.at("restart").is_string()) throw ProfileError(w + ": 'restart' must be a string");
    try {
      spec.restart = parse_restart_policy(m.at("restart").get<std::string>());
    } catch (const ProfileError& e) {
      throw ProfileError(w + ": " + e.what());
    }
  }
  spec.ready_timeout_s = number(m, "ready_timeout_s", spec.ready_timeout_s, w, 0.1);
  spec.heartbeat_timeout_s = number(m, "heartbeat_timeout_s", spec.heartbeat_timeout_s, w, 1.5);
  spec.backoff_max_s = number(m, "backoff_max_s", spec.backoff_max_s, w, 0.1);
  if (m.contains("needs")) spec.needs = strings(m.at("needs"), w + " needs");
  if (m.contains("env")) {
    spec.env = strings(m.at("env"), w + " env");
    for (const auto& e : spec.env)
      if (e.find('=') == std::string::npos || e[0] == '=') throw ProfileError(w + ": env entry '" + e + "' is not NAME=value");
  }
  if (m.contains("when_closed")) {
    const json& v = m.at("when_closed");
    if (!v.is_string() || (v.get<std::string>() != "stop" && v.get<std::string>() != "run"))
      throw ProfileError(w + ": 'when_closed' must be \"stop\" (the default: stopped outside the opening hours) or \"run\"");
    spec.run_when_closed = v.get<std::string>() == "run";
  }
  return spec;
}

// The line of the file where "key" first appears, for errors in values a person types by hand.
int line_of(const std::string& text, const std::string& key) {
  const auto at = text.find("\"" + key + "\"");
  if (at == std::string::npos) return 0;
  return 1 + static_cast<int>(std::count(text.begin(), text.begin() + static_cast<std::ptrdiff_t>(at), '\n'));
}

// The logger's own declaration (logger_node.h: each flag's range, and its rules across flags) judges
// the flags the profile's logger keys become, so a profile is refused at load for exactly what
// bricklayer-logger would refuse, with the rules written once.
void check_logger_rules(const LoggerSpec& spec, const std::string& where) {
  logger::LoggerConfig c;
  c.file = spec.file;
  c.rotate = spec.rotate;
  c.split_mb = spec.split_mb;
  c.budget_mb = spec.budget_mb;
  c.min_free_mb = spec.min_free_mb;
  if (spec.frames) {
    c.frame_rate = spec.frames->rate;
    c.full_rate_before_s = spec.frames->before_s;
    c.full_rate_after_s = spec.frames->after_s;
    c.answers_with_frames = spec.frames->answers_with_frames;
    c.max_mb_per_hour = spec.frames->max_mb_per_hour;
  }
  try {
    runtime::validate(c);
    logger::LoggerNode::check(c);
  } catch (const std::invalid_argument& e) {
    const std::string why = e.what();
    throw ProfileError(where + ": bricklayer-logger would refuse it: " + (why.rfind("--", 0) == 0 ? "" : "--") + why);
  }
}

}  // namespace

RestartPolicy parse_restart_policy(const std::string& text) {
  if (text == "always") return RestartPolicy::kAlways;
  if (text == "on-failure") return RestartPolicy::kOnFailure;
  if (text == "never") return RestartPolicy::kNever;
  throw ProfileError("restart policy '" + text + "' is not one of always, on-failure, never");
}

std::string to_string(RestartPolicy policy) {
  switch (policy) {
    case RestartPolicy::kAlways: return "always";
    case RestartPolicy::kOnFailure: return "on-failure";
    case RestartPolicy::kNever: return "never";
  }
  return "?";
}

Profile parse_profile(const std::string& json_text, const std::string& name) {
  json doc;
  try {
    doc = json::parse(json_text);
  } catch (const json::exception& e) {
    throw ProfileError("profile " + name + ": not valid JSON: " + e.what());
  }
  const std::string where = "profile " + name;
  check_keys(doc, {"description", "modules", "logger", "duration_s", "headless_duration_s", "stop_timeout_s", "notes",
                   "opening_hours", "nightly_restart", "multicast_route"},
             where);
  Profile p;
  p.name = name;
  if (doc.contains("description")) {
    if (!doc.at("description").is_string()) throw ProfileError(where + ": 'description' must be a string");
    p.description = doc.at("description").get<std::string>();
  }
  if (!doc.contains("modules") || !doc.at("modules").is_array())
    throw ProfileError(where + ": 'modules' (an array, in start order) is required");
  std::set<std::string> names;
  for (size_t i = 0; i < doc.at("modules").size(); ++i) {
    ModuleSpec spec = parse_module(doc.at("modules")[i], where + " module #" + std::to_string(i + 1));
    if (!names.insert(spec.name).second) throw ProfileError(where + ": two modules are named '" + spec.name + "'");
    p.modules.push_back(std::move(spec));
  }
  if (doc.contains("logger") && !doc.at("logger").is_null()) {
    const json& l = doc.at("logger");
    const std::string lw = where + " logger";
    check_keys(l, {"file", "rotate", "split_mb", "budget_mb", "min_free_mb", "frames"}, lw);
    LoggerSpec spec;
    if (l.contains("file")) {
      if (!l.at("file").is_string() || l.at("file").get<std::string>().empty())
        throw ProfileError(lw + ": 'file' must be a non-empty string");
      spec.file = l.at("file").get<std::string>();
    }
    spec.budget_mb = number(l, "budget_mb", 0, lw);
    spec.min_free_mb = number(l, "min_free_mb", 0, lw);
    // A budget bounds the series by itself: increment naming (rotation would rename what the index names).
    spec.rotate = static_cast<int>(number(l, "rotate", spec.budget_mb > 0 ? 0 : spec.rotate, lw));
    spec.split_mb = number(l, "split_mb", spec.split_mb, lw, 0.01);
    if (l.contains("frames") && !l.at("frames").is_null()) {
      const json& f = l.at("frames");
      if (!f.is_object())
        throw ProfileError(lw + ": 'frames' must be an object {rate, before_s, after_s, answers, max_mb_per_hour}");
      check_keys(f, {"rate", "before_s", "after_s", "answers", "max_mb_per_hour"}, lw + " frames");
      FrameSpec frames{.before_s = logger::LoggerConfig{}.full_rate_before_s, .after_s = logger::LoggerConfig{}.full_rate_after_s};
      frames.rate = number(f, "rate", frames.rate, lw + " frames", 0.001);
      frames.before_s = number(f, "before_s", frames.before_s, lw + " frames");
      frames.after_s = number(f, "after_s", frames.after_s, lw + " frames");
      frames.max_mb_per_hour = number(f, "max_mb_per_hour", 0, lw + " frames");
      if (f.contains("answers")) {
        const json& a = f.at("answers");
        if (!a.is_string() || (a != "with_frames" && a != "whole"))
          throw ProfileError(lw + " frames: 'answers' must be \"with_frames\" or \"whole\"");
        frames.answers_with_frames = a == "with_frames";
      }
      spec.frames = frames;
    }
    check_logger_rules(spec, lw);
    p.logger = spec;
  }
  if (p.modules.empty() && !p.logger) throw ProfileError(where + ": nothing to launch (no modules, no logger)");
  p.duration_s = number(doc, "duration_s", 0, where);
  p.headless_duration_s = number(doc, "headless_duration_s", 0, where);
  p.stop_timeout_s = number(doc, "stop_timeout_s", 5, where, 0.1);
  if (doc.contains("notes")) p.notes = strings(doc.at("notes"), where + " notes");
  // Wall-clock times typed by a museum's staff: a mistake names the line, and the profile does not start.
  auto at_line = [&](const std::string& key) {
    const int line = line_of(json_text, key);
    return where + (line > 0 ? " line " + std::to_string(line) : std::string()) + ": '" + key + "'";
  };
  if (doc.contains("opening_hours")) {
    const json& v = doc.at("opening_hours");
    if (!v.is_string()) throw ProfileError(at_line("opening_hours") + " must be a string such as \"09:30-18:00\"");
    try {
      p.opening_hours = OpeningHours::parse(v.get<std::string>());
    } catch (const std::invalid_argument& e) {
      throw ProfileError(at_line("opening_hours") + " \"" + v.get<std::string>() + "\": " + e.what());
    }
  }
  if (doc.contains("nightly_restart")) {
    const json& v = doc.at("nightly_restart");
    if (!v.is_string()) throw ProfileError(at_line("nightly_restart") + " must be a time of day such as \"03:00\"");
    try {
      p.nightly_restart = parse_clock(v.get<std::string>());
    } catch (const std::invalid_argument& e) {
      throw ProfileError(at_line("nightly_restart") + ": " + e.what());
    }
  }
  if (doc.contains("multicast_route")) {
    const json& v = doc.at("multicast_route");
    if (!v.is_string() || v.get<std::string>().empty() || v.get<std::string>().find_first_of(" /\t") != std::string::npos)
      throw ProfileError(where + ": 'multicast_route' must be an interface name such as \"eth0\"");
    p.multicast_route = v.get<std::string>();
  }
  return p;
}

std::string series_prefix(const std::string& file_pattern) {
  const std::string name = std::filesystem::path(file_pattern).filename().string();
  const auto percent = name.find('%');
  return percent == std::string::npos ? name + "." : name.substr(0, percent);
}

std::vector<std::string> logger_arguments(const LoggerSpec& l, const std::string& file) {
  auto text = [](double v) {
    char buf[32];
    std::snprintf(buf, sizeof buf, "%g", v);
    return std::string(buf);
  };
  // --rotate 0 means increment (FILE.00, FILE.01, ...), as lcm-logger's -i.
  std::vector<std::string> args = {"--rotate=" + std::to_string(std::max(0, l.rotate)), "--split-mb=" + text(l.split_mb)};
  if (l.budget_mb > 0 || l.min_free_mb > 0) args.push_back("--series=" + series_prefix(l.file));
  if (l.budget_mb > 0) args.push_back("--budget-mb=" + text(l.budget_mb));
  if (l.min_free_mb > 0) args.push_back("--min-free-mb=" + text(l.min_free_mb));
  if (l.frames) {
    args.push_back("--frame-rate=" + text(l.frames->rate));
    args.push_back("--full-rate-before-s=" + text(l.frames->before_s));
    args.push_back("--full-rate-after-s=" + text(l.frames->after_s));
    if (l.frames->answers_with_frames) args.push_back("--answers-with-frames");
    if (l.frames->max_mb_per_hour > 0) args.push_back("--max-mb-per-hour=" + text(l.frames->max_mb_per_hour));
  }
  args.push_back(file);
  return args;
}

Profile load_profile(const std::string& path) {
  std::ifstream in(path);
  if (!in) throw ProfileError("cannot read profile '" + path + "' (see launch/profiles/ for the available ones)");
  std::stringstream text;
  text << in.rdbuf();
  return parse_profile(text.str(), std::filesystem::path(path).stem().string());
}

}  // namespace bricklayer::launcher
