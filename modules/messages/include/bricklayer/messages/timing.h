// timing_t: how long one stage took for one input. Run-to-run figures: replay comparisons leave
// BL_TIMING out.
#pragma once

#include <chrono>
#include <cstdint>
#include <string>

#include "bricklayer/timing_t.hpp"

namespace bricklayer::messages {

timing_t make_timing(const std::string& module, const std::string& stage, int64_t utime, int64_t frame_number,
                     int64_t elapsed_us, int64_t received_utime);

// Measures a stage in real time. Only for timing_t's elapsed_us: nothing a node computes may depend
// on it (a node's time is its bus's clock).
class Stopwatch {
 public:
  Stopwatch() : start_(std::chrono::steady_clock::now()) {}
  int64_t elapsed_us() const {
    return std::chrono::duration_cast<std::chrono::microseconds>(std::chrono::steady_clock::now() - start_).count();
  }
  double elapsed_ms() const { return static_cast<double>(elapsed_us()) / 1000.0; }

 private:
  std::chrono::steady_clock::time_point start_;
};

}  // namespace bricklayer::messages
