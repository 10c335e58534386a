// Reading the study messages out of recorded bus logs (standard LCM log files, as bricklayer-logger and
// lcm-logger write them). Other channels are skipped; a study message that does not decode is counted
// and reported, and the rest of the log is still read.
#pragma once

#include <cstddef>
#include <string>
#include <vector>

#include "bricklayer/study/table.h"

namespace bricklayer::study {

struct LogReadCounts {
  size_t events = 0;          // every event in the log
  size_t study_messages = 0;  // decoded study messages
  size_t bad_messages = 0;    // study channel events that did not decode
  std::vector<std::string> errors;  // one line per problem (first 20)
};

// Adds the study messages of one log to `collector`. Throws std::runtime_error when the file cannot be
// opened as an LCM log. Channels are matched with the deployment's prefix (bricklayer::channel()).
LogReadCounts read_study_log(const std::string& path, StudyCollector& collector);

}  // namespace bricklayer::study
