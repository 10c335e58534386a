#include "bricklayer/common/log.h"

#include <atomic>
#include <cstdio>
#include <mutex>
#include <stdexcept>

namespace bricklayer::log {
namespace {
std::mutex g_mutex;
std::string g_module = "bricklayer";
std::atomic<int> g_level{static_cast<int>(Level::kInfo)};
const char* name_of(Level level) {
  switch (level) {
    case Level::kDebug: return "DEBUG";
    case Level::kInfo: return "INFO";
    case Level::kWarn: return "WARN";
    case Level::kError: return "ERROR";
  }
  return "?";
}
}  // namespace

void set_module(std::string name) {
  std::lock_guard lock(g_mutex);
  g_module = std::move(name);
}
void set_level(Level level) { g_level = static_cast<int>(level); }
Level parse_level(std::string_view text) {
  if (text == "debug") return Level::kDebug;
  if (text == "info") return Level::kInfo;
  if (text == "warn") return Level::kWarn;
  if (text == "error") return Level::kError;
  throw std::invalid_argument("unknown log level '" + std::string(text) + "' (expected debug, info, warn or error)");
}
bool enabled(Level level) { return static_cast<int>(level) >= g_level.load(); }
void write(Level level, std::string_view message) {
  std::lock_guard lock(g_mutex);
  std::fprintf(stderr, "%s %s %.*s\n", g_module.c_str(), name_of(level), static_cast<int>(message.size()), message.data());
  std::fflush(stderr);
}
}  // namespace bricklayer::log
