// Exact percentiles of a stream of integer values in bounded memory: a count per distinct value (the
// report's latencies, rounded down to a resolution of 10 microseconds, take a few thousand distinct
// values a day). Percentiles are nearest-rank: the smallest value with at least p% of the samples at
// or below it, so anyone recomputing them from the CSV gets the same number.
#pragma once

#include <cstdint>
#include <map>

namespace bricklayer::inspect {

class ValueCounts {
 public:
  void add(int64_t value, uint64_t count = 1);
  void merge(const ValueCounts& other);
  uint64_t size() const { return total_; }
  bool empty() const { return total_ == 0; }
  // p in 0..100 (whole percents); 0 gives the minimum. Requires !empty().
  int64_t percentile(int p) const;
  int64_t max() const { return counts_.rbegin()->first; }

 private:
  std::map<int64_t, uint64_t> counts_;
  uint64_t total_ = 0;
};

}  // namespace bricklayer::inspect
