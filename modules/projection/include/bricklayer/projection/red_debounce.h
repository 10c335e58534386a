// When to beep: a red (cause) block must be present for hold_ms without a break before the beep
// sounds, and the beep re-arms only after no red has been seen for rearm_ms. Flicker of a single
// frame neither beeps nor re-arms. Pure: times are passed in (milliseconds, monotonic).
#pragma once

#include <cstdint>
#include <optional>

namespace bricklayer::projection {

class RedDebounce {
 public:
  explicit RedDebounce(int64_t hold_ms = 300, int64_t rearm_ms = 1000) : hold_ms_(hold_ms), rearm_ms_(rearm_ms) {}

  // Feeds the current observation; returns true exactly when the beep should start now.
  bool update(bool red, int64_t now_ms);
  bool armed() const { return armed_; }

 private:
  int64_t hold_ms_;
  int64_t rearm_ms_;
  bool armed_ = true;
  std::optional<int64_t> red_since_;
  std::optional<int64_t> clear_since_;
};

}  // namespace bricklayer::projection
