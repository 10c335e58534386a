#include "bricklayer/replay/output_matcher.h"

namespace bricklayer::replay {

OutputMatcher::OutputMatcher(const MessageDiff& diff, std::function<void(const Pair&)> on_pair,
                             std::function<void(const MessageKey&, int)> on_lone, int64_t window_us)
    : diff_(diff), on_pair_(std::move(on_pair)), on_lone_(std::move(on_lone)), window_us_(window_us) {}

void OutputMatcher::add(int side, const std::string& channel, std::vector<uint8_t> bytes, int64_t log_utime) {
  const auto key = diff_.key(channel, bytes.data(), bytes.size());
  if (!key) {
    on_lone_(MessageKey{"", log_utime, -1}, side);
    return;
  }
  const int other = 1 - side;
  auto it = waiting_[other].find(*key);
  if (it != waiting_[other].end() && !it->second.empty()) {
    Pair p;
    p.key = *key;
    p.utime = log_utime;
    p.a = side == 0 ? std::move(bytes) : std::move(it->second.front().bytes);
    p.b = side == 0 ? std::move(it->second.front().bytes) : std::move(bytes);
    it->second.pop_front();
    if (it->second.empty()) waiting_[other].erase(it);
    on_pair_(p);
    return;
  }
  waiting_[side][*key].push_back({std::move(bytes), log_utime});
  order_[side].emplace_back(log_utime, *key);
}

void OutputMatcher::advance(int64_t log_utime) {
  for (int side = 0; side < 2; ++side) {
    auto& order = order_[side];
    while (!order.empty() && order.front().first + window_us_ < log_utime) {
      const auto [arrived, key] = order.front();
      order.pop_front();
      auto it = waiting_[side].find(key);
      // Paired meanwhile (pairing takes the oldest waiting one first).
      if (it == waiting_[side].end() || it->second.empty() || it->second.front().utime != arrived) continue;
      it->second.pop_front();
      if (it->second.empty()) waiting_[side].erase(it);
      on_lone_(key, side);
    }
  }
}

void OutputMatcher::finish() { advance(INT64_MAX - window_us_ - 1); }

}  // namespace bricklayer::replay
