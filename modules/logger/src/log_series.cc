#include "bricklayer/logger/log_series.h"

#include <algorithm>
#include <cstdio>
#include <ctime>
#include <filesystem>
#include <stdexcept>
#include <system_error>

namespace bricklayer::logger {
namespace fs = std::filesystem;

LogSeries::LogSeries(std::string base, int rotate) : base_(std::move(base)), rotate_(rotate) {
  if (base_.empty()) throw std::invalid_argument("the log file name is empty");
  if (rotate_ < 0) throw std::invalid_argument("rotate must be >= 0 (0 = increment), got " + std::to_string(rotate_));
}

std::string LogSeries::next() {
  const fs::path base(base_);
  std::error_code ec;
  if (base.has_parent_path()) {
    fs::create_directories(base.parent_path(), ec);
    if (ec) throw std::runtime_error("cannot create the log directory " + base.parent_path().string() + ": " + ec.message());
  }
  auto numbered = [&](int k) { return base_ + "." + std::to_string(k); };
  if (rotate_ > 0) {
    // Oldest first, so no rename ever lands on a file that still exists.
    if (fs::exists(numbered(rotate_ - 1)) && !fs::remove(numbered(rotate_ - 1), ec))
      throw std::runtime_error("cannot delete the oldest log " + numbered(rotate_ - 1) + ": " + ec.message());
    for (int k = rotate_ - 2; k >= 0; --k) {
      if (!fs::exists(numbered(k))) continue;
      fs::rename(numbered(k), numbered(k + 1), ec);
      if (ec) throw std::runtime_error("cannot rename " + numbered(k) + " to " + numbered(k + 1) + ": " + ec.message());
    }
    return numbered(0);
  }
  if (next_ < 0) {
    // After the highest number already there (a restarted logger continues its recording), so the
    // numbers follow the time order even once the budget has deleted the oldest parts.
    next_ = 0;
    const std::string prefix = base.filename().string() + ".";
    for (const auto& entry : fs::directory_iterator(base.has_parent_path() ? base.parent_path() : fs::path("."), ec)) {
      const std::string name = entry.path().filename().string();
      if (name.size() <= prefix.size() || name.compare(0, prefix.size(), prefix) != 0) continue;
      const std::string suffix = name.substr(prefix.size());
      if (suffix.size() > 7 || suffix.find_first_not_of("0123456789") != std::string::npos) continue;
      next_ = std::max(next_, std::stoi(suffix) + 1);
    }
  }
  for (int k = next_; k < 10000000; ++k) {
    char suffix[16];
    std::snprintf(suffix, sizeof suffix, ".%02d", k);
    std::string path = base_ + suffix;
    if (!fs::exists(path, ec) && !ec) {
      next_ = k + 1;  // never a name used before, even when that file is gone
      return path;
    }
  }
  throw std::runtime_error("no free file name " + base_ + ".NN (ten million logs already?)");
}

std::string expand_strftime(const std::string& pattern, long long t) {
  std::time_t tt = static_cast<std::time_t>(t);
  std::tm tm{};
  localtime_r(&tt, &tm);
  char buf[4096];
  const size_t n = std::strftime(buf, sizeof buf, pattern.c_str(), &tm);
  if (n == 0) throw std::invalid_argument("the file pattern '" + pattern + "' expands to nothing (or more than 4 KB)");
  return std::string(buf, n);
}

}  // namespace bricklayer::logger
