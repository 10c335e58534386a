// The rules every stack vision publishes obeys, so bricklayer-prediction never rejects one as invalid
// (core::validate): blocks of one row never overlap, and every block lies whole inside the camera image.
//
// Measured positions break the first rule without any detection being wrong: two blocks touching end to end
// are measured a few thousandths of a block apart or overlapping, and the temporal filter's deadband can
// keep a position up to its width away from the measurement. Such small overlaps are resolved by moving the
// blocks the least (in the least-squares sense) until they just touch. An overlap larger than any
// measurement error means one of the two is not a block (a pair of lines taken from two blocks): the one
// with less support (confidence) is dropped. A block cut by the image border was paired from a line the
// camera saw and one it only guessed (or its row band is cut off): dropped. Every change is counted.
#pragma once

#include <vector>

#include <opencv2/core.hpp>

#include "bricklayer/detection/board_frame.h"
#include "bricklayer/detection/detector.h"

namespace bricklayer::vision {

// Block lengths: overlaps up to this are measurement error of touching blocks (vision measures to a
// p95 of 0.002 and a worst case of ~0.03 at the harsh level; the filter's deadband adds 0.01 per block).
inline constexpr double kMaxSnapOverlap = 0.1;

// What make_publishable changed so a stack is one prediction accepts.
struct PublishCounts {
  int moved = 0;            // blocks moved (by at most kMaxSnapOverlap) so touching blocks do not overlap
  int dropped_overlap = 0;  // blocks dropped for overlapping a better-supported block by more than that
  int dropped_border = 0;   // blocks not whole inside the camera image (or with a non-finite position)

  PublishCounts& operator+=(const PublishCounts& o) {
    moved += o.moved, dropped_overlap += o.dropped_overlap, dropped_border += o.dropped_border;
    return *this;
  }
};

// Applies the rules to `blocks` in place, keeping the input's order (moving never reorders a row) and
// returning what changed. `image_size` is the camera frame's size. Blocks that move get their pixel
// geometry recomputed through `frame`.
PublishCounts make_publishable(std::vector<detection::DetectedBlock*>& blocks, const detection::BoardFrame& frame,
                               cv::Size image_size, double max_snap_overlap = kMaxSnapOverlap);

// Convenience for containers of blocks or of anything holding one (get(item) -> detection::DetectedBlock&).
template <class T, class Get>
PublishCounts make_publishable(std::vector<T>& items, Get get, const detection::BoardFrame& frame,
                               cv::Size image_size, double max_snap_overlap = kMaxSnapOverlap) {
  std::vector<detection::DetectedBlock*> blocks;
  blocks.reserve(items.size());
  for (T& item : items) blocks.push_back(&get(item));
  const PublishCounts counts = make_publishable(blocks, frame, image_size, max_snap_overlap);
  std::vector<T> kept;
  kept.reserve(blocks.size());
  size_t next = 0;
  for (T& item : items)
    if (next < blocks.size() && &get(item) == blocks[next]) kept.push_back(std::move(item)), ++next;
  items = std::move(kept);
  return counts;
}

// A detection's own blocks, as bricklayer-vision applies the rules to every frame it detects.
inline PublishCounts make_publishable(std::vector<detection::DetectedBlock>& blocks, const detection::BoardFrame& frame,
                                      cv::Size image_size) {
  return make_publishable(blocks, [](detection::DetectedBlock& b) -> detection::DetectedBlock& { return b; }, frame,
                          image_size);
}

}  // namespace bricklayer::vision
