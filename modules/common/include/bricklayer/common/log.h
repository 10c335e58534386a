// Levelled logging to stderr: "<module> <LEVEL> message". One line per call, safe from any thread.
#pragma once

#include <sstream>
#include <string>
#include <string_view>

namespace bricklayer::log {

enum class Level { kDebug = 0, kInfo = 1, kWarn = 2, kError = 3 };

void set_module(std::string name);
void set_level(Level level);
// Parses "debug", "info", "warn", "error"; throws std::invalid_argument otherwise.
Level parse_level(std::string_view text);
bool enabled(Level level);
void write(Level level, std::string_view message);

namespace detail {
template <typename... Args>
std::string concat(const Args&... args) {
  std::ostringstream out;
  (out << ... << args);
  return out.str();
}
}  // namespace detail

template <typename... Args> void debug(const Args&... a) { if (enabled(Level::kDebug)) write(Level::kDebug, detail::concat(a...)); }
template <typename... Args> void info(const Args&... a) { if (enabled(Level::kInfo)) write(Level::kInfo, detail::concat(a...)); }
template <typename... Args> void warn(const Args&... a) { if (enabled(Level::kWarn)) write(Level::kWarn, detail::concat(a...)); }
template <typename... Args> void error(const Args&... a) { if (enabled(Level::kError)) write(Level::kError, detail::concat(a...)); }

}  // namespace bricklayer::log
