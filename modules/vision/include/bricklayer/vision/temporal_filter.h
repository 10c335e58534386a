// Temporal filtering of detections so the published stack does not flicker: a block is confirmed when
// it was seen in at least N of the last M frames, a lost block is held for a few frames, and its x only
// moves when the measurement leaves a deadband around the published value. Ids are stable while a block
// stays in view; new blocks get fresh ids (left to right, bottom row first within one frame).
// Each track also keeps its block's recent measured x, whose spread is part of the block's position
// uncertainty (position_uncertainty.h): frame-to-frame scatter of a block that stands still is measurement
// noise seen directly, and a block a hand is moving spreads too.
// Deterministic: a pure function of the sequence of detections.
#pragma once

#include <array>
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
  // Block lengths: a measurement this far from the mean of a track's recent ones starts its history afresh (a
  // hand put the block elsewhere; measurement noise is two orders smaller, its worst outliers ~0.03).
  double history_reset = 0.05;
};

// Frames of measured x a track keeps for its spread (a quarter of a second at 30 frames/s).
inline constexpr int kSpreadFrames = 8;

struct FilteredBlock {
  int64_t id = 0;
  detection::DetectedBlock block;  // published geometry (x within the deadband of the latest measurement)
  int missed = 0;       // consecutive frames without a measurement (0 = seen in this frame)
  // Block lengths the published x is away from the latest measurement (inside the deadband it is kept while the
  // measurement moves); the deadband itself while the block is held unseen.
  double lag = 0.0;
  // This block's own measurement uncertainty (block lengths) as given to update() with its latest measurement
  // (kept while it is held unseen); 0 when none was given.
  double measured_uncertainty = 0.0;
  // Sample standard deviation (block lengths) of its last `spread_samples` measured x (up to kSpreadFrames,
  // since its history last started: see TemporalFilterConfig::history_reset).
  double spread = 0.0;
  int spread_samples = 0;
};

class TemporalFilter {
 public:
  explicit TemporalFilter(const TemporalFilterConfig& config = {});

  // Feeds one frame's detection; returns the confirmed blocks, bottom row first, left to right.
  // `uncertainties`: each detection's measurement uncertainty (same order), or empty for none.
  // Throws std::invalid_argument when it is neither empty nor one per detection.
  std::vector<FilteredBlock> update(const std::vector<detection::DetectedBlock>& detections,
                                    const std::vector<double>& uncertainties = {});
  void reset();

 private:
  struct Track {
    int64_t id;
    detection::DetectedBlock published;
    uint32_t history = 0;  // bit k: seen k frames ago
    int missed = 0;
    bool confirmed = false;
    double lag = 0.0;  // FilteredBlock::lag
    double measured_uncertainty = 0.0;
    std::array<double, kSpreadFrames> recent{};  // ring of measured x, `recent_count` valid, newest at recent_next - 1
    int recent_count = 0, recent_next = 0;
  };
  static void remember(Track& track, double x, double reset);
  static FilteredBlock output(const Track& track);
  static double recent_at(const Track& track, int k);  // the k-th oldest recent measurement
  static double recent_mean(const Track& track);
  TemporalFilterConfig config_;
  std::vector<Track> tracks_;
  int64_t next_id_ = 0;
};

}  // namespace bricklayer::vision
