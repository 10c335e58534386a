#include "bricklayer/logger/recording_policy.h"

#include <algorithm>
#include <cmath>
#include <optional>
#include <stdexcept>

namespace bricklayer::logger {
namespace {

// Frames remembered as thinned: about two minutes at 30 frames a second.
constexpr size_t kThinnedRemembered = 4096;

// utime and frame_number, the first two fields of image_t and of every answer to a frame: LCM encodes
// an 8-byte fingerprint, then the fields in declaration order, integers big-endian.
std::optional<std::pair<int64_t, int64_t>> frame_key(const std::vector<uint8_t>& data) {
  if (data.size() < 24) return std::nullopt;
  auto at = [&](size_t offset) {
    uint64_t v = 0;
    for (size_t i = 0; i < 8; ++i) v = (v << 8) | data[offset + i];
    return static_cast<int64_t>(v);
  };
  return std::make_pair(at(8), at(16));
}

// Whether t is in a window: some moment m with m - before <= t <= m + after. Frames leave in time order,
// so the moments whose window has closed are done and dropped.
bool in_window(std::deque<int64_t>& moments, int64_t t, int64_t before_us, int64_t after_us) {
  while (!moments.empty() && moments.front() + after_us < t) moments.pop_front();
  return !moments.empty() && moments.front() - before_us <= t;
}

}  // namespace

RecordingPolicy::RecordingPolicy(FramePolicyOptions options) : options_(std::move(options)) {
  for (double v : {options_.rate, options_.before_s, options_.after_s, options_.max_mb_per_hour})
    if (!std::isfinite(v) || v < 0)
      throw std::invalid_argument("frame rate, window lengths and the hourly allowance must be finite and >= 0");
  before_us_ = static_cast<int64_t>(std::llround(options_.before_s * 1e6));
  after_us_ = static_cast<int64_t>(std::llround(options_.after_s * 1e6));
  period_us_ = options_.rate > 0 ? static_cast<int64_t>(std::llround(1e6 / options_.rate)) : 0;
  capacity_ = options_.max_mb_per_hour * 1e6;
  per_us_ = capacity_ / 3.6e9;
  allowance_ = capacity_;
}

void RecordingPolicy::refill(int64_t t) {
  if (capacity_ <= 0) return;
  if (refilled_at_ != INT64_MIN && t > refilled_at_)
    allowance_ = std::min(capacity_, allowance_ + per_us_ * static_cast<double>(t - refilled_at_));
  if (refilled_at_ == INT64_MIN || t > refilled_at_) refilled_at_ = t;
}

void RecordingPolicy::pay(int64_t bytes) {
  if (capacity_ <= 0) return;
  // A debt of at most one hour's allowance: after a stretch whose thinned stream alone overspent it
  // (more blocks than the allowance was sized for), windows come back within the hour it is repaid.
  allowance_ = std::max(-capacity_, allowance_ - static_cast<double>(bytes));
}

void RecordingPolicy::offer(Event e) {
  held_bytes_ += EventWriter::file_size_of(e);
  held_.push_back(std::move(e));
}

void RecordingPolicy::moment(int64_t utime, bool exempt) {
  std::deque<int64_t>& moments = exempt ? exempt_ : moments_;
  if (!moments.empty() && utime < moments.back()) utime = moments.back();  // arrival order
  moments.push_back(utime);
}


bool RecordingPolicy::keep_frame(int64_t t, int64_t bytes) {
  const bool exempt = in_window(exempt_, t, before_us_, after_us_);
  bool window = in_window(moments_, t, before_us_, after_us_) || exempt;
  const bool due = last_kept_ == INT64_MIN || t - last_kept_ >= period_us_;
  if (window && !due && !exempt && capacity_ > 0 && allowance_ < static_cast<double>(bytes)) {
    ++window_frames_refused_;
    window = false;
  }
  if (window || due) {
    // The reduced rate is kept on its own grid, so a window does not shift it.
    if (due) last_kept_ = last_kept_ == INT64_MIN || t - last_kept_ >= 2 * period_us_ ? t : last_kept_ + period_us_;
    return true;
  }
  return false;
}

bool RecordingPolicy::is_answer(const std::string& channel) const {
  return std::find(options_.answer_channels.begin(), options_.answer_channels.end(), channel) !=
         options_.answer_channels.end();
}

void RecordingPolicy::remember_thinned(const FrameKey& key) {
  if (!thinned_.insert(key).second) return;
  thinned_order_.push_back(key);
  if (thinned_order_.size() > kThinnedRemembered) {
    thinned_.erase(thinned_order_.front());
    thinned_order_.pop_front();
  }
}

void RecordingPolicy::leave(std::vector<Event>& out) {
  Event& e = held_.front();
  const int64_t bytes = EventWriter::file_size_of(e);
  held_bytes_ -= bytes;
  refill(e.utime);
  const size_t before = out.size();
  if (!thins()) {
    out.push_back(std::move(e));
  } else if (e.channel == options_.frame_channel) {
    if (keep_frame(e.utime, bytes)) {
      ++frames_kept_;
      out.push_back(std::move(e));
    } else {
      ++frames_thinned_;
      if (!options_.answer_channels.empty())
        if (const auto key = frame_key(e.data)) remember_thinned(*key);
    }
  } else if (is_answer(e.channel)) {
    // An answer leaves after its frame (it arrived after it), so its frame is decided by now.
    const auto key = frame_key(e.data);
    if (key && thinned_.count(*key)) {
      ++answers_thinned_;
    } else {
      out.push_back(std::move(e));
    }
  } else {
    out.push_back(std::move(e));
  }
  if (out.size() > before) pay(bytes);
  held_.pop_front();
}

std::vector<Event> RecordingPolicy::release(int64_t now) {
  std::vector<Event> out;
  const int64_t wait = thins() ? before_us_ : 0;
  while (!held_.empty() && (held_.front().utime + wait <= now || held_bytes_ > options_.max_held_bytes)) leave(out);
  return out;
}

std::vector<Event> RecordingPolicy::release_all() {
  std::vector<Event> out;
  while (!held_.empty()) leave(out);
  return out;
}

}  // namespace bricklayer::logger
