// The queueing every bus implementation shares, so that the three deliver by the same rules: each
// subscription holds its messages under its QueuePolicy (oldest dropped first, counted), and
// dispatch() hands them to their handlers in global arrival order. A subscription's channel is, as in
// LCM, a regular expression matched against the whole channel name ("BL_STACK", ".*", "BL_.*").
#pragma once

#include <cstdint>
#include <deque>
#include <list>
#include <map>
#include <optional>
#include <regex>
#include <string>
#include <vector>

#include "bricklayer/runtime/bus.h"

namespace bricklayer::runtime {

class SubscriptionQueues {
 public:
  // The stats of the new subscription (stable for the life of this object).
  const SubscriptionStats& add(const std::string& channel, QueuePolicy policy, Handler handler);

  // Queues a copy of the message for every subscription whose pattern matches the channel. Returns
  // how many took it.
  int enqueue(const std::string& channel, const uint8_t* data, size_t size, int64_t utime);
  // The same, for the subscriptions made with exactly this pattern (LCM has already matched it).
  int enqueue_for(const std::string& pattern, const std::string& channel, const uint8_t* data, size_t size,
                  int64_t utime);

  // Whether any subscription listens to the channel.
  bool wanted(const std::string& channel) const;

  // Delivers the messages queued before this call, in arrival order. Messages queued by the
  // handlers themselves wait for the next call (a node answering itself cannot loop forever).
  // Returns how many were delivered. Handlers must not throw (the node wraps them).
  int dispatch();

  bool empty() const;
  // The distinct patterns subscribed to, in subscription order.
  const std::vector<std::string>& patterns() const { return patterns_; }

 private:
  struct Pending {
    uint64_t sequence;
    int64_t utime;
    std::string channel;
    std::vector<uint8_t> bytes;
  };
  struct Subscription {
    std::string pattern;
    std::optional<std::regex> regex;  // unset when the pattern is a plain channel name
    mutable std::map<std::string, bool> matches;  // regex results by channel (bounded: names come from the network)
    QueuePolicy policy;
    Handler handler;
    SubscriptionStats stats;
    std::deque<Pending> queue;
  };
  static bool matches(const Subscription& s, const std::string& channel);
  void push(Subscription& s, uint64_t sequence, const std::string& channel, const uint8_t* data, size_t size,
            int64_t utime);

  std::list<Subscription> subscriptions_;  // stable addresses: the stats are handed out
  std::vector<std::string> patterns_;      // distinct, in subscription order
  uint64_t next_sequence_ = 0;
};

}  // namespace bricklayer::runtime
