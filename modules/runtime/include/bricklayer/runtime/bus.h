// The bus a node talks through: publish, subscribe with an explicit queue policy, handle with a
// timeout, and a clock. Three implementations share this interface and its delivery rules
// (Drake's DrakeLcmInterface in spirit):
//   LcmBus        the live exhibit (LCM udpm); its clock is the wall clock; it heals a lost socket
//   InProcessBus  tests: one thread, deterministic delivery order, a clock the test sets
//   LogBus        a recorded log, delivered in order as fast as the node consumes it; its clock is
//                 each event's recorded utime, never the wall clock
// A node reads time only through now_utime(), so its outputs are a function of its inputs and their
// times, and a recorded run replays byte for byte.
#pragma once

#include <cstddef>
#include <cstdint>
#include <functional>
#include <string>

namespace bricklayer::runtime {

// How a subscription's queue overflows between two handle() calls: it holds at most `capacity`
// messages and, when full, drops the oldest (every drop is counted). capacity 1 is "newest wins":
// a module that falls behind skips to the newest input instead of working through a backlog.
struct QueuePolicy {
  size_t capacity = 1;
  static QueuePolicy newest() { return QueuePolicy{1}; }
  static QueuePolicy keep(size_t capacity) { return QueuePolicy{capacity}; }
};

// One message as a handler sees it. data is valid only during the call.
struct Received {
  const std::string& channel;  // the message's channel (not the pattern subscribed to)
  const uint8_t* data;
  size_t size;
  int64_t utime;  // the bus clock when the message arrived, microseconds
};

using Handler = std::function<void(const Received&)>;

// What a subscription has seen, for the node's counters.
struct SubscriptionStats {
  int64_t delivered = 0;  // handed to the handler
  int64_t dropped = 0;    // pushed out of a full queue by newer messages
};

class Bus {
 public:
  // handle() returns kEnded when no message will ever arrive again (a recorded log played to its end).
  static constexpr int kEnded = -2;

  virtual ~Bus() = default;

  // Sends a message to every subscriber of the channel, this bus's own included (as LCM udpm does).
  // Returns false when the transport refused it (the bus is down, the message is too large).
  virtual bool publish(const std::string& channel, const uint8_t* data, size_t size) = 0;

  // Delivers every message on `channel` to handler, from handle() on the calling thread, in arrival
  // order across all subscriptions. As in LCM, `channel` is a regular expression matched against the
  // whole channel name (".*" is every channel). The returned stats live as long as the bus.
  virtual const SubscriptionStats& subscribe(const std::string& channel, QueuePolicy policy, Handler handler) = 0;

  // Waits up to timeout_ms (by this bus's clock) for messages, then delivers what is queued. Returns
  // how many were delivered (0 when the wait ended with none), or kEnded.
  virtual int handle(int timeout_ms) = 0;

  // Microseconds since the epoch, by this bus's clock.
  virtual int64_t now_utime() const = 0;

  // "" while the transport works, else a short operator-readable problem ("no multicast route ...").
  virtual std::string problem() const { return ""; }

  // For logs and status lines: the URL, "in-process" or the log's path.
  virtual std::string describe() const = 0;
};

}  // namespace bricklayer::runtime
