// Camera frames for the soak and the latency benchmark: simcam renders of a pile with a given
// number of blocks, all in view (piles::pile_in_view), JPEG-encoded as a camera would publish them.
// Deterministic per seed.
#pragma once

#include <cstdint>
#include <stdexcept>
#include <vector>

#include <opencv2/imgcodecs.hpp>

#include "bricklayer/piles/pile_in_view.h"
#include "bricklayer/simcam/render.h"

namespace bricklayer::reliability {

struct Frames {
  std::vector<std::vector<uint8_t>> jpeg;
  cv::Size size;
};

inline Frames render_frames(int blocks, int count, uint64_t seed = 1000) {
  if (blocks > 210) throw std::invalid_argument("render_frames: at most 210 blocks fit the default camera view");
  simcam::Renderer renderer;
  simcam::Nuisance nuisance;
  Frames out;
  for (int i = 0; i < count; ++i) {
    auto r = renderer.render(piles::pile_in_view(blocks, seed + static_cast<uint64_t>(i)), nuisance, nullptr, seed + 7 + i);
    std::vector<uint8_t> jpeg;
    cv::imencode(".jpg", r.bgr, jpeg, {cv::IMWRITE_JPEG_QUALITY, 90});
    out.jpeg.push_back(std::move(jpeg));
    out.size = r.bgr.size();
  }
  return out;
}

}  // namespace bricklayer::reliability
