#include "bricklayer/runtime/subscription_queues.h"

#include <algorithm>
#include <stdexcept>

namespace bricklayer::runtime {

const SubscriptionStats& SubscriptionQueues::add(const std::string& channel, QueuePolicy policy, Handler handler) {
  if (policy.capacity == 0) throw std::invalid_argument("a subscription queue needs a capacity of at least 1");
  subscriptions_.push_back(Subscription{channel, policy, std::move(handler), {}, {}});
  if (std::find(channels_.begin(), channels_.end(), channel) == channels_.end()) channels_.push_back(channel);
  return subscriptions_.back().stats;
}

int SubscriptionQueues::enqueue(const std::string& channel, const uint8_t* data, size_t size, int64_t utime) {
  const uint64_t sequence = next_sequence_++;
  int taken = 0;
  for (Subscription& s : subscriptions_) {
    if (s.channel != channel) continue;
    if (s.queue.size() >= s.policy.capacity) {
      s.queue.pop_front();
      ++s.stats.dropped;
    }
    s.queue.push_back(Pending{sequence, utime, std::vector<uint8_t>(data, data + size)});
    ++taken;
  }
  return taken;
}

bool SubscriptionQueues::wanted(const std::string& channel) const {
  return std::find(channels_.begin(), channels_.end(), channel) != channels_.end();
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
    next->handler(Received{next->channel, p.bytes.data(), p.bytes.size(), p.utime});
  }
}

}  // namespace bricklayer::runtime
