// Camera frames for the soak and the latency benchmark: simcam renders of a pile with a given
// number of blocks, all in view, JPEG-encoded as a camera would publish them. Deterministic per seed.
#pragma once

#include <algorithm>
#include <cmath>
#include <cstdint>
#include <random>
#include <stdexcept>
#include <vector>

#include <opencv2/imgcodecs.hpp>

#include "bricklayer/core/stack.h"
#include "bricklayer/simcam/render.h"

namespace bricklayer::reliability {

struct Frames {
  std::vector<std::vector<uint8_t>> jpeg;
  cv::Size size;
};

// A pile of n blocks that the default camera sees whole, as a player builds it: columns of blocks standing
// on each other (each block within +-0.015 of its column, so every one rests on the one below), rows of
// ceil(n / 21) (at least 5) columns with gaps of 0.04-0.3, the last row partly filled. For odd seeds the top
// block of the rightmost column leans 0.6 out over its support: an unbalanced pile with a cause, so the
// frames alternate between the two cases prediction meets. The default view is 10.67 block lengths wide
// and 22 rows tall, so up to 210 blocks fit. (simcam's random_pile grows piles upwards past the view, and
// vision rightly drops blocks it cannot see whole: the benchmark would time fewer blocks than it names.)
inline core::Stack pile_in_view(int n, uint64_t seed) {
  std::mt19937_64 rng(seed);
  const int columns = std::max(5, (n + 20) / 21);
  const double max_gap = std::min(0.3, (10.4 - columns) / std::max(1, columns - 1));
  std::uniform_real_distribution<double> gap(0.04, std::max(0.04, max_gap)), jitter(-0.015, 0.015), unit(0.0, 1.0);
  std::vector<double> base(static_cast<size_t>(columns));
  double width = columns;
  for (int k = 1; k < columns; ++k) width += (base[static_cast<size_t>(k)] = gap(rng));
  double x = -5.25 + unit(rng) * std::max(0.0, 10.5 - width);
  for (int k = 0; k < columns; ++k) {
    x += base[static_cast<size_t>(k)];
    base[static_cast<size_t>(k)] = x;
    x += 1.0;
  }
  core::Stack s;
  for (int id = 1, row = 0; id <= n; ++row)
    for (int k = 0; k < columns && id <= n; ++k, ++id) s.blocks.push_back({id, row, base[static_cast<size_t>(k)] + jitter(rng)});
  if (seed % 2 == 1 && !s.blocks.empty()) {
    // The top block of the rightmost column (the last block placed in that column).
    size_t top = 0;
    for (size_t i = 0; i < s.blocks.size(); ++i)
      if (std::abs(s.blocks[i].x - base.back()) < 0.1 && s.blocks[i].row >= s.blocks[top].row) top = i;
    if (s.blocks[top].row > 0) s.blocks[top].x += 0.6;
  }
  return s;
}

inline Frames render_frames(int blocks, int count, uint64_t seed = 1000) {
  if (blocks > 210) throw std::invalid_argument("render_frames: at most 210 blocks fit the default camera view");
  simcam::Renderer renderer;
  simcam::Nuisance nuisance;
  Frames out;
  for (int i = 0; i < count; ++i) {
    auto r = renderer.render(pile_in_view(blocks, seed + static_cast<uint64_t>(i)), nuisance, nullptr, seed + 7 + i);
    std::vector<uint8_t> jpeg;
    cv::imencode(".jpg", r.bgr, jpeg, {cv::IMWRITE_JPEG_QUALITY, 90});
    out.jpeg.push_back(std::move(jpeg));
    out.size = r.bgr.size();
  }
  return out;
}

}  // namespace bricklayer::reliability
