// bricklayer-bench-planner: median and p99 of the collapse preview and of the next-block hint at 60 blocks
// (12 staggered rows of 5, 40 jittered piles each; previews of the same walls with the top rows pushed
// over the edge). Prints one line per measurement.
#include <algorithm>
#include <chrono>
#include <cstdio>
#include <vector>

#include "bricklayer/core/predict.h"
#include "bricklayer/planner/collapse.h"
#include "bricklayer/planner/hint.h"
#include "bricklayer/planner/piles.h"

using namespace bricklayer;

namespace {

void report(const char* what, std::vector<double> ms) {
  std::sort(ms.begin(), ms.end());
  const double median = ms[ms.size() / 2];
  const double p99 = ms[std::min(ms.size() - 1, static_cast<size_t>(0.99 * static_cast<double>(ms.size())))];
  std::printf("%-40s n=%3zu median %8.3f ms  p99 %8.3f ms  max %8.3f ms\n", what, ms.size(), median, p99, ms.back());
}

template <typename F>
double time_ms(F f) {
  const auto t0 = std::chrono::steady_clock::now();
  f();
  return std::chrono::duration<double, std::milli>(std::chrono::steady_clock::now() - t0).count();
}

}  // namespace

int main() {
  constexpr int kPiles = 40;
  std::vector<double> preview_ms, hint_ms, rebalance_ms;
  int frames = 0, evaluations = 0;
  for (int seed = 1; seed <= kPiles; ++seed) {
    // Preview: the top 4 rows pushed 1.3 beyond the edge.
    const core::Stack falling = planner::toppling_pile(12, 5, 4, 1.3 + 0.01 * seed, static_cast<uint64_t>(seed));
    const core::Prediction p = core::predict(falling);
    planner::CollapseInput input;
    input.block_height = falling.block_height;
    for (size_t i = 0; i < falling.blocks.size(); ++i)
      input.blocks.push_back({falling.blocks[i].row, falling.blocks[i].x, p.blocks[i].state != core::BlockState::kStable});
    planner::CollapsePreview preview;
    preview_ms.push_back(time_ms([&] { preview = planner::simulate_collapse(input); }));
    frames += static_cast<int>(preview.frames.size());

    const core::Stack wall = planner::wall_pile(12, 5, static_cast<uint64_t>(seed), 0.3);
    planner::Hint hint;
    hint_ms.push_back(time_ms([&] { hint = planner::next_block_hint(wall); }));
    evaluations += hint.evaluations;

    const core::Stack tipping = planner::toppling_pile(12, 5, 1, 0.62, static_cast<uint64_t>(seed));
    rebalance_ms.push_back(time_ms([&] { hint = planner::next_block_hint(tipping); }));
  }
  std::printf("bricklayer-bench-planner: 60 blocks, %d piles each\n", kPiles);
  report("collapse preview (simulate_collapse)", preview_ms);
  report("hint, balanced pile (extend)", hint_ms);
  report("hint, unbalanced pile (rebalance)", rebalance_ms);
  std::printf("mean key frames per preview %.1f, mean predict() calls per extend hint %.1f\n",
              static_cast<double>(frames) / kPiles, static_cast<double>(evaluations) / kPiles);
  return 0;
}
