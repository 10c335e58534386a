// The unit of each message field, for column names ("x_block_lengths", "utime_us"). The .lcm comments
// state every unit in prose; this table is their machine-readable form. A field named "utime" or
// "..._utime" is microseconds whatever its type; a field whose name already ends in a unit ("_ms",
// "_us", "_s", "_px") keeps its name; counts, ids, states, flags and text have no unit.
#pragma once

#include <string>

namespace bricklayer::inspect {

// The suffix for member `member` of struct `type` (full name), e.g. "block_lengths", or "" for none.
std::string unit_suffix(const std::string& type, const std::string& member);

// member + "_" + unit, or member alone when it has no unit.
std::string column_name(const std::string& type, const std::string& member);

}  // namespace bricklayer::inspect
