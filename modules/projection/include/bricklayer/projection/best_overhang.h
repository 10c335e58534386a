// The best possible overhang for n blocks (block lengths), from the planner's table
// modules/planner/data/best_overhang.json: {"1": 0.5, "2": 0.75, ..., "30": 2.70909, ...}.
#pragma once

#include <map>
#include <optional>
#include <string>

namespace bricklayer::projection {

class BestOverhang {
 public:
  BestOverhang() = default;
  // Throws std::runtime_error naming the problem (unreadable file, bad JSON, a key that is not a
  // positive integer, a value that is not a positive finite number).
  static BestOverhang load(const std::string& path);
  static BestOverhang parse(const std::string& json_text);

  // Best overhang for n blocks, or nothing when the table does not know n.
  std::optional<double> best_for(int num_blocks) const;
  bool empty() const { return table_.empty(); }
  size_t size() const { return table_.size(); }
  // The largest block count the table knows (0 when empty).
  int largest() const { return table_.empty() ? 0 : table_.rbegin()->first; }

 private:
  std::map<int, double> table_;
};

}  // namespace bricklayer::projection
