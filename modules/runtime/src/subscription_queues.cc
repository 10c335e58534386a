#include "bricklayer/runtime/subscription_queues.h"

#include <algorithm>
#include <cctype>
#include <stdexcept>

namespace bricklayer::runtime {
namespace {
bool is_plain_name(const std::string& pattern) {
  return std::all_of(pattern.begin(), pattern.end(), [](char c) { return std::isalnum(static_cast<unsigned char>(c)) || c == '_' || c == '-' || c == '/'; });
}
constexpr size_t kMaxRememberedMatches = 4096;
}  // namespace

const SubscriptionStats& SubscriptionQueues::add(const std::string& channel, QueuePolicy policy, Handler handler) {
  if (policy.capacity == 0) throw std::invalid_argument("a subscription queue needs a capacity of at least 1");
  Subscription s{channel, std::nullopt, {}, policy, std::move(handler), {}, {}};
  if (!is_plain_name(channel)) {
    try {
      s.regex.emplace(channel);
    } catch (const std::regex_error& e) {
      throw std::invalid_argument("'" + channel + "' is not a valid channel pattern: " + e.what());
    }
  }
  subscriptions_.push_back(std::move(s));
  if (std::find(patterns_.begin(), patterns_.end(), channel) == patterns_.end()) patterns_.push_back(channel);
  return subscriptions_.back().stats;
}

bool SubscriptionQueues::matches(const Subscription& s, const std::string& channel) {
  if (!s.regex) return s.pattern == channel;
  if (auto it = s.matches.find(channel); it != s.matches.end()) return it->second;
  const bool m = std::regex_match(channel, *s.regex);
  if (s.matches.size() < kMaxRememberedMatches) s.matches.emplace(channel, m);
  return m;
}

void SubscriptionQueues::push(Subscription& s, uint64_t sequence, const std::string& channel, const uint8_t* data,
                              size_t size, int64_t utime) {
  if (s.queue.size() >= s.policy.capacity) {
    s.queue.pop_front();
    ++s.stats.dropped;
  }
  s.queue.push_back(Pending{sequence, utime, channel, std::vector<uint8_t>(data, data + size)});
}

int SubscriptionQueues::enqueue(const std::string& channel, const uint8_t* data, size_t size, int64_t utime) {
  const uint64_t sequence = next_sequence_++;
  int taken = 0;
  for (Subscription& s : subscriptions_) {
    if (!matches(s, channel)) continue;
    push(s, sequence, channel, data, size, utime);
    ++taken;
  }
  return taken;
}

int SubscriptionQueues::enqueue_for(const std::string& pattern, const std::string& channel, const uint8_t* data,
                                    size_t size, int64_t utime) {
  const uint64_t sequence = next_sequence_++;
  int taken = 0;
  for (Subscription& s : subscriptions_) {
    if (s.pattern != pattern) continue;
    push(s, sequence, channel, data, size, utime);
    ++taken;
  }
  return taken;
}

bool SubscriptionQueues::wanted(const std::string& channel) const {
  return std::any_of(subscriptions_.begin(), subscriptions_.end(), [&](const Subscription& s) { return matches(s, channel); });
}

bool SubscriptionQueues::empty() const {
  return std::all_of(subscriptions_.begin(), subscriptions_.end(), [](const Subscription& s) { return s.queue.empty(); });
}

int SubscriptionQueues::dispatch() {
  const uint64_t end = next_sequence_;
  int delivered = 0;
  for (;;) {
    // The oldest queued message of any subscription (a handful of subscriptions: a scan is cheapest).
    Subscription* next = nullptr;
    for (Subscription& s : subscriptions_) {
      if (!s.queue.empty() && s.queue.front().sequence < end && (!next || s.queue.front().sequence < next->queue.front().sequence))
        next = &s;
    }
    if (!next) return delivered;
    Pending p = std::move(next->queue.front());
    next->queue.pop_front();
    ++next->stats.delivered;
    ++delivered;
    next->handler(Received{p.channel, p.bytes.data(), p.bytes.size(), p.utime});
  }
}

}  // namespace bricklayer::runtime
