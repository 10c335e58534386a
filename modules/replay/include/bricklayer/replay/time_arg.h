// --from / --to: a wall time or seconds into the log.
//   "90", "90s", "+90", "1.5"        seconds after the log's first event
//   "14:32", "14:32:05", "14:32:05.5" that local time on the day of the log's first event
//   "2026-12-01 14:32:05" (or with T)  that local date and time
//   "1764599525000000"                 a utime (microseconds since the epoch)
#pragma once

#include <cstdint>
#include <string>

namespace bricklayer::replay {

// Throws std::invalid_argument saying what was expected.
int64_t parse_time_arg(const std::string& text, int64_t log_start_utime);

}  // namespace bricklayer::replay
