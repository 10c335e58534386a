// The older process skeleton: it owns the LCM handle, decodes inputs defensively (malformed,
// wrong-fingerprint and oversized messages are counted errors, never crashes), publishes a heartbeat
// with its counters once a second, and stops cleanly on SIGINT/SIGTERM. No module runs on it any more
// (every stage is a node on the runtime, modules/runtime); process tests still use it to play a peer
// on the live bus. New code uses runtime::LcmBus and tests/harness instead.
//
// LCM 1.3.1 has no lambda subscribe and must be pumped from one thread (shared NOTES), so handlers
// are std::functions behind a static trampoline, and run() pumps with handleTimeout on the calling
// thread. No exception ever crosses LCM's C callback.
#pragma once

#include <lcm/lcm-cpp.hpp>

#include <atomic>
#include <chrono>
#include <cstdint>
#include <functional>
#include <list>
#include <map>
#include <memory>
#include <optional>
#include <string>
#include <vector>

#include "bricklayer/common/log.h"

namespace bricklayer {

struct Counters {
  std::atomic<int64_t> received{0};
  std::atomic<int64_t> published{0};
  std::atomic<int64_t> dropped{0};
  std::atomic<int64_t> errors{0};
};

// Microseconds since the epoch. For stamps and timing fields only, never inside a computation.
int64_t wall_utime();

class Module {
 public:
  // name: module name in heartbeats and logs. url: already resolved (see resolve_lcm_url).
  // Throws std::runtime_error when the bus cannot be opened (getFileno() < 0 is the real check).
  Module(std::string name, const std::string& url);
  ~Module();
  Module(const Module&) = delete;
  Module& operator=(const Module&) = delete;

  lcm::LCM& lcm() { return *lcm_; }
  Counters& counters() { return counters_; }
  const std::string& name() const { return name_; }

  // Subscribes to a channel of message type T. Each message that decodes cleanly and is at most
  // max_bytes long is counted as received and handed to handler; anything else is a counted error
  // with one warning line. Handler exceptions are caught, logged and counted as errors.
  // queue_capacity: LCM's per-subscription queue (it discards silently when full, so keep it
  // generous and let Latest<> decide what to drop).
  template <typename T>
  void subscribe(const std::string& channel, std::function<void(const T&)> handler,
                 size_t max_bytes = 16 << 20, int queue_capacity = 100) {
    auto decode = [handler = std::move(handler)](const void* data, uint32_t size) {
      T msg{};
      if (msg.decode(data, 0, static_cast<int>(size)) < 0) return false;
      handler(msg);
      return true;
    };
    subscribe_raw(channel, std::move(decode), max_bytes, queue_capacity);
  }

  // Publishes and counts. Returns false (and counts an error) when LCM refuses the message.
  template <typename T>
  bool publish(const std::string& channel, const T& msg) {
    if (lcm_->publish(channel, &msg) != 0) {
      ++counters_.errors;
      log::warn("publish on ", channel, " failed");
      return false;
    }
    ++counters_.published;
    return true;
  }

  // Module-specific figures carried in every heartbeat ("drift_px", ...).
  void set_value(const std::string& name, double value) { values_[name] = value; }
  // "ok" or a short operator-readable problem.
  void set_status(std::string status) { status_ = std::move(status); }

  // Pumps messages until stop is requested. After each batch of handled messages (and at least every
  // tick_ms) calls tick(), where newest-wins processing happens. Publishes a heartbeat every
  // heartbeat_ms. Returns the process exit code (0 after a clean stop).
  int run(const std::function<void()>& tick, int tick_ms = 20, int heartbeat_ms = 1000);

  // Publishes a heartbeat now (run() does this periodically).
  void publish_heartbeat();

  // Installs SIGINT/SIGTERM handlers that make run() return; idempotent.
  static void install_signal_handlers();
  static bool stop_requested();
  static void request_stop();

 private:
  using RawHandler = std::function<bool(const void*, uint32_t)>;
  struct Subscription {
    Module* module;
    std::string channel;
    size_t max_bytes;
    RawHandler handler;
  };
  static void trampoline(const lcm::ReceiveBuffer* rbuf, const std::string& channel, Subscription* sub);
  void subscribe_raw(const std::string& channel, RawHandler handler, size_t max_bytes, int queue_capacity);

  std::string name_;
  std::unique_ptr<lcm::LCM> lcm_;
  Counters counters_;
  std::list<Subscription> subscriptions_;  // stable addresses for the trampoline context
  std::map<std::string, double> values_;
  std::string status_ = "ok";
  int32_t restarts_ = 0;
  std::chrono::steady_clock::time_point started_;
};

}  // namespace bricklayer
