// How a message type becomes CSV rows, derived from its definition alone:
// - one row per element of the message's first variable-length array (stack_t: one row per block;
//   prediction_t: per block; heartbeat_t: per named value), with every other member repeated on each
//   row; a message whose array is empty, or that has none, is one row;
// - nested structs and fixed-size arrays become columns ("blocks.corner_u_2_px", "image.width_px");
// - other variable-length arrays become one cell holding a JSON array;
// - byte arrays (image data) are left out; their size stays;
// - every time in microseconds ("utime", "..._utime") gets a wall-clock twin ("utime_utc").
// Leading columns name the log event: event, log_utime_us, log_utc, item_index (the row's position in
// the array, empty when the message has no element).
#pragma once

#include <string>
#include <vector>

#include "bricklayer/inspect/lcm_decoder.h"
#include "bricklayer/inspect/lcm_schema.h"

namespace bricklayer::inspect {

struct LogEvent;

class TableLayout {
 public:
  TableLayout(const LcmTypeSet& types, const LcmStruct& type);

  const std::vector<std::string>& header() const { return header_; }
  bool has_items() const { return !row_members_.empty(); }
  // The rows of one decoded message (cells as CSV text, not yet quoted).
  std::vector<std::vector<std::string>> rows(const LogEvent& event, const Json& message) const;

 private:
  struct Step {
    std::string member;  // empty: an index step
    size_t index = 0;
  };
  enum class Kind { kValue, kUtcText, kJsonText };
  struct Column {
    std::vector<Step> path;
    Kind kind = Kind::kValue;
    bool per_item = false;  // path starts inside the row array's element
  };
  void add_member(const LcmTypeSet& types, const LcmStruct& owner, const LcmMember& m, const std::string& prefix,
                  std::vector<Step> path, bool per_item, bool row_member);
  void add_value(const LcmTypeSet& types, const std::string& type, const std::string& owner, const std::string& name,
                 const std::string& prefix, std::vector<Step> path, bool per_item);

  std::vector<std::string> header_;
  std::vector<Column> columns_;
  std::string row_length_member_;
  std::vector<std::string> row_members_;
};

// One CSV cell from a JSON scalar: integers as written, doubles in their shortest exact form, "nan",
// "inf", booleans "true"/"false", strings as they are.
std::string cell_text(const Json& value);

// RFC 4180 quoting: a cell with a comma, quote, CR or LF is quoted, quotes doubled.
std::string csv_quote(const std::string& cell);

}  // namespace bricklayer::inspect
