#include "bricklayer/replay/time_arg.h"

#include <cmath>
#include <ctime>
#include <regex>
#include <stdexcept>

namespace bricklayer::replay {

int64_t parse_time_arg(const std::string& text, int64_t start) {
  static const std::regex seconds(R"(\+?(\d+(\.\d*)?)s?)");
  static const std::regex clock(R"(((\d{4})-(\d{2})-(\d{2})[ T])?(\d{1,2}):(\d{2})(:(\d{2}(\.\d*)?))?)");
  std::smatch m;
  if (std::regex_match(text, m, seconds)) {
    if (m[1].length() >= 13 && !m[2].matched && text[0] != '+') return std::stoll(m[1]);  // a utime
    return start + static_cast<int64_t>(std::llround(std::stod(m[1]) * 1e6));
  }
  if (std::regex_match(text, m, clock)) {
    const std::time_t base = static_cast<std::time_t>(start / 1'000'000);
    std::tm tm{};
    localtime_r(&base, &tm);
    if (m[1].matched) {
      tm.tm_year = std::stoi(m[2]) - 1900;
      tm.tm_mon = std::stoi(m[3]) - 1;
      tm.tm_mday = std::stoi(m[4]);
    }
    tm.tm_hour = std::stoi(m[5]);
    tm.tm_min = std::stoi(m[6]);
    const double sec = m[8].matched ? std::stod(m[8]) : 0.0;
    tm.tm_sec = 0;
    tm.tm_isdst = -1;
    if (tm.tm_hour > 23 || tm.tm_min > 59 || sec >= 61) throw std::invalid_argument("'" + text + "' is not a time of day");
    const std::time_t t = std::mktime(&tm);
    return static_cast<int64_t>(t) * 1'000'000 + static_cast<int64_t>(std::llround(sec * 1e6));
  }
  throw std::invalid_argument("'" + text +
                              "' is not a time: seconds into the log (90, +90s), a time of day (14:32:05) or a date and "
                              "time (2026-12-01 14:32:05)");
}

}  // namespace bricklayer::replay
