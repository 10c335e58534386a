// Microseconds since the epoch as wall-clock text that pandas, LibreOffice and Excel read as a date and
// time without being told a format: "2026-12-01 22:43:22.123456" (UTC; the column names say so).
#pragma once

#include <cstdint>
#include <string>

namespace bricklayer::inspect {

std::string utc_text(int64_t utime_us);

// True for a member that holds a time in microseconds since the epoch: "utime" or "..._utime".
bool is_utime_name(const std::string& member);

}  // namespace bricklayer::inspect
