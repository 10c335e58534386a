// Progress of a long read on stderr, at most every `interval_s` (2 s) of wall time and only once a run
// has taken that long (a short log prints nothing): bytes done of the total, rate and time left. On a terminal
// it redraws one line; otherwise it prints one line per report (a log file or CI keeps them).
#pragma once

#include <chrono>
#include <cstdint>
#include <string>

namespace bricklayer::inspect {

class Progress {
 public:
  Progress(std::string program, uint64_t total_bytes, bool enabled, double interval_s = 2.0);
  void update(uint64_t done_bytes);
  void finish();

 private:
  using Clock = std::chrono::steady_clock;
  std::string program_;
  uint64_t total_;
  bool enabled_;
  bool tty_;
  bool printed_ = false;
  std::chrono::duration<double> interval_;
  Clock::time_point start_;
  Clock::time_point last_;
};

}  // namespace bricklayer::inspect
