#include "bricklayer/inspect/value_counts.h"

#include <string>
#include <stdexcept>

namespace bricklayer::inspect {

void ValueCounts::add(int64_t value, uint64_t count) {
  counts_[value] += count;
  total_ += count;
}

void ValueCounts::merge(const ValueCounts& other) {
  for (const auto& [v, n] : other.counts_) add(v, n);
}

int64_t ValueCounts::percentile(int p) const {
  if (total_ == 0) throw std::logic_error("percentile of no values");
  if (p < 0 || p > 100) throw std::invalid_argument("percentile " + std::to_string(p) + " is not in 0..100");
  // Integer arithmetic: ceil(p * N / 100), with no rounding error at any N.
  uint64_t rank = (static_cast<uint64_t>(p) * total_ + 99) / 100;
  if (rank < 1) rank = 1;
  uint64_t seen = 0;
  for (const auto& [v, n] : counts_) {
    seen += n;
    if (seen >= rank) return v;
  }
  return counts_.rbegin()->first;
}

}  // namespace bricklayer::inspect
