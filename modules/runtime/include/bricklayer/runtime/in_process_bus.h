// A bus inside one process, for tests: nodes built on endpoints of one InProcessBus hear each other as
// they would on LCM (every subscriber of a channel, the publisher's own included), but on one thread,
// in a deterministic order, and on a clock the test sets. Delivery never blocks and never moves the
// clock: the test (tests/harness/rig.h) steps the nodes and advances the time.
#pragma once

#include <cstdint>
#include <functional>
#include <list>
#include <memory>
#include <string>
#include <vector>

#include "bricklayer/runtime/bus.h"
#include "bricklayer/runtime/subscription_queues.h"

namespace bricklayer::runtime {

class InProcessBus {
 public:
  // 2026-01-01T00:00:00Z: a fixed, readable start, so runs are identical.
  static constexpr int64_t kDefaultStartUtime = 1767225600000000;

  explicit InProcessBus(int64_t start_utime = kDefaultStartUtime);
  ~InProcessBus();
  InProcessBus(const InProcessBus&) = delete;
  InProcessBus& operator=(const InProcessBus&) = delete;

  // A new endpoint: the Bus one node (or a test's recorder) uses. Owned by the hub.
  Bus& endpoint(const std::string& name = "");

  int64_t now_utime() const { return now_; }
  void set_utime(int64_t utime);    // never backwards
  void advance(int64_t microseconds);

  // Whether any endpoint has messages waiting to be handled.
  bool pending() const;

  // Calls handle_round (every node, recorder and peer handles what is queued, once) while anything is
  // pending, so replies to replies are delivered too; returns the rounds it took. Nodes that keep
  // answering each other are a bug of theirs: after max_rounds it throws std::runtime_error.
  int settle(const std::function<void()>& handle_round, int max_rounds = 10000);

  // Called for every message published through any endpoint, in publication order (a tap for tests).
  using Tap = std::function<void(const std::string& endpoint, const std::string& channel, const uint8_t* data,
                                 size_t size, int64_t utime)>;
  void set_tap(Tap tap) { tap_ = std::move(tap); }

  // Makes every publish() fail, as a transport that is down would (tests of how nodes report it).
  void set_down(bool down) { down_ = down; }

 private:
  class Endpoint;
  void deliver(const Endpoint& from, const std::string& channel, const uint8_t* data, size_t size);

  int64_t now_;
  bool down_ = false;
  std::list<std::unique_ptr<Endpoint>> endpoints_;
  Tap tap_;
};

}  // namespace bricklayer::runtime
