// Messages lost before they reached the logger, found by their numbers. LCM 1.3.1 tells a subscriber
// nothing about loss (its own packet sequence number is not exposed), so the logger checks the
// numbers our messages carry: image_t.frame_number "increases by one per frame from the source"
// (lcmtypes/image_t.lcm). A jump from n to n + k + 1 is k lost frames; a step back is a restarted
// source, not a loss.
#pragma once

#include <cstdint>
#include <map>
#include <string>
#include <utility>

namespace bricklayer::logger {

class SequenceGaps {
 public:
  // Records message `number` of the stream (channel, source). Returns how many numbers were skipped
  // since the previous message of that stream (0 for the first, a repeat or a restart).
  int64_t observe(const std::string& channel, const std::string& source, int64_t number);

  int64_t missing() const { return missing_; }    // numbers skipped, over all streams
  int64_t restarts() const { return restarts_; }  // steps back (a source started again at 0)
  size_t streams() const { return last_.size(); }

  // Streams kept at most; beyond it one stream is forgotten (bounded memory when a
  // hostile sender invents sources).
  static constexpr size_t kMaxStreams = 256;

 private:
  std::map<std::pair<std::string, std::string>, int64_t> last_;
  int64_t missing_ = 0;
  int64_t restarts_ = 0;
};

}  // namespace bricklayer::logger
