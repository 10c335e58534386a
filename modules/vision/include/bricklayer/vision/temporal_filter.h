// Temporal filtering of detections so the published stack does not flicker: a block is confirmed when
// it was seen in at least N of the last M frames, a lost block is held for a few frames, and its x only
// moves when the measurement leaves a deadband around the published value. Ids are stable while a block
// stays in view; new blocks get fresh ids (left to right, bottom row first within one frame).
// Deterministic: a pure function of the sequence of detections.
#pragma once

#include <cstdint>
#include <vector>

#include "bricklayer/detection/detector.h"

namespace bricklayer::vision {

struct TemporalFilterConfig {
  int confirm_hits = 2;       // N: frames a block must be seen in ...
  int confirm_window = 3;     // M: ... out of the last M frames to be published
  int hold_frames = 3;        // a confirmed block missing for more than this many frames is dropped
  double deadband = 0.01;     // block lengths: smaller changes of x are not published
  double match_distance = 0.3;  // block lengths: a detection within this of a track (same row) is that block
};

struct FilteredBlock {
  int64_t id = 0;
  detection::DetectedBlock block;  // published geometry (x within the deadband of the latest measurement)
  int missed = 0;       // consecutive frames without a measurement (0 = seen in this frame)
  // Block lengths the published x is away from the latest measurement (inside the deadband it is kept while the
  // measurement moves); the deadband itself while the block is held unseen.
  double lag = 0.0;
};

class TemporalFilter {
 public:
  explicit TemporalFilter(const TemporalFilterConfig& config = {});

  // Feeds one frame's detection; returns the confirmed blocks, bottom row first, left to right.
  std::vector<FilteredBlock> update(const std::vector<detection::DetectedBlock>& detections);
  void reset();

 private:
  struct Track {
    int64_t id;
    detection::DetectedBlock published;
    uint32_t history = 0;  // bit k: seen k frames ago
    int missed = 0;
    bool confirmed = false;
    double lag = 0.0;  // FilteredBlock::lag
  };
  TemporalFilterConfig config_;
  std::vector<Track> tracks_;
  int64_t next_id_ = 0;
};

}  // namespace bricklayer::vision
