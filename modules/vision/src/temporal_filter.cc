#include "bricklayer/vision/temporal_filter.h"

#include <algorithm>
#include <bit>
#include <cmath>
#include <stdexcept>
#include <string>
#include <tuple>

namespace bricklayer::vision {

using detection::DetectedBlock;

TemporalFilter::TemporalFilter(const TemporalFilterConfig& config) : config_(config) {
  if (config.confirm_window < 1 || config.confirm_window > 32 || config.confirm_hits < 1 ||
      config.confirm_hits > config.confirm_window || config.hold_frames < 0 || !(config.deadband >= 0) ||
      !(config.match_distance > 0) || !(config.history_reset > 0))
    throw std::invalid_argument(
        "temporal filter: need 1 <= N <= M <= 32, hold >= 0, deadband >= 0, match > 0, history reset > 0");
}

void TemporalFilter::reset() {
  tracks_.clear();
  next_id_ = 0;
}

// The k-th oldest of a track's recent measurements. Sums run oldest first, never in the ring's storage
// order: the same recent measurements then give the same bits whatever the ring's phase, which depends
// on every frame since the track began (a replay that sees a frame the live process dropped long ago
// would otherwise differ in the last bit).
double TemporalFilter::recent_at(const Track& t, int k) {
  return t.recent[static_cast<size_t>((t.recent_next - t.recent_count + k + kSpreadFrames) % kSpreadFrames)];
}

double TemporalFilter::recent_mean(const Track& t) {
  double mean = 0;
  for (int k = 0; k < t.recent_count; ++k) mean += recent_at(t, k);
  return mean / t.recent_count;
}

void TemporalFilter::remember(Track& t, double x, double reset) {
  if (t.recent_count > 0) {
    const double mean = recent_mean(t);
    if (std::abs(x - mean) > reset) t.recent_count = 0, t.recent_next = 0;
  }
  t.recent[static_cast<size_t>(t.recent_next)] = x;
  t.recent_next = (t.recent_next + 1) % kSpreadFrames;
  t.recent_count = std::min(t.recent_count + 1, kSpreadFrames);
}

FilteredBlock TemporalFilter::output(const Track& t) {
  FilteredBlock b{t.id, t.published, t.missed, t.lag, t.measured_uncertainty, 0.0, t.recent_count};
  if (t.recent_count >= 2) {
    const double mean = recent_mean(t);
    double ss = 0;
    for (int k = 0; k < t.recent_count; ++k) ss += (recent_at(t, k) - mean) * (recent_at(t, k) - mean);
    b.spread = std::sqrt(ss / (t.recent_count - 1));
  }
  return b;
}

std::vector<FilteredBlock> TemporalFilter::update(const std::vector<DetectedBlock>& detections,
                                                  const std::vector<double>& uncertainties) {
  if (!uncertainties.empty() && uncertainties.size() != detections.size())
    throw std::invalid_argument("temporal filter: " + std::to_string(uncertainties.size()) + " uncertainties for " +
                                std::to_string(detections.size()) + " detections");
  auto uncertainty = [&](size_t d) { return uncertainties.empty() ? 0.0 : uncertainties[d]; };
  // Greedy association by distance, nearest pairs first, same row only; ties broken by index so the
  // result does not depend on anything but the inputs.
  struct Candidate {
    double distance;
    size_t track, detection;
  };
  std::vector<Candidate> candidates;
  for (size_t t = 0; t < tracks_.size(); ++t) {
    for (size_t d = 0; d < detections.size(); ++d) {
      if (detections[d].row != tracks_[t].published.row) continue;
      const double dist = std::abs(detections[d].x - tracks_[t].published.x);
      if (dist <= config_.match_distance) candidates.push_back({dist, t, d});
    }
  }
  std::sort(candidates.begin(), candidates.end(), [](const Candidate& a, const Candidate& b) {
    return std::tie(a.distance, a.track, a.detection) < std::tie(b.distance, b.track, b.detection);
  });
  std::vector<int> track_match(tracks_.size(), -1), detection_match(detections.size(), -1);
  for (const Candidate& c : candidates) {
    if (track_match[c.track] >= 0 || detection_match[c.detection] >= 0) continue;
    track_match[c.track] = static_cast<int>(c.detection);
    detection_match[c.detection] = static_cast<int>(c.track);
  }

  const uint32_t window_mask = config_.confirm_window >= 32 ? ~0u : ((1u << config_.confirm_window) - 1);
  std::vector<Track> kept;
  for (size_t t = 0; t < tracks_.size(); ++t) {
    Track track = tracks_[t];
    track.history = (track.history << 1) & window_mask;
    if (track_match[t] >= 0) {
      const DetectedBlock& m = detections[track_match[t]];
      track.measured_uncertainty = uncertainty(static_cast<size_t>(track_match[t]));
      remember(track, m.x, config_.history_reset);
      track.history |= 1u;
      track.missed = 0;
      const double x_before = track.published.x;
      const double left_before = track.published.left_px;
      if (std::abs(m.x - x_before) > config_.deadband) {
        track.published = m;
        track.lag = 0.0;
      } else {
        track.lag = std::abs(m.x - x_before);
        // Inside the deadband: keep the published position, refresh everything else.
        track.published = m;
        track.published.x = x_before;
        track.published.left_px = left_before;
        track.published.corner_u = tracks_[t].published.corner_u;
        track.published.corner_v = tracks_[t].published.corner_v;
      }
    } else {
      ++track.missed;
      track.lag = config_.deadband;  // unseen: it may have moved up to the deadband unnoticed
    }
    if (std::popcount(track.history) >= config_.confirm_hits) track.confirmed = true;
    const bool lost = track.confirmed ? track.missed > config_.hold_frames
                                      : track.history == 0;  // an unconfirmed block gone from the window
    if (!lost) kept.push_back(track);
  }
  // New tracks in detection order (bottom row first, left to right).
  for (size_t d = 0; d < detections.size(); ++d) {
    if (detection_match[d] >= 0) continue;
    Track track{next_id_++, detections[d], 1u, 0, config_.confirm_hits <= 1};
    track.measured_uncertainty = uncertainty(d);
    remember(track, detections[d].x, config_.history_reset);
    kept.push_back(track);
  }
  tracks_ = std::move(kept);

  // A held block that now overlaps a block seen in this frame (same row) has been replaced by it (it
  // moved further than match_distance): drop it, never publish two blocks in one place.
  std::vector<Track> live;
  for (const Track& t : tracks_) {
    bool replaced = false;
    if (t.missed > 0) {
      for (const Track& o : tracks_)
        if (o.missed == 0 && o.published.row == t.published.row && std::abs(o.published.x - t.published.x) < 1.0)
          replaced = true;
    }
    if (!replaced) live.push_back(t);
  }
  tracks_ = std::move(live);
  std::vector<FilteredBlock> out;
  for (const Track& t : tracks_)
    if (t.confirmed) out.push_back(output(t));
  std::sort(out.begin(), out.end(), [](const FilteredBlock& a, const FilteredBlock& b) {
    return std::tie(a.block.row, a.block.x, a.id) < std::tie(b.block.row, b.block.x, b.id);
  });
  return out;
}

}  // namespace bricklayer::vision
