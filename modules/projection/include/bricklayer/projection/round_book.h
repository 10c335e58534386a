// The rounds kept on disk, so the day's best and the round history (start, end, MAX, blocks used)
// survive a restart of projection or of anything else. One small JSON file, replaced atomically: the
// new content goes to a temporary file beside it, is flushed to the disk, and is renamed over the old
// one, so a crash or a power cut leaves either the old file or the new one, never a torn one.
#pragma once

#include <optional>
#include <string>
#include <vector>

#include "bricklayer/projection/round_referee.h"

namespace bricklayer::projection {

struct RoundBook {
  std::vector<RoundRecord> history;   // finished rounds, oldest first
  std::optional<RoundRecord> running;  // the round running when it was written
  bool operator==(const RoundBook&) const = default;
};

// Reads the book; a missing file is an empty book. Throws std::runtime_error naming the file and what
// is wrong when it cannot be read or is not a round book.
RoundBook load_round_book(const std::string& path);
// Writes the book atomically (see above). Throws std::runtime_error naming the file.
void save_round_book(const std::string& path, const RoundBook& book);

}  // namespace bricklayer::projection
