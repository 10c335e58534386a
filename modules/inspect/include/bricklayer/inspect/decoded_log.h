// The one loop every inspect tool runs: read the log's events in order, recognise each message's type
// by its fingerprint, decode it from the .lcm definitions, and hand it on; count what could not be
// decoded, and keep the file problems (torn or corrupt stretches) for the final report.
#pragma once

#include <cstdint>
#include <functional>
#include <string>
#include <vector>

#include "bricklayer/inspect/lcm_decoder.h"
#include "bricklayer/inspect/log_source.h"

namespace bricklayer::inspect {

struct DecodedEvent {
  const LogEvent& event;
  const LcmStruct* type;   // null when the fingerprint is not a known type or the data is too short
  const Json* message;     // null when not decoded
  const std::string& error;  // why not decoded ("" when decoded)
  int64_t fingerprint;     // 0 when the data is shorter than a fingerprint
};

struct ReadSummary {
  uint64_t events = 0;
  uint64_t decoded = 0;
  uint64_t unknown_type = 0;  // a fingerprint no .lcm definition here has (another program's messages)
  uint64_t malformed = 0;     // a known type that does not decode: damage
  std::vector<LogProblem> problems;
  bool damaged() const { return malformed > 0 || !problems.empty(); }
  // "... N events ..." and one line per problem, for the operator.
  std::string describe() const;
};

// Reads every event of `files`; `progress_program` non-empty shows progress under that name, a line
// every `progress_seconds` once the run has taken that long.
// Throws LogOpenError when a file cannot be opened; damage inside files is in the summary.
ReadSummary read_decoded(const std::vector<std::string>& files, const LcmTypeSet& types,
                         const std::function<void(const DecodedEvent&)>& on_event,
                         const std::string& progress_program = "", double progress_seconds = 2.0);

}  // namespace bricklayer::inspect
