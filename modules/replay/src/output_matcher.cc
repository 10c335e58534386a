#include "bricklayer/replay/output_matcher.h"

#include <algorithm>
#include <tuple>

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
    p.b_stamp_utime = key->utime;
    p.a_log_utime = side == 0 ? log_utime : it->second.front().utime;
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

void OutputMatcher::set_nearest(std::vector<std::string> channels, int64_t tolerance_us, int64_t arrival_us,
                                std::function<bool(const std::vector<uint8_t>&, const std::vector<uint8_t>&)> same) {
  same_ = std::move(same);
  nearest_channels_ = std::move(channels);
  tolerance_us_ = tolerance_us;
  arrival_us_ = arrival_us;
}

bool OutputMatcher::is_nearest(const std::string& channel) const {
  return std::find(nearest_channels_.begin(), nearest_channels_.end(), channel) != nearest_channels_.end();
}

void OutputMatcher::pair_nearest(int64_t log_utime, bool everything) {
  if (nearest_channels_.empty()) return;
  // Every output stamped before `arrived` is here (it reaches the matcher within arrival_us of its
  // stamp); a pair is decided once every output within the tolerance of both is here.
  const int64_t arrived = everything ? INT64_MAX : log_utime - arrival_us_;
  const int64_t decided = everything ? INT64_MAX : arrived - tolerance_us_;
  for (const auto& ch : nearest_channels_) {
    struct Item {
      MessageKey key;
      size_t index;  // in its deque
    };
    std::vector<Item> items[2];
    for (int side = 0; side < 2; ++side) {
      for (auto it = waiting_[side].lower_bound(MessageKey{ch, INT64_MIN, INT64_MIN});
           it != waiting_[side].end() && it->first.channel == ch && it->first.utime < arrived; ++it)
        for (size_t i = 0; i < it->second.size(); ++i) items[side].push_back({it->first, i});
      std::stable_sort(items[side].begin(), items[side].end(),
                       [](const Item& x, const Item& y) { return x.key.utime < y.key.utime; });
    }
    // Nothing to decide yet: nothing old enough to pair or to be alone (the alignment compares
    // contents, pictures decoded: it runs when an output is due, not on every event).
    int64_t oldest = INT64_MAX;
    for (int side = 0; side < 2; ++side)
      if (!items[side].empty()) oldest = std::min<int64_t>(oldest, items[side].front().key.utime);
    if (oldest >= decided) continue;
    // The two sequences aligned in stamp order (the order both published in), at least cost: a pair
    // costs its stamps' distance (plus the tolerance when their contents differ), an output left alone
    // the tolerance. Only outputs about the same input pair (the same frame_number where the type has
    // one: the stack drawn), within the tolerance.
    const size_t n = items[0].size(), m = items[1].size();
    auto bytes = [this](int side, const Item& x) -> const std::vector<uint8_t>& {
      return waiting_[side].find(x.key)->second[x.index].bytes;
    };
    auto pairable = [&](size_t i, size_t j) {
      return items[0][i].key.frame_number == items[1][j].key.frame_number &&
             std::llabs(items[0][i].key.utime - items[1][j].key.utime) <= tolerance_us_;
    };
    std::vector<int64_t> pair_cost(n * m, -1);  // -1: not pairable
    for (size_t i = 0; i < n; ++i)
      for (size_t j = 0; j < m; ++j)
        if (pairable(i, j)) {
          const auto& a = bytes(0, items[0][i]);
          const auto& b = bytes(1, items[1][j]);
          const bool equal = a == b || (same_ && same_(a, b));
          pair_cost[i * m + j] = std::llabs(items[0][i].key.utime - items[1][j].key.utime) + (equal ? 0 : tolerance_us_);
        }
    auto paired_cost = [&](size_t i, size_t j) { return pair_cost[i * m + j]; };
    std::vector<int64_t> cost((n + 1) * (m + 1));
    auto at = [&](size_t i, size_t j) -> int64_t& { return cost[i * (m + 1) + j]; };
    for (size_t i = 0; i <= n; ++i)
      for (size_t j = 0; j <= m; ++j) {
        if (i == 0 || j == 0) {
          at(i, j) = static_cast<int64_t>(i + j) * tolerance_us_;
          continue;
        }
        int64_t c = std::min<int64_t>(at(i - 1, j), at(i, j - 1)) + tolerance_us_;
        if (paired_cost(i - 1, j - 1) >= 0) c = std::min<int64_t>(c, at(i - 1, j - 1) + paired_cost(i - 1, j - 1));
        at(i, j) = c;
      }
    std::vector<std::pair<size_t, size_t>> chosen;
    std::vector<bool> used[2] = {std::vector<bool>(n), std::vector<bool>(m)};
    for (size_t i = n, j = m; i > 0 && j > 0;) {
      if (paired_cost(i - 1, j - 1) >= 0 && at(i, j) == at(i - 1, j - 1) + paired_cost(i - 1, j - 1)) {
        used[0][i - 1] = used[1][j - 1] = true;
        if (std::max(items[0][i - 1].key.utime, items[1][j - 1].key.utime) < decided) chosen.emplace_back(i - 1, j - 1);
        --i;
        --j;
      } else if (at(i, j) == at(i - 1, j) + tolerance_us_) {
        --i;
      } else {
        --j;
      }
    }
    std::reverse(chosen.begin(), chosen.end());
    std::vector<Pair> pairs;
    std::vector<std::pair<MessageKey, size_t>> taken[2];
    for (const auto& [i, j] : chosen) {
      const Item& x = items[0][i];
      const Item& y = items[1][j];
      Pair p;
      p.key = x.key;
      p.nearest = true;
      p.b_stamp_utime = y.key.utime;
      p.a_log_utime = waiting_[0][x.key][x.index].utime;
      p.a = waiting_[0][x.key][x.index].bytes;
      p.b = waiting_[1][y.key][y.index].bytes;
      p.utime = std::max(waiting_[0][x.key][x.index].utime, waiting_[1][y.key][y.index].utime);
      pairs.push_back(std::move(p));
      taken[0].emplace_back(x.key, x.index);
      taken[1].emplace_back(y.key, y.index);
    }
    // What nothing within the tolerance can pair any more is alone now (and the waiting lists stay
    // short: the alignment above looks at all of them).
    std::vector<MessageKey> lone[2];
    for (int side = 0; side < 2; ++side)
      for (size_t i = 0; i < items[side].size(); ++i)
        if (!used[side][i] && items[side][i].key.utime < decided - tolerance_us_) {
          taken[side].emplace_back(items[side][i].key, items[side][i].index);
          lone[side].push_back(items[side][i].key);
        }
    // Taken out of the waiting lists last to first within a key, so the indexes stay valid.
    for (int side = 0; side < 2; ++side) {
      std::sort(taken[side].begin(), taken[side].end(), [](const auto& x, const auto& y) {
        return x.first < y.first || (x.first == y.first && x.second > y.second);
      });
      for (const auto& [k, i] : taken[side]) {
        auto it = waiting_[side].find(k);
        it->second.erase(it->second.begin() + static_cast<std::ptrdiff_t>(i));
        if (it->second.empty()) waiting_[side].erase(it);
      }
    }
    for (const auto& p : pairs) on_pair_(p);
    for (int side = 0; side < 2; ++side)
      for (const auto& k : lone[side]) on_lone_(k, side);
  }
}

void OutputMatcher::advance(int64_t log_utime) {
  pair_nearest(log_utime, false);
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

void OutputMatcher::finish() {
  pair_nearest(INT64_MAX, true);
  advance(INT64_MAX - window_us_ - 1);
}

}  // namespace bricklayer::replay
