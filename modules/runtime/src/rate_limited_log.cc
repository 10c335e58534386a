#include "bricklayer/runtime/rate_limited_log.h"

#include "bricklayer/common/log.h"

namespace bricklayer::runtime {

std::string with_thousands(int64_t n) {
  const std::string digits = std::to_string(n < 0 ? -n : n);
  std::string out = n < 0 ? "-" : "";
  for (size_t i = 0; i < digits.size(); ++i) {
    if (i > 0 && (digits.size() - i) % 3 == 0) out += ',';
    out += digits[i];
  }
  return out;
}

void RateLimitedLog::summarise(const std::string& kind, Kind& k) {
  if (k.count == 0) return;
  log::warn(with_thousands(k.count), " more ", kind, " in the last ", window_us_ / 1'000'000, " s (latest: ", k.latest, ")");
  ++written_;
  k.count = 0;
}

void RateLimitedLog::warn(const std::string& kind, const std::string& message, int64_t now_utime) {
  auto it = kinds_.find(kind);
  if (it != kinds_.end() && now_utime - it->second.window_start >= window_us_) {
    summarise(kind, it->second);
    kinds_.erase(it);
    it = kinds_.end();
  }
  if (it == kinds_.end()) {
    log::warn(message);
    ++written_;
    kinds_.emplace(kind, Kind{now_utime, 0, message});
    return;
  }
  ++it->second.count;
  ++suppressed_;
  it->second.latest = message;
}

void RateLimitedLog::flush(int64_t now_utime) {
  for (auto it = kinds_.begin(); it != kinds_.end();) {
    Kind& k = it->second;
    if (now_utime - k.window_start >= window_us_) {
      summarise(it->first, k);
      it = kinds_.erase(it);  // the next occurrence is written at once again
    } else {
      ++it;
    }
  }
}

}  // namespace bricklayer::runtime
