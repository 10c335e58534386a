#include "bricklayer/logger/sequence_gaps.h"

namespace bricklayer::logger {

int64_t SequenceGaps::observe(const std::string& channel, const std::string& source, int64_t number) {
  auto key = std::make_pair(channel, source);
  auto it = last_.find(key);
  if (it == last_.end()) {
    if (last_.size() >= kMaxStreams) last_.erase(last_.begin());
    last_.emplace(std::move(key), number);
    return 0;
  }
  const int64_t previous = it->second;
  it->second = number;
  if (number <= previous) {
    if (number < previous) ++restarts_;
    return 0;
  }
  // A jump of more than a billion is a new numbering (or a hostile message), not a billion losses.
  const int64_t skipped = number - previous - 1;
  if (skipped > 1000000000) {
    ++restarts_;
    return 0;
  }
  missing_ += skipped;
  return skipped;
}

}  // namespace bricklayer::logger
