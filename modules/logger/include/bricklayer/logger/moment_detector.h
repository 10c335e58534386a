// The moments worth full-rate frames and an index entry, found in the messages the logger records
// (the definitions of bricklayer-report, modules/inspect/README.md, so the report and the index agree):
//   red          a prediction_t (status OK) with a cause block after one with none
//   collapse     that red episode ended (a prediction with no cause) on a pile of fewer blocks than
//                the one that turned red: it fell
//   round_start  a round_t in state RUNNING after one that was not
//   round_end    a round_t no longer RUNNING (ENDED: time up, IDLE: reset) after a RUNNING one
//   mark         a command_t MARK_MOMENT (the operator: bricklayer-mark "NOTE"); its argument is the note
// round_start is only indexed; the others also open a full-rate window.
#pragma once

#include <cstdint>
#include <optional>
#include <string>

#include "bricklayer/logger/recording_index.h"

namespace bricklayer::logger {

struct MomentChannels {
  std::string prediction = "BL_PREDICTION";
  std::string round = "BL_ROUND";
  std::string command = "BL_COMMAND";
};

class MomentDetector {
 public:
  explicit MomentDetector(MomentChannels channels = {});

  // A message the logger received at utime; a moment when it is one. Bytes that do not decode are
  // ignored (they are logged anyway).
  std::optional<Moment> observe(const std::string& channel, const uint8_t* data, size_t size, int64_t utime);
  // Whether the moment opens a full-rate window.
  static bool wants_full_rate(const Moment& m) { return m.kind != "round_start"; }

  const MomentChannels& channels() const { return channels_; }

 private:
  MomentChannels channels_;
  bool red_ = false;
  int32_t red_blocks_ = 0;
  bool running_ = false;
};

}  // namespace bricklayer::logger
