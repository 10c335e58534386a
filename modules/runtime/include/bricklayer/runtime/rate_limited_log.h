// Warnings that cannot flood: the first message of a kind is written at once; further ones of the same
// kind within the window are counted and summarised in one line when the window ends ("1,234 malformed
// messages on BL_STACK in the last 10 s (latest: ...)"). A day of bad network then costs a few lines a
// minute, not gigabytes of journal. Time is the caller's (the bus clock), so replays log alike.
#pragma once

#include <cstdint>
#include <map>
#include <string>

namespace bricklayer::runtime {

class RateLimitedLog {
 public:
  explicit RateLimitedLog(int64_t window_us = 10'000'000) : window_us_(window_us) {}

  // kind: what the summary counts ("malformed messages on BL_STACK"); message: this occurrence.
  void warn(const std::string& kind, const std::string& message, int64_t now_utime);
  // Writes the summaries whose window has ended. Call regularly (the node does at every step).
  void flush(int64_t now_utime);

  int64_t written() const { return written_; }        // lines written
  int64_t suppressed() const { return suppressed_; }  // occurrences only counted

 private:
  struct Kind {
    int64_t window_start = 0;
    int64_t count = 0;  // occurrences in the window after the one written
    std::string latest;
  };
  void summarise(const std::string& kind, Kind& k);

  int64_t window_us_;
  std::map<std::string, Kind> kinds_;
  int64_t written_ = 0;
  int64_t suppressed_ = 0;
};

// 1234567 -> "1,234,567".
std::string with_thousands(int64_t n);

}  // namespace bricklayer::runtime
