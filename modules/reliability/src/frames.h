// Camera frames for the soak and the latency benchmark: simcam renders of a random pile with a given
// number of blocks, JPEG-encoded as a camera would publish them. Deterministic per seed.
#pragma once

#include <algorithm>
#include <cstdint>
#include <vector>

#include <opencv2/imgcodecs.hpp>

#include "bricklayer/simcam/piles.h"
#include "bricklayer/simcam/render.h"

namespace bricklayer::reliability {

struct Frames {
  std::vector<std::vector<uint8_t>> jpeg;
  cv::Size size;
};

// More blocks per row for big piles so 200 blocks stay inside the default camera view.
inline Frames render_frames(int blocks, int count, uint64_t seed = 1000) {
  simcam::Renderer renderer;
  simcam::PileOptions opt;
  opt.blocks = blocks;
  opt.max_per_row = std::max(9, blocks / 12 + 1);
  if (blocks > 60) {
    opt.min_gap = 0.02;
    opt.max_gap = 0.3;
  }
  simcam::Nuisance nuisance;
  Frames out;
  for (int i = 0; i < count; ++i) {
    auto r = renderer.render(simcam::random_pile(seed + static_cast<uint64_t>(i), opt), nuisance, nullptr, seed + 7 + i);
    std::vector<uint8_t> jpeg;
    cv::imencode(".jpg", r.bgr, jpeg, {cv::IMWRITE_JPEG_QUALITY, 90});
    out.jpeg.push_back(std::move(jpeg));
    out.size = r.bgr.size();
  }
  return out;
}

}  // namespace bricklayer::reliability
