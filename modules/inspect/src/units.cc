#include "bricklayer/inspect/units.h"

#include <map>
#include <utility>

#include "bricklayer/inspect/wall_clock.h"

namespace bricklayer::inspect {

namespace {

bool ends_with(const std::string& s, const std::string& tail) {
  return s.size() > tail.size() && s.compare(s.size() - tail.size(), tail.size(), tail) == 0;
}

const std::map<std::pair<std::string, std::string>, std::string>& table() {
  static const std::map<std::pair<std::string, std::string>, std::string> units = {
      {{"bricklayer.image_t", "width"}, "px"},
      {{"bricklayer.image_t", "height"}, "px"},
      {{"bricklayer.image_t", "size"}, "bytes"},
      {{"bricklayer.block_t", "x"}, "block_lengths"},
      {{"bricklayer.block_t", "corner_u"}, "px"},
      {{"bricklayer.block_t", "corner_v"}, "px"},
      {{"bricklayer.stack_t", "block_height"}, "block_lengths"},
      {{"bricklayer.stack_t", "table_edge"}, "block_lengths"},
      {{"bricklayer.block_prediction_t", "accel"}, "g"},
      {{"bricklayer.block_prediction_t", "alpha"}, "g_per_block_length"},
      {{"bricklayer.prediction_t", "overhang"}, "block_lengths"},
      {{"bricklayer.prediction_t", "score"}, "points"},
      {{"bricklayer.prediction_t", "position_tolerance"}, "block_lengths"},
      {{"bricklayer.calibration_t", "camera_width"}, "px"},
      {{"bricklayer.calibration_t", "camera_height"}, "px"},
      {{"bricklayer.calibration_t", "projector_width"}, "px"},
      {{"bricklayer.calibration_t", "projector_height"}, "px"},
      {{"bricklayer.calibration_t", "camera_matrix"}, "px"},
      {{"bricklayer.calibration_t", "block_height"}, "block_lengths"},
      {{"bricklayer.round_t", "score"}, "points"},
      {{"bricklayer.round_t", "max_score"}, "points"},
      {{"bricklayer.round_t", "best_possible"}, "block_lengths"},
      {{"bricklayer.hint_t", "xs"}, "block_lengths"},
      {{"bricklayer.hint_t", "score_after"}, "points"},
      {{"bricklayer.hint_t", "margin"}, "block_lengths"},
  };
  return units;
}

}  // namespace

std::string unit_suffix(const std::string& type, const std::string& member) {
  if (is_utime_name(member)) return "us";
  for (const char* tail : {"_us", "_ms", "_s", "_px", "_kb", "_mb", "_bytes"})
    if (ends_with(member, tail)) return "";
  auto it = table().find({type, member});
  return it == table().end() ? "" : it->second;
}

std::string column_name(const std::string& type, const std::string& member) {
  std::string unit = unit_suffix(type, member);
  return unit.empty() ? member : member + "_" + unit;
}

}  // namespace bricklayer::inspect
