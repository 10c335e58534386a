// What of the bus a day's recording keeps: every channel but camera frames, whole; camera frames at a
// reduced rate, plus every frame in a window around the moments that matter (a red block appears, a
// collapse, a round ends, an operator's mark), so the disk holds a whole day and every incident can be
// watched at full rate.
//
// A window reaches back before its moment (what led to a collapse matters most), so frames must be
// held until it is known whether a moment follows: every event waits before_s seconds in a delay line
// (all channels, so the file stays in time order) and each frame is decided when it leaves. The price:
// a logger killed with -9 loses the last before_s seconds instead of the last flush period; a clean
// stop writes everything. rate 0 keeps every frame and holds nothing.
//
// At 60 blocks the answers to each frame (stacks with every block's corners, predictions, timings,
// previews) outweigh the thinned frames themselves. With answer_channels set, an answer to a frame
// the policy thinned goes with it, so a thinned stretch holds whole frame-and-answer sets at the
// reduced rate and the windows hold everything. An answer names its frame by its first two fields,
// utime and frame_number, as image_t does (every answer type is declared so; replay pairs outputs with
// inputs by them too).
//
// A busy exhibit has a moment every few seconds (every red pile is one), so windows alone could keep
// most of the day at full rate: about 4 GB an hour at 60 blocks. max_mb_per_hour bounds the whole
// recording instead: a bucket that holds one hour's allowance, starts full, refills at that rate with
// the events' own times, and pays for every event kept. Frames a window keeps beyond the reduced rate
// are kept only while the bucket holds their bytes; the rest of the recording (every other channel,
// the reduced rate) is always kept and pays too. So H hours take at most (H + 1) * max_mb_per_hour
// while the thinned stream alone stays below the allowance; a window the allowance cannot pay for
// falls back to the reduced rate and is counted (window_frames_refused), never silently. An operator's
// mark is rare and asked for by a person (a visitor's complaint): its window is always kept whole.
#pragma once

#include <cstdint>
#include <deque>
#include <set>
#include <string>
#include <utility>
#include <vector>

#include "bricklayer/logger/event_writer.h"

namespace bricklayer::logger {

struct FramePolicyOptions {
  std::string frame_channel = "BL_IMAGE";
  double rate = 0;          // frames kept per second outside windows; 0 = keep every frame (no delay)
  double before_s = 10;     // full rate this long before a moment ...
  double after_s = 10;      // ... and this long after
  int64_t max_held_bytes = 256ll << 20;  // beyond this the oldest held events leave early (decided as they are)
  std::vector<std::string> answer_channels;  // thinned with the frame they answer (empty: kept whole)
  double max_mb_per_hour = 0;  // with rate > 0: the recording's average bound (MB = 1e6 bytes); 0 = none
};

class RecordingPolicy {
 public:
  // Throws std::invalid_argument for negative or non-finite figures.
  explicit RecordingPolicy(FramePolicyOptions options);

  bool thins() const { return options_.rate > 0; }
  // Takes an event (its utime is its arrival time).
  void offer(Event e);
  // Full rate around utime from now on; an exempt moment's window is kept whole whatever the allowance.
  void moment(int64_t utime, bool exempt = false);
  // The events whose wait is over at now, in arrival order, frames decided; the others.
  std::vector<Event> release(int64_t now_utime);
  // Everything held (at stop): frames decided with the moments known.
  std::vector<Event> release_all();

  int64_t frames_kept() const { return frames_kept_; }
  int64_t frames_thinned() const { return frames_thinned_; }
  int64_t answers_thinned() const { return answers_thinned_; }
  // Frames inside a window thinned to the reduced rate because the hour's allowance was spent.
  int64_t window_frames_refused() const { return window_frames_refused_; }
  // Bytes the allowance holds now (negative after the always-kept stream overspent it); 0 without one.
  double allowance_bytes() const { return allowance_; }
  int64_t held_bytes() const { return held_bytes_; }
  const FramePolicyOptions& options() const { return options_; }

 private:
  using FrameKey = std::pair<int64_t, int64_t>;  // a frame's utime and frame_number

  void leave(std::vector<Event>& out);
  bool keep_frame(int64_t utime, int64_t bytes);
  void refill(int64_t utime);
  void pay(int64_t bytes);
  bool is_answer(const std::string& channel) const;
  void remember_thinned(const FrameKey& key);

  FramePolicyOptions options_;
  int64_t before_us_, after_us_, period_us_;
  std::deque<Event> held_;
  std::deque<int64_t> moments_, exempt_;  // ascending
  int64_t held_bytes_ = 0;
  int64_t last_kept_ = INT64_MIN;
  int64_t frames_kept_ = 0, frames_thinned_ = 0, answers_thinned_ = 0, window_frames_refused_ = 0;
  double capacity_ = 0, per_us_ = 0, allowance_ = 0;  // bytes, bytes per microsecond, bytes
  int64_t refilled_at_ = INT64_MIN;
  // The frames thinned lately (answers come within a second or so of their frame; a bounded memory,
  // oldest forgotten first: an answer to a frame forgotten is kept).
  std::set<FrameKey> thinned_;
  std::deque<FrameKey> thinned_order_;
};

}  // namespace bricklayer::logger
