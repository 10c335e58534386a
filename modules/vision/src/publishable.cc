#include "bricklayer/vision/publishable.h"

#include <algorithm>
#include <cmath>
#include <tuple>

namespace bricklayer::vision {

using detection::BoardFrame;
using detection::DetectedBlock;
using detection::place_block;
using detection::whole_in_view;

namespace {

// Least-squares positions of one row's blocks (sorted by x) such that each starts at least one length
// after the previous one: with y_i = x_i - i the constraint is y non-decreasing, so the answer is the
// isotonic regression of y (pool adjacent violators), exact and order-preserving.
void separate_row(const std::vector<DetectedBlock*>& row, std::vector<double>& x_out) {
  struct Pool {
    double sum;
    int count;
    double mean() const { return sum / count; }
  };
  std::vector<Pool> pools;
  for (size_t i = 0; i < row.size(); ++i) {
    pools.push_back({row[i]->x - static_cast<double>(i), 1});
    while (pools.size() > 1 && pools[pools.size() - 2].mean() > pools.back().mean()) {
      pools[pools.size() - 2].sum += pools.back().sum;
      pools[pools.size() - 2].count += pools.back().count;
      pools.pop_back();
    }
  }
  x_out.clear();
  for (const Pool& p : pools) {
    if (p.count == 1) {  // untouched: keep x bit for bit
      x_out.push_back(row[x_out.size()]->x);
      continue;
    }
    for (int k = 0; k < p.count; ++k) x_out.push_back(p.mean() + static_cast<double>(x_out.size()));
  }
}

}  // namespace

PublishCounts make_publishable(std::vector<DetectedBlock*>& blocks, const BoardFrame& frame, cv::Size image_size,
                               double max_snap_overlap) {
  PublishCounts counts;
  std::vector<DetectedBlock*> order;
  for (DetectedBlock* b : blocks) {
    if (whole_in_view(*b, image_size))
      order.push_back(b);
    else
      ++counts.dropped_border;
  }
  // Stable order: by row, then x, then input position (ties are exact duplicates; keep the first).
  std::vector<size_t> rank(order.size());
  for (size_t i = 0; i < order.size(); ++i) rank[i] = i;
  std::sort(rank.begin(), rank.end(), [&](size_t a, size_t b) {
    return std::tie(order[a]->row, order[a]->x, a) < std::tie(order[b]->row, order[b]->x, b);
  });
  std::vector<bool> keep(order.size(), true);
  std::vector<DetectedBlock*> row;
  std::vector<double> separated;
  for (size_t start = 0; start < rank.size();) {
    size_t end = start;
    while (end < rank.size() && order[rank[end]]->row == order[rank[start]]->row) ++end;
    // Large overlaps: keep the better-supported block (on equal confidence the left one), then compare
    // the next block with the survivor.
    std::vector<size_t> kept_in_row;
    for (size_t k = start; k < end; ++k) {
      const size_t q = rank[k];
      while (!kept_in_row.empty()) {
        const size_t p = kept_in_row.back();
        if (order[p]->x + 1.0 - order[q]->x <= max_snap_overlap) break;
        ++counts.dropped_overlap;
        if (order[q]->confidence > order[p]->confidence) {
          keep[p] = false;
          kept_in_row.pop_back();  // q may overlap the block before p too
        } else {
          keep[q] = false;
          break;
        }
      }
      if (keep[q]) kept_in_row.push_back(q);
    }
    // Small overlaps: move the least so neighbours at most touch.
    row.clear();
    for (size_t i : kept_in_row) row.push_back(order[i]);
    separate_row(row, separated);
    for (size_t i = 0; i < row.size(); ++i) {
      if (separated[i] == row[i]->x) continue;
      row[i]->x = separated[i];
      place_block(*row[i], frame);
      ++counts.moved;
    }
    start = end;
  }
  std::vector<DetectedBlock*> out;
  for (size_t i = 0; i < order.size(); ++i) {
    if (!keep[i]) continue;
    if (!whole_in_view(*order[i], image_size)) {  // moved across the border (dropping never creates an overlap)
      ++counts.dropped_border;
      continue;
    }
    out.push_back(order[i]);
  }
  blocks = std::move(out);
  return counts;
}

}  // namespace bricklayer::vision
