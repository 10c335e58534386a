// A module's logic as a node on a Bus. The runtime owns what every module shares: defensive decoding
// (oversized, malformed and other-type messages are counted errors with a rate-limited warning, never
// crashes), queue policies with counted drops, the heartbeat with its counters and status once a
// second, input staleness ("no frames for 7 s"), the configuration recorded on BL_CONFIG, and a clean
// stop. A node subscribes, publishes and reads the time only through here, so the same node runs
// live (LcmBus), in a test (InProcessBus) and from a recorded log (LogBus).
//
// Writing a node: derive, subscribe in the constructor, publish from handlers or from tick():
//
//   class EchoNode final : public runtime::Node {
//    public:
//     EchoNode(const EchoConfig& config, runtime::Bus& bus) : Node("echo", bus) {
//       subscribe<stack_t>(channel(kStackChannel), QueuePolicy::newest(), [this](const stack_t& s) { publish(..., s); });
//     }
//   };
#pragma once

#include <chrono>
#include <cstdint>
#include <deque>
#include <list>
#include <functional>
#include <map>
#include <optional>
#include <string>
#include <vector>

#include "bricklayer/heartbeat_t.hpp"
#include "bricklayer/runtime/bus.h"
#include "bricklayer/runtime/codec.h"
#include "bricklayer/runtime/rate_limited_log.h"

namespace bricklayer::runtime {

inline constexpr size_t kDefaultMaxMessageBytes = 16u << 20;

struct NodeCounters {
  int64_t received = 0;   // inputs that decoded (a newer one may still supersede them: dropped)
  int64_t published = 0;  // outputs sent (reports such as timings and heartbeats are not counted)
  int64_t dropped = 0;    // inputs skipped by the node itself (queue drops are added in the heartbeat)
  int64_t errors = 0;     // rejected inputs, failed computations, refused publications
};

class Node {
 public:
  Node(std::string name, Bus& bus);
  virtual ~Node();
  Node(const Node&) = delete;
  Node& operator=(const Node&) = delete;

  const std::string& name() const { return name_; }
  Bus& bus() { return bus_; }
  int64_t now() const { return bus_.now_utime(); }

  // One iteration: waits for input up to timeout_ms (by the bus clock; less when a timer is due),
  // delivers it, calls tick(), and publishes the heartbeat when due. False once the bus has ended.
  bool step(int timeout_ms);
  // Steps until a stop is requested or the bus ends; then a last heartbeat. Returns the exit code.
  int run();
  // run() returns after the current step (from inside the node, or from another thread's signal).
  void stop() { stopping_ = true; }

  // SIGINT/SIGTERM make every node's run() return. Idempotent.
  static void install_signal_handlers();
  static bool stop_requested();
  static void request_stop();

  const NodeCounters& counters() const { return counters_; }
  // The heartbeat's status: the bus's problem, stale inputs and the node's own status, or "ok".
  std::string status() const;
  // The heartbeat as it would be published now.
  heartbeat_t heartbeat() const;
  // Whether the last heartbeat was published (and at what bus time); -1 before the first.
  int64_t last_heartbeat_utime() const { return last_heartbeat_utime_; }
  const RateLimitedLog& warnings() const { return warnings_; }

  // What the node was configured with, recorded on BL_CONFIG at start and every 10 s.
  void set_config(std::string program, std::string config_json);

 protected:
  // Decodes every message on channel as T on arrival and hands it to handler, under policy. A message
  // longer than max_bytes, that does not decode, or whose handler throws is a counted error (with a
  // rate-limited warning); it never takes a good message's place in the queue, so garbage cannot push
  // out a real input. Handlers run after the step's arrivals, in arrival order across subscriptions.
  template <typename T>
  void subscribe(const std::string& channel, QueuePolicy policy, std::function<void(const T&)> handler,
                 size_t max_bytes = kDefaultMaxMessageBytes) {
    subscribe_raw(channel, policy, max_bytes, [handler = std::move(handler)](const Received& r) -> std::function<void()> {
      std::optional<T> msg = decode<T>(r.data, r.size);
      if (!msg) return {};
      return [handler, m = std::move(*msg)] { handler(m); };
    });
  }

  // Every message on the channels matching pattern (a regular expression, ".*" = all), undecoded: for
  // nodes that handle bytes (the logger). Oversized messages are counted errors.
  void subscribe_bytes(const std::string& pattern, QueuePolicy policy, std::function<void(const Received&)> handler,
                       size_t max_bytes = kDefaultMaxMessageBytes);

  // An output: counted as published. A refused publication is a counted error.
  template <typename T>
  bool publish(const std::string& channel, const T& msg) {
    return publish_bytes(channel, encode(msg), true);
  }
  // A report beside the outputs (timings): sent like an output, not counted as one.
  template <typename T>
  bool publish_report(const std::string& channel, const T& msg) {
    return publish_bytes(channel, encode(msg), false);
  }

  // Called after every step's deliveries, and when a step's wait ends without any.
  virtual void tick() {}
  // Called just before each heartbeat: refresh values and status.
  virtual void before_heartbeat() {}
  // Called once when run() ends, before the last heartbeat: finish what is in flight.
  virtual void before_stop() {}

  // Asks the next step to wait no later than this bus time (pacing: a camera's next frame).
  void wake_at(int64_t utime);
  // How long a step waits at most when no timer is due (default 20 ms).
  void set_tick_ms(int ms) { tick_ms_ = ms; }

  void set_value(const std::string& name, double value) { values_[name] = value; }
  // "ok" or a short operator-readable problem of the node's own.
  void set_status(std::string status) { status_ = std::move(status); }

  // A counted error and a rate-limited warning. kind: what the summary counts.
  void error(const std::string& kind, const std::string& message);
  // A rate-limited warning that counts nothing.
  void warn(const std::string& kind, const std::string& message);
  void count_dropped(int64_t n = 1) { counters_.dropped += n; }
  // For a node whose counters mean something else (the logger: published = events written).
  NodeCounters& own_counters() { return counters_; }
  void count_received(int64_t n = 1) { counters_.received += n; }

  // Input staleness: while channel has been silent for more than after_s (since the node started, or
  // since its last message), the status says "<what> for N s". what: e.g. "no frames".
  void watch_input(const std::string& channel, double after_s, std::string what);
  // Microseconds since the channel's last message (or since the node started if none came).
  int64_t silent_for_us(const std::string& channel) const;
  // The first stale input's words ("no frames for 7 s"), or "".
  std::string stale_inputs() const;

 private:
  // Decodes a message into the call that hands it over; an empty function when it does not decode.
  using Decoder = std::function<std::function<void()>(const Received&)>;
  void subscribe_raw(const std::string& channel, QueuePolicy policy, size_t max_bytes, Decoder decoder);
  void deliver_pending();
  bool publish_bytes(const std::string& channel, const std::vector<uint8_t>& bytes, bool output);
  void publish_heartbeat();
  void publish_config();
  int64_t queue_drops() const;

  // Decoded inputs waiting for their handlers, per subscription, under its policy.
  struct Pending {
    uint64_t sequence;
    std::function<void()> call;
  };
  struct Inbox {
    std::string channel;
    QueuePolicy policy;
    std::deque<Pending> queue;
    int64_t dropped = 0;
  };

  struct Watch {
    std::string channel;
    int64_t after_us;
    std::string what;
  };

  std::string name_;
  Bus& bus_;
  NodeCounters counters_;
  std::vector<const SubscriptionStats*> subscription_stats_;  // the transport's queues (drops under a flood)
  std::list<Inbox> inboxes_;                                   // stable addresses for the bus's handlers
  uint64_t next_sequence_ = 0;
  std::map<std::string, int64_t> last_message_utime_;
  std::vector<Watch> watches_;
  std::map<std::string, double> values_;
  std::string status_ = "ok";
  RateLimitedLog warnings_;
  std::string heartbeat_channel_, config_channel_;
  std::string program_, config_json_;
  std::string instance_;
  int32_t pid_ = 0;
  int32_t restarts_ = 0;
  int64_t start_utime_;
  int64_t next_heartbeat_utime_;
  int64_t last_heartbeat_utime_ = -1;
  int64_t heartbeats_ = 0;
  int64_t wake_utime_ = INT64_MAX;
  int tick_ms_ = 20;
  bool stopping_ = false;
};

}  // namespace bricklayer::runtime
