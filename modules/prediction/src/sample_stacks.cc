#include "bricklayer/prediction/sample_stacks.h"

#include <algorithm>
#include <cmath>
#include <random>

#include "bricklayer/board/board_geometry.h"

namespace bricklayer::prediction {

stack_t sample_stack(int num_blocks, uint32_t seed, int64_t utime, int64_t frame_number) {
  std::mt19937 rng(seed);  // mt19937's sequence is fixed by the standard; the scaling below is ours
  auto uniform = [&rng](double lo, double hi) { return lo + (hi - lo) * (static_cast<double>(rng()) / 4294967296.0); };
  stack_t s{};
  s.utime = utime;
  s.frame_number = frame_number;
  s.block_length = 1.0;
  s.block_height = 1.0 / 3.0;
  s.table_edge = 0.0;
  s.status = stack_t::STATUS_OK;
  const int width = std::max(1, static_cast<int>(std::ceil(std::sqrt(static_cast<double>(num_blocks)))));
  const double shift = uniform(0.0, 1.2);  // how far the wall leans out over the edge
  const BoardGeometry board;
  int id = 0;
  for (int row = 0; id < num_blocks; ++row) {
    const int in_row = std::min(width - (row % 2), num_blocks - id);
    for (int i = 0; i < std::max(1, in_row); ++i, ++id) {
      block_t b{};
      b.id = id + 1;
      b.row = row;
      // 1.05 spacing with +-0.02 jitter: never overlapping within a row.
      b.x = -1.05 * width + shift + i * 1.05 + (row % 2 ? 0.525 : 0.0) + 0.02 * row / 4.0 + uniform(-0.02, 0.02);
      const double u0 = board.to_px_x(b.x), u1 = board.to_px_x(b.x + 1.0);
      const double v0 = board.surface_y_px - row * board.block_height_px, v1 = v0 - board.block_height_px;
      const double us[4] = {u0, u1, u1, u0}, vs[4] = {v0, v0, v1, v1};
      for (int k = 0; k < 4; ++k) {
        b.corner_u[k] = us[k];
        b.corner_v[k] = vs[k];
      }
      b.confidence = 1.0;
      s.blocks.push_back(b);
    }
  }
  s.num_blocks = static_cast<int32_t>(s.blocks.size());
  return s;
}

}  // namespace bricklayer::prediction
