// Helpers for tests that drive real processes on the real LCM bus (inside a NETNS test's private
// network namespace): where the binaries are, a raw-bytes listener, encode().
#pragma once

#include <lcm/lcm-cpp.hpp>

#include <chrono>
#include <functional>
#include <map>
#include <memory>
#include <string>
#include <thread>
#include <vector>

#include "bricklayer/common/channels.h"
#include "bricklayer/heartbeat_t.hpp"

namespace bricklayer::test {

inline constexpr const char* kTestUrl = "udpm://239.255.76.67:7667?ttl=0";

inline std::string bin(const std::string& name) { return std::string(BRICKLAYER_BINARY_DIR) + "/bin/" + name; }

template <typename T>
std::vector<uint8_t> encode(const T& msg) {
  std::vector<uint8_t> out(static_cast<size_t>(msg.getEncodedSize()));
  msg.encode(out.data(), 0, static_cast<int>(out.size()));
  return out;
}

template <typename T>
bool decode(const std::vector<uint8_t>& bytes, T& msg) {
  return msg.decode(bytes.data(), 0, static_cast<int>(bytes.size())) >= 0;
}

// Records every message on the given channels (raw bytes, arrival order). Pump from the test thread.
class Listener {
 public:
  struct Message {
    std::string channel;
    std::vector<uint8_t> bytes;
    std::chrono::steady_clock::time_point when;
  };

  explicit Listener(const std::string& url = kTestUrl) : lcm_(std::make_unique<lcm::LCM>(url)) {}
  void listen(const std::string& channel) {
    lcm_->subscribeFunction(channel, &Listener::on_message, this)->setQueueCapacity(100000);
  }
  lcm::LCM& lcm() { return *lcm_; }
  bool ok() const { return lcm_->good() && lcm_->getFileno() >= 0; }

  void pump(std::chrono::milliseconds for_how_long) {
    auto until = std::chrono::steady_clock::now() + for_how_long;
    while (std::chrono::steady_clock::now() < until) lcm_->handleTimeout(5);
  }
  // Pumps until pred() holds or the timeout passes; returns pred().
  bool pump_until(const std::function<bool()>& pred, std::chrono::milliseconds timeout) {
    auto until = std::chrono::steady_clock::now() + timeout;
    while (!pred()) {
      if (std::chrono::steady_clock::now() >= until) return false;
      lcm_->handleTimeout(5);
    }
    return true;
  }

  std::vector<Message> on(const std::string& channel) const {
    std::vector<Message> out;
    for (const auto& m : messages) if (m.channel == channel) out.push_back(m);
    return out;
  }
  size_t count(const std::string& channel) const {
    size_t n = 0;
    for (const auto& m : messages) n += m.channel == channel;
    return n;
  }
  // The newest heartbeat of a module (decoded), if any.
  bool last_heartbeat(const std::string& module, heartbeat_t& out) const {
    for (auto it = messages.rbegin(); it != messages.rend(); ++it) {
      if (it->channel != channel(kHeartbeatChannel)) continue;
      heartbeat_t hb{};
      if (decode(it->bytes, hb) && hb.module == module) {
        out = hb;
        return true;
      }
    }
    return false;
  }

  std::vector<Message> messages;

 private:
  static void on_message(const lcm::ReceiveBuffer* rbuf, const std::string& channel, Listener* self) {
    const auto* d = static_cast<const uint8_t*>(rbuf->data);
    self->messages.push_back(Message{channel, std::vector<uint8_t>(d, d + rbuf->data_size), std::chrono::steady_clock::now()});
  }
  std::unique_ptr<lcm::LCM> lcm_;
};

}  // namespace bricklayer::test
