// Records what a bus carries and waits for it with typed predicates, on any Bus: the live LCM bus of a
// process test (waits in wall time, pumping the bus) or an in-process rig (waits in the rig's clock,
// stepping its nodes). Readiness is a heartbeat, never a sleep.
//
//   auto p = recorder.wait_for<prediction_t>(channel(kPredictionChannel),
//                                            [](const prediction_t& p) { return p.frame_number == 7; });
//   REQUIRE(p);
#pragma once

#include <chrono>
#include <cstdint>
#include <functional>
#include <optional>
#include <string>
#include <vector>

#include "bricklayer/heartbeat_t.hpp"
#include "bricklayer/runtime/bus.h"
#include "bricklayer/runtime/codec.h"

namespace bricklayer::harness {

class Recorder {
 public:
  struct Message {
    std::string channel;
    std::vector<uint8_t> bytes;
    int64_t utime;  // the bus clock when it arrived
  };

  // pump: lets the bus deliver (one short wait, or one rig step); clock_us: the time waits are
  // measured in. Subscribes to every channel given (an unbounded queue: a test loses nothing).
  Recorder(runtime::Bus& bus, const std::vector<std::string>& channels, std::function<void()> pump,
           std::function<int64_t()> clock_us);

  // A recorder on a live bus: pumps with handle(5 ms), waits in wall time.
  static Recorder live(runtime::Bus& bus, const std::vector<std::string>& channels);

  const std::vector<Message>& messages() const { return messages_; }
  size_t count(const std::string& channel) const;
  void clear() { messages_.clear(); }

  // Every message on channel that decodes as T, in arrival order.
  template <typename T>
  std::vector<T> all(const std::string& channel) const {
    std::vector<T> out;
    for (const Message& m : messages_)
      if (m.channel == channel)
        if (auto msg = runtime::decode<T>(m.bytes)) out.push_back(*msg);
    return out;
  }

  // The newest message recorded on channel that decodes as T (the state a peer shows now).
  template <typename T>
  std::optional<T> newest(const std::string& channel) const {
    for (auto it = messages_.rbegin(); it != messages_.rend(); ++it)
      if (it->channel == channel)
        if (auto msg = runtime::decode<T>(it->bytes)) return msg;
    return std::nullopt;
  }

  // The first message recorded on channel (from the start of the recording) that decodes as T and
  // satisfies pred, pumping until it arrives or timeout passes.
  template <typename T>
  std::optional<T> wait_for(const std::string& channel, const std::function<bool(const T&)>& pred = {},
                            std::chrono::milliseconds timeout = std::chrono::seconds(10)) {
    size_t seen = 0;
    const int64_t deadline = clock_us_() + timeout.count() * 1000;
    for (;;) {
      for (; seen < messages_.size(); ++seen) {
        const Message& m = messages_[seen];
        if (m.channel != channel) continue;
        auto msg = runtime::decode<T>(m.bytes);
        if (msg && (!pred || pred(*msg))) return msg;
      }
      if (clock_us_() >= deadline) return std::nullopt;
      pump_();
    }
  }

  // Pumps until pred() holds or timeout passes; returns pred().
  bool wait_until(const std::function<bool()>& pred, std::chrono::milliseconds timeout = std::chrono::seconds(10));
  // Pumps for this long.
  void pump_for(std::chrono::milliseconds duration);

  // The first heartbeat of module (optionally: satisfying pred) on BL_HEARTBEAT.
  std::optional<heartbeat_t> wait_for_heartbeat(const std::string& module,
                                                const std::function<bool(const heartbeat_t&)>& pred = {},
                                                std::chrono::milliseconds timeout = std::chrono::seconds(10));
  // The newest heartbeat of module recorded so far.
  std::optional<heartbeat_t> last_heartbeat(const std::string& module) const;

 private:
  std::vector<Message> messages_;
  std::function<void()> pump_;
  std::function<int64_t()> clock_us_;
};

// The value a heartbeat carries under name, if any.
std::optional<double> heartbeat_value(const heartbeat_t& hb, const std::string& name);

}  // namespace bricklayer::harness
