// A recording as replay reads it: one or more LCM log files (parts) in order, or a recording's index
// (NAME.index, written by bricklayer-logger), which names the parts and lets a replay start at a wall
// time without reading what comes before. Every damaged region (a torn event, a truncated end) is
// recorded with the part it is in and how many events were read after it, and so is every part the
// index names that is gone: a replay must report them, never pass them off as a complete log.
#pragma once

#include <cstdint>
#include <memory>
#include <optional>
#include <string>
#include <vector>

#include "bricklayer/logger/recording_index.h"
#include "bricklayer/runtime/log_file.h"

namespace bricklayer::replay {

struct PartDamage {
  std::string part;
  runtime::LogDamage damage;
  int64_t events_after = 0;  // intact events read after it (in this part and the next ones)
};

class RecordingReader {
 public:
  // sources: part files, or one NAME.index. from_utime: with an index, reading starts at its seek point
  // for this time (events before from_utime are still returned: the caller skips them). Throws
  // std::runtime_error when nothing can be read (no such file, an index without any part left).
  RecordingReader(const std::vector<std::string>& sources, int64_t from_utime = 0);

  // The next intact event, across parts; false at the end.
  bool next(runtime::LogEvent& event);

  const std::vector<std::string>& parts() const { return parts_; }
  const std::string& current_part() const { return parts_[std::min(current_, parts_.size() - 1)]; }
  std::vector<PartDamage> damage() const;
  // Parts the index names that no longer exist (deleted by the disk budget, or moved away).
  const std::vector<std::string>& missing_parts() const { return missing_; }
  const std::optional<logger::RecordingIndex>& index() const { return index_; }
  // For progress: bytes of all parts, and bytes read so far.
  int64_t total_bytes() const { return total_bytes_; }
  int64_t done_bytes() const;

 private:
  bool open(size_t part, int64_t offset);
  std::vector<std::string> parts_;
  std::vector<std::string> missing_;
  std::optional<logger::RecordingIndex> index_;
  size_t current_ = 0;
  std::unique_ptr<runtime::LogReader> reader_;
  std::vector<PartDamage> damage_;
  size_t damage_seen_in_part_ = 0;
  int64_t total_bytes_ = 0, done_before_ = 0;
};

}  // namespace bricklayer::replay
